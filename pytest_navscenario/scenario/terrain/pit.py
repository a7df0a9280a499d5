"""A hole in the floor (``type: pit`` in ``terrain:``): its declaration, its pieces and its YAML keys."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Literal

from ..keys import Number, section
from .base import NAME, X, Y, LENGTH, WIDTH, YAW, Piece, TerrainKind


@dataclass(frozen=True)
class Pit:
    """A hole in the floor, ``length`` by ``width``, ``depth`` deep, with vertical walls."""
    name: str
    x: float
    y: float
    length: float
    width: float
    depth: float
    yaw: float = 0.0
    kind: Literal["pit"] = field(default="pit", init=False)
    grid: ClassVar[bool] = False   # a height grid (no pieces)

    def pieces(self, index: int) -> tuple[Piece, ...]:
        """One cut, its bottom ``depth`` below the floor."""
        return (Piece(index, -self.length / 2, self.length / 2, -self.depth, -self.depth, cut=True),)


PIT = section(Pit, "terrain[] (pit)", "a hole in the floor with vertical walls", [
    NAME, X, Y, LENGTH, WIDTH, Number("depth", "m", "how deep it is", gt=0, example="depth: 0.5"), YAW])

KIND = TerrainKind("pit", Pit, PIT)
