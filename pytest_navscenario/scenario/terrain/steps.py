"""A flight of steps (``type: steps`` in ``terrain:``): its declaration, its pieces and its YAML keys."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Literal

from ..keys import Choice, Integer, Number, section
from .base import FLOOR, NAME, X, Y, WIDTH, YAW, Z, Piece, TerrainKind


@dataclass(frozen=True)
class Steps:
    """A flight of ``count`` steps, each ``rise`` high and ``run`` deep, ``width`` wide, over a
    footprint ``count * run`` long centred on (x, y). ``up``: they climb along their own +x from
    the base height ``z`` (the top of the last step at ``z + count * rise``). ``down``: they descend
    along +x below ``z``, cut into the ground (the last step's top at ``z - count * rise``), as a
    stairwell seen from the floor above."""
    name: str
    x: float
    y: float
    count: int
    rise: float
    run: float
    width: float
    yaw: float = 0.0
    z: float = 0.0
    direction: Literal["up", "down"] = "up"
    kind: Literal["steps"] = field(default="steps", init=False)
    grid: ClassVar[bool] = False   # a height grid (no pieces)

    @property
    def length(self) -> float:
        return self.count * self.run

    def pieces(self, index: int) -> tuple[Piece, ...]:
        """One block a step; a step whose top lies below the floor is a cut (a stairwell)."""
        sign = 1.0 if self.direction == "up" else -1.0
        out = []
        for k in range(self.count):
            top = self.z + sign * (k + 1) * self.rise
            u0 = -self.length / 2 + k * self.run
            out.append(Piece(index, u0, u0 + self.run, top, top, cut=top < FLOOR - 1e-12))
        return tuple(out)


STEPS = section(Steps, "terrain[] (steps)", "a flight of steps, count × run long", [
    NAME, X, Y,
    Integer("count", "", "how many steps", ge=1, le=1000, example="count: 3"),
    Number("rise", "m", "each step's height", gt=0, example="rise: 0.15"),
    Number("run", "m", "each step's depth", gt=0, example="run: 0.3"),
    WIDTH, YAW, Z,
    Choice("direction", "", "up: they climb along +x from z; down: they descend along +x below z, cut into "
           "the ground", options=("up", "down"))])

KIND = TerrainKind("steps", Steps, STEPS)
