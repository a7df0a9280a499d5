"""Height grids in the MuJoCo world: a rough or heightfield element as an ``hfield`` geom, and the
same grid placed in the world for the lidars' own ray cast (``hfield_rays.py``).

The geom is MuJoCo's heightfield over the element's footprint (centred on its (x, y), turned by its
yaw), its surface the grid's heights above the element's base ``z`` (MuJoCo stores them as float32,
normalised to [0, 1] and scaled by the elevation range), with a solid base reaching
``BASE_BELOW_FLOOR`` below the floor so that a raised patch has no gap under it. It is put in geom
group ``HFIELD_GROUP``: ``mj_multiRay`` skips that group (it costs 9-240 ms for a 16 x 360 scan
against heightfields of 32-256 cells a side, measured) and the lidars cast against the grid instead.

The grid comes from ``scenario.heightmap.height_grid`` (read or generated once per process and
cached); the compiled model is cached with the world (``world.compiled_world``), so a 256 x 256
heightfield is built once per process per layout and reused by every episode.
"""
from __future__ import annotations

import math
from typing import Any, NamedTuple

import mujoco
import numpy as np

from ...scenario.ground.heightmap import HeightGrid

HFIELD_GROUP = 2            # geom group of heightfields: mj_multiRay skips it (hfield_rays casts instead)
BASE_BELOW_FLOOR = 0.1      # m: the solid base under a heightfield reaches this far below z = 0
MIN_ELEVATION = 1e-6        # m: MuJoCo needs an elevation range > 0; a flat grid gets this


class PlacedGrid(NamedTuple):
    """A height grid where it lies in the world: its centre (x, y), yaw (rad), the height of its
    base ``z`` (grid heights are above it) and the element's name (for messages)."""
    grid: HeightGrid
    x: float
    y: float
    yaw: float
    z: float
    name: str


def placed_grid(element: Any, grid: HeightGrid) -> PlacedGrid:
    """The PlacedGrid of a rough or heightfield element (YAML units: yaw in degrees)."""
    return PlacedGrid(grid, float(element.x), float(element.y), math.radians(element.yaw),
                      float(element.z), element.name)


def hfield_size(grid: HeightGrid, z: float) -> tuple[list[float], float]:
    """(MuJoCo's hfield size [x radius, y radius, elevation, base], the geom's z): the geom sits at
    the grid's lowest point, its base reaching ``BASE_BELOW_FLOOR`` below the floor."""
    length, width = grid.extent
    low, high = float(grid.heights.min()), float(grid.heights.max())
    bottom = z + low
    return [length / 2.0, width / 2.0, max(high - low, MIN_ELEVATION),
            max(bottom, 0.0) + BASE_BELOW_FLOOR], bottom


def add_heightfield(spec: mujoco.MjSpec, element: Any, grid: HeightGrid, *, name: str | None = None,
                    contype: int = 2, conaffinity: int = 1, friction: Any = None,
                    rgba: Any = (0.55, 0.5, 0.42, 1.0)) -> Any:
    """Add ``element``'s grid to ``spec`` as an hfield asset and a static geom (named ``name``, by
    default ``terrain:<element name>``) in ``HFIELD_GROUP``; returns the geom. Contacts as
    obstacles by default (contype 2, conaffinity 1): the caller sets what the ground touches (and
    its ``friction``, MuJoCo's default when None)."""
    gname = name or f"terrain:{element.name}"
    size, bottom = hfield_size(grid, float(element.z))
    heights = grid.heights
    low, high = float(heights.min()), float(heights.max())
    data = ((heights - low) / (high - low) if high > low else np.zeros_like(heights)).astype(np.float32)
    rows, cols = heights.shape
    spec.add_hfield(name=gname, size=size, nrow=rows, ncol=cols, userdata=data.ravel())
    yaw = math.radians(element.yaw)
    extra = {} if friction is None else {"friction": list(friction)}
    return spec.worldbody.add_geom(
        name=gname, type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname=gname,
        pos=[float(element.x), float(element.y), bottom],
        quat=[math.cos(yaw / 2.0), 0.0, 0.0, math.sin(yaw / 2.0)],
        contype=contype, conaffinity=conaffinity, group=HFIELD_GROUP, rgba=list(rgba), **extra)


GRID_KINDS = ("rough", "heightfield")
_PLACED: dict[Any, tuple[PlacedGrid, ...]] = {}


def placed_grids(scenario: Any) -> tuple[PlacedGrid, ...]:
    """The scenario's rough and heightfield elements as PlacedGrids (empty without any), the same
    objects for the same terrain within a process (the ray cast prepares each grid once)."""
    elements = tuple(el for el in getattr(scenario, "terrain", ()) if el.kind in GRID_KINDS)
    if not elements:
        return ()
    from ...scenario.ground.heightmap import height_grid

    key = (elements, scenario.source if any(el.kind == "heightfield" for el in elements) else None)
    placed = _PLACED.get(key)
    if placed is None:
        if len(_PLACED) >= 64:
            _PLACED.clear()
        placed = _PLACED[key] = tuple(placed_grid(el, height_grid(el, scenario)) for el in elements)
    return placed
