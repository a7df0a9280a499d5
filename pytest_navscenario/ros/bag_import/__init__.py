"""``navscenario from-bag``: a seed scenario from a real robot's bag.

Topics are found by type (odometry; a 2D laser, else a 3D lidar's point cloud; transforms,
localisation poses, navigation goals, velocity commands, the robot's URDF and Nav2 footprint).
The seed's world frame is the map frame when the bag has ``map -> odom`` or a pose topic in the
map, else the odometry frame:

* start: the first pose of the window (``--start``/``--end``, or ``--at`` with ``--window``);
  goal: the recorded navigation goal in force at the window's end, else its last pose;
* the driven path: decimated waypoints, or a reference trajectory (CSV ``t,x,y`` beside the
  seed, ``reference.file`` relative to it);
* obstacles: every scan projected with the laser's mounting (``--laser-pose``, else
  ``/tf_static``, else the first ``/tf`` transforms, else guessed from the scans), or every point
  cloud (streamed, ground removed, the robot's height band kept), accumulated on a grid,
  clustered, and fitted as cylinders and oriented boxes (with their heights from a 3D lidar);
  neighbours merged into simplified polygons; those near the driven path searchable, the rest
  (and the bag's ``/map``, when there is one) a fixed background in ``search: frozen``;
* the robot: the footprint from the URDF or Nav2, else a circle.

``--list-events`` lists candidate moments of the whole bag instead (``events``).

Modules, in the order the data flows: ``topics`` (which topic plays which part), ``reading``
(first pass: bag -> arrays), ``frames`` (map or odometry frame), ``goal``, ``footprint``,
``mount`` (laser mounting), ``projection`` (scans -> grid), ``clouds`` (second pass: clouds ->
grid), ``obstacles`` (grid -> clusters -> obstacles), ``simplify`` (merge, searchable or fixed),
``known_map`` (the bag's /map), ``seed`` (the scenario), ``events``,
``cli`` (the command line).
"""
from __future__ import annotations

from .cli import add_arguments, reference_csv, run
from .mount import estimate_mount, laser_mount
from .obstacles import Cluster, FitSettings, fit_circle, fit_obstacles, occupied_clusters
from .projection import Grid, grid_returns, project_scans
from .reading import BagData, BagImportError, read_bag
from .seed import BagSeed, decimate_path, scenario_from_bag

__all__ = [
    "BagData", "BagImportError", "BagSeed", "Cluster", "FitSettings", "Grid", "add_arguments",
    "decimate_path", "estimate_mount", "fit_circle", "fit_obstacles", "grid_returns", "laser_mount",
    "occupied_clusters", "project_scans", "read_bag", "reference_csv", "run", "scenario_from_bag",
]
