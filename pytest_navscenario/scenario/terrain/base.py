"""What every terrain element shares: the convex ``Piece`` a primitive element is built of (the
ground's heights, the MuJoCo world and the pictures all read pieces), and the YAML keys of an
element's placement."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..keys import Integer, Number, Text

FLOOR = 0.0


@dataclass(frozen=True)
class Piece:
    """One convex block of an element, in the element's frame: ``u0..u1`` along its length, the
    full width, its top a plane from ``top0`` (at u0) to ``top1`` (at u1). ``cut``: the floor is
    removed over it (its top lies below the floor)."""
    element: int          # index in scenario.terrain
    u0: float
    u1: float
    top0: float
    top1: float
    cut: bool = False


@dataclass(frozen=True)
class TerrainKind:
    """One kind of terrain element, as its module gives it (``KIND``): the ``type`` it is written
    with, its frozen dataclass (with ``grid`` and ``pieces(index)``) and its YAML keys."""
    name: str
    declaration: type
    keys: Any


NAME = Text("name", "", "a label for messages (generated when absent: ramp1, steps1 ...)", default=None,
            name_rules=True, default_doc="generated")
X = Number("x", "m", "its footprint's centre, along x", example="x: 0.0")
Y = Number("y", "m", "its footprint's centre, along y", example="y: 0.0")
LENGTH = Number("length", "m", "its size along its own x axis (the way it rises or runs)", gt=0,
                example="length: 2.0")
WIDTH = Number("width", "m", "its size across", gt=0, example="width: 1.0")
YAW = Number("yaw", "deg", "its rotation, counter-clockwise")
Z = Number("z", "m", "the height of its base above the floor", ge=0)
SEED = Integer("seed", "", "the random seed of its shape (the same seed, the same ground)", ge=0, le=2**63 - 1)
