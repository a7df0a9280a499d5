"""A height grid read from a file (``type: heightfield`` in ``terrain:``): its declaration, its pieces and its YAML keys."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal

from ..keys import Number, Rule, Text, section
from .base import NAME, X, Y, LENGTH, WIDTH, YAW, Z, Piece, TerrainKind


@dataclass(frozen=True)
class Heightfield:
    """A height grid read from ``file`` beside the scenario (a greyscale PNG or a NumPy ``.npy``
    array; the same path rules as mesh obstacles), stretched over ``length`` by ``width`` metres,
    its values mapped to heights from ``min_height`` to ``max_height`` above ``z``. ``digest`` is
    what the loader read from the file (a hash of the grid): it makes the grid part of the content,
    wherever the file lives."""
    name: str
    x: float
    y: float
    file: str
    length: float
    width: float
    min_height: float = 0.0
    max_height: float = 1.0
    yaw: float = 0.0
    z: float = 0.0
    digest: str = ""
    kind: Literal["heightfield"] = field(default="heightfield", init=False)
    grid: ClassVar[bool] = True   # a height grid (no pieces)

    def pieces(self, index: int) -> tuple[Piece, ...]:
        """None: a grid (scenario/ground/heightmap.py)."""
        return ()


def _heights(values: Any, given: Any) -> tuple[str, str, str] | None:
    if values["max_height"] <= values["min_height"]:
        return ("max_height", f"max_height ({values['max_height']!r} m) must be greater than min_height "
                f"({values['min_height']!r} m)", "raise max_height")
    return None


HEIGHTFIELD = section(Heightfield, "terrain[] (heightfield)", "a height grid read from a greyscale PNG or a "
                      ".npy file beside the scenario", [
    NAME, X, Y,
    Text("file", "", "a .png or .npy file, relative to the scenario's folder and inside it", path=True, inside=True,
         example="file: ground/yard.png"),
    LENGTH, WIDTH,
    Number("min_height", "m", "the height of the grid's lowest value above z"),
    Number("max_height", "m", "the height of the grid's highest value above z"),
    YAW, Z], rules=[Rule("max_height is greater than min_height", _heights),
                      Rule("the height file exists, is readable and within the size limits", None)])

KIND = TerrainKind("heightfield", Heightfield, HEIGHTFIELD)
