"""Terrain and the 3D lidar: the scenario-model side of ground that is not a flat floor.

Frozen dataclasses mirroring the YAML, in YAML units (metres, degrees), like ``model.py``; no I/O.
Three additions to a scenario, each off by default so that every file written before them loads
and means the same, bit for bit (and hashes the same: see ``model._ADDED_DEFAULTS``):

* ``terrain:`` a list of elements, each placed like an obstacle by its footprint centre (x, y) and
  ``yaw`` (degrees, counter-clockwise), its own +x axis being the direction it rises or runs along.
  Raised elements (ramp, steps, platform) and patches (rough, heightfield) rest their base at ``z``
  metres above the floor (0 by default: on the floor); a pit is a hole in the floor. The floor
  elsewhere is z = 0, as today.
* ``robot.body`` (its kinds are scenario/bodies/): how the robot meets the ground. ``planar`` (the default) is today's body: slide
  and hinge joints in the plane, gravity off. ``wheeled`` rides the terrain under gravity on real
  wheel contacts; ``legged`` is a capability model of a walking robot (what it can climb, step over
  and cross), not a walking controller; ``mjcf`` is the user's own MJCF robot with a controller of
  theirs. ``robot.drive`` (omni, diff) still says what the planner's commands mean.
* ``robot.lidar3d``: a spinning multi-ring lidar whose point cloud is part of the observation; the
  2D lidar (``robot.lidar``) stays, at its ``mount_height`` above the robot's base.

Names (``name``) label elements in messages ("fell off platform 'dock'"); they are not content.

Read first: ``base.py`` (``Piece``, the convex block a primitive element is built of, and the keys
of an element's placement), then one module per element (``ramp.py``, ``steps.py``,
``platform.py``, ``pit.py``: each builds its own pieces; ``rough.py`` and ``heightfield.py``:
height grids, scenario/ground/heightmap.py) and ``lidar3d.py``. The bodies are scenario/bodies/.

``ELEMENT_MODULES`` below is the registry: adding a terrain element is one module (a frozen
dataclass with ``grid`` and ``pieces(index)``, its YAML keys, and its ``KIND``) and one line here; see docs/contributing.md.
"""
from __future__ import annotations

import importlib
from typing import Union

from ..keys import SCENARIO_LIMITS as _LIMITS
from ..keys import Element, Elements
from .base import Piece, TerrainKind
from .heightfield import HEIGHTFIELD, Heightfield
from .lidar3d import LIDAR3D, Lidar3D
from .pit import PIT, Pit
from .platform import PLATFORM, Platform
from .ramp import RAMP, Ramp
from .rough import ROUGH, Rough
from .steps import STEPS, Steps

# The registry: the modules of this package that each give a terrain element (their ``KIND``), in
# the order the YAML, the JSON Schema and the reference list them. Adding an element: one line.
ELEMENT_MODULES = (
    "ramp",
    "steps",
    "platform",
    "pit",
    "rough",
    "heightfield",
)
ELEMENTS: tuple[TerrainKind, ...] = tuple(importlib.import_module(f".{m}", __name__).KIND for m in ELEMENT_MODULES)

TerrainElement = Union[tuple(kind.declaration for kind in ELEMENTS)]  # type: ignore[valid-type]
TERRAIN_TYPES = tuple(kind.name for kind in ELEMENTS)

TERRAIN = Elements("terrain", "", "ground that is not the flat floor: ramps, steps, platforms, pits, rough "
                   "patches, height grids", max=int(_LIMITS["max_obstacles"]), what="terrain elements",
                   item="terrain element", default=(),
                   example="{type: ramp, x: 3.0, y: 0.0, length: 2.0, width: 1.5, rise: 0.3}", types=tuple(Element(kind.name, kind.keys, kind.name, kind.keys.doc) for kind in ELEMENTS))

__all__ = ["ELEMENTS", "ELEMENT_MODULES", "HEIGHTFIELD", "LIDAR3D", "PIT", "PLATFORM", "RAMP", "ROUGH", "STEPS", "TERRAIN", "TERRAIN_TYPES",
           "Heightfield", "Lidar3D", "Piece", "Pit", "Platform", "Ramp", "Rough", "Steps", "TerrainElement",
           "TerrainKind"]
