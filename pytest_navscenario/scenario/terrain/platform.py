"""A raised floor (``type: platform`` in ``terrain:``): its declaration, its pieces and its YAML keys."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Literal

from ..keys import Number, section
from .base import NAME, X, Y, LENGTH, WIDTH, YAW, Z, Piece, TerrainKind


@dataclass(frozen=True)
class Platform:
    """A raised floor (a loading dock, a mezzanine): a solid block ``length`` by ``width`` whose top
    is ``height`` above its base ``z``, with drop edges on every side."""
    name: str
    x: float
    y: float
    length: float
    width: float
    height: float
    yaw: float = 0.0
    z: float = 0.0
    kind: Literal["platform"] = field(default="platform", init=False)
    grid: ClassVar[bool] = False   # a height grid (no pieces)

    def pieces(self, index: int) -> tuple[Piece, ...]:
        """One block, its top at ``z + height``."""
        return (Piece(index, -self.length / 2, self.length / 2, self.z + self.height, self.z + self.height),)


PLATFORM = section(Platform, "terrain[] (platform)", "a raised floor with drop edges on every side", [
    NAME, X, Y, LENGTH, WIDTH,
    Number("height", "m", "its top above its base z", gt=0, example="height: 1.0"), YAW, Z])

KIND = TerrainKind("platform", Platform, PLATFORM)
