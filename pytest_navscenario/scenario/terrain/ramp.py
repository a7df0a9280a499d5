"""An inclined plane (``type: ramp`` in ``terrain:``): its declaration, its pieces and its YAML keys."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar, Literal

from ..keys import Number, section
from .base import NAME, X, Y, LENGTH, WIDTH, YAW, Z, Piece, TerrainKind


@dataclass(frozen=True)
class Ramp:
    """An inclined plane ``length`` long (along its own +x) and ``width`` wide, rising by ``rise``
    from its low end (at -x, height ``z``) to its high end (at +x, height ``z + rise``); solid
    below its surface, with vertical sides."""
    name: str
    x: float
    y: float
    length: float
    width: float
    rise: float
    yaw: float = 0.0
    z: float = 0.0
    kind: Literal["ramp"] = field(default="ramp", init=False)
    grid: ClassVar[bool] = False   # a height grid (no pieces)

    @property
    def slope(self) -> float:
        """The ramp's slope in degrees."""
        return math.degrees(math.atan2(self.rise, self.length))

    def pieces(self, index: int) -> tuple[Piece, ...]:
        """One block, its top rising from ``z`` to ``z + rise``."""
        return (Piece(index, -self.length / 2, self.length / 2, self.z, self.z + self.rise),)


RAMP = section(Ramp, "terrain[] (ramp)", "an inclined plane rising by rise along its own +x", [
    NAME, X, Y, LENGTH, WIDTH,
    Number("rise", "m", "how much its high end (+x) is above its low end", gt=0, example="rise: 0.3"),
    YAW, Z])

KIND = TerrainKind("ramp", Ramp, RAMP)
