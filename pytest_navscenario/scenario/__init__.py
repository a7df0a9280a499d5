"""Scenario: the test case as data.

In: YAML text or files (or plain dicts). Out: a frozen ``Scenario`` (robot, mission, obstacles,
simulation settings, marks, search bounds), validated with ``file:line: field: message (fix: ...)``
errors, and YAML that loads back to the same value.

Read first: ``model.py`` (the dataclasses and their units), then ``loader.py`` (validation),
``dump.py`` (writing), ``yaml_tree.py`` (the line-tracking YAML reader), ``geometry.py``
(footprints and obstacle outlines as shapely polygons), ``motion.py`` (where a moving obstacle is at
a time: the one function the simulation, the verdict and the pictures share).

The format as data: ``keys.py`` (each key's type, range, default, unit, declared beside its
dataclass), ``format.py`` (the top level), ``reading.py`` (reading by declaration), ``json_schema.py``
and ``modeline.py`` (the JSON Schema for editors and the first line of written files).

Terrain and bodies: ``terrain.py`` (terrain elements, bodies, the 3D lidar as dataclasses),
``mjcf_files.py`` (an MJCF robot's files), and the subpackage ``ground/``: the ground's geometry,
MuJoCo-free, here because the simulation, the verdict, the pictures, the search and the importers all
read it and this is the lowest layer they share (``surface.py`` the height under any point and each
element's pieces, ``heightmap.py`` height grids, ``crossing.py`` what a body can cross, ``chassis.py``
a wheeled body's layout).
"""
from .model import (  # noqa: F401  (the model is the public face of this package)
    SCHEMA_VERSION,
    BoxObstacle,
    CylinderObstacle,
    Footprint,
    GoalTolerance,
    Lidar,
    Limits,
    Mark,
    Mission,
    Obstacle,
    Pose,
    Reference,
    Robot,
    Safety,
    Scenario,
    Simulation,
    content_hash,
)
