"""Rough ground: a patch of random bumps (``type: rough`` in ``terrain:``): its declaration, its pieces and its YAML keys."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, Literal

from ..keys import Number, section
from .base import NAME, X, Y, LENGTH, WIDTH, YAW, Z, SEED, Piece, TerrainKind


@dataclass(frozen=True)
class Rough:
    """A patch of rough ground ``length`` by ``width``: smooth random bumps of up to ``amplitude``
    metres with a typical spacing of ``wavelength`` metres, drawn from ``seed`` (the same seed gives
    the same ground), resting on ``z``."""
    name: str
    x: float
    y: float
    length: float
    width: float
    amplitude: float
    wavelength: float
    seed: int = 0
    yaw: float = 0.0
    z: float = 0.0
    kind: Literal["rough"] = field(default="rough", init=False)
    grid: ClassVar[bool] = True   # a height grid (no pieces)

    def pieces(self, index: int) -> tuple[Piece, ...]:
        """None: a grid (scenario/ground/heightmap.py)."""
        return ()


ROUGH = section(Rough, "terrain[] (rough)", "a patch of smooth random bumps", [
    NAME, X, Y, LENGTH, WIDTH,
    Number("amplitude", "m", "the bumps' largest height", gt=0, example="amplitude: 0.05"),
    Number("wavelength", "m", "the bumps' typical spacing", gt=0, example="wavelength: 0.5"),
    SEED, YAW, Z])

KIND = TerrainKind("rough", Rough, ROUGH)
