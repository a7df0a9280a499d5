"""``navscenario from-bag``: a seed scenario from a real robot's bag.

Topics are found by type (odometry; a 2D laser, else a 3D lidar's point cloud; transforms,
localisation poses, navigation goals, velocity commands, the robot's URDF and Nav2 footprint).
The seed's world frame is the map frame when the bag has ``map -> odom`` or a pose topic in the
map, else the odometry frame:

* start: the first pose of the window (``--start``/``--end``, or ``--at`` with ``--window``);
  goal: the recorded navigation goal in force at the window's end, else its last pose;
* the driven path: decimated waypoints, or a reference trajectory (CSV ``t,x,y`` beside the
  seed, ``reference.file`` relative to it);
* obstacles: every scan streamed (a second pass over the bag), each beam placed with the robot's
  pose at the moment it was measured (``time_increment`` / ``scan_time``, the driver's stamp
  convention) and the laser's mounting (``--laser-pose``, else ``/tf_static``, else the first
  ``/tf`` transforms, else guessed from the scans); without ``map -> odom`` the poses corrected by
  scan matching (``--scan-match``); returns accumulated on a grid and free space
  carved along every beam (log-odds occupancy), or every point cloud (streamed, ground removed,
  the robot's height band kept); clustered and fitted as cylinders, compact boxes and wall
  outlines (simplified polygons; with their heights from a 3D lidar); neighbours merged into
  simplified polygons; those near the driven path searchable, the rest (and the bag's ``/map``,
  when there is one) a fixed background in ``search: frozen``;
* the robot: the footprint from the URDF or Nav2, else a circle;
* the fit figure: the seed ray-cast from the recorded poses against the recorded ranges (``fit``).

``--list-events`` lists candidate moments of the whole bag instead (``events``).

Modules, in the order the data flows: ``topics`` (which topic plays which part), ``reading``
(first pass: bag -> arrays), ``scans`` (the scans' layout and timing, the streamed second pass),
``motion`` (turns, reversing), ``frames`` (map or odometry frame), ``goal``, ``footprint``,
``mount`` (laser mounting), ``scan_match`` (odometry drift corrected by aligning scans),
``projection`` (beams -> grid), ``occupancy`` (log-odds, free space carved, walls beside the path
kept), ``clouds`` (second pass: clouds -> grid), ``obstacles`` (grid -> clusters -> obstacles),
``outline`` (cells -> wall polygons), ``simplify`` (merge, searchable or fixed), ``known_map`` (the
bag's /map), ``seed`` (the scenario), ``fit`` (the seed against its scans), ``events``, ``cli``
(the command line).
"""
from __future__ import annotations

from .cli import add_arguments, reference_csv, run
from .mount import estimate_mount, laser_mount
from .obstacles import Cluster, FitSettings, fit_circle, fit_obstacles, occupied_clusters
from .projection import Grid, ScanMap, map_scans, project_scans
from .reading import BagData, BagImportError, read_bag
from .seed import BagSeed, decimate_path, scenario_from_bag

__all__ = [
    "BagData", "BagImportError", "BagSeed", "Cluster", "FitSettings", "Grid", "add_arguments",
    "decimate_path", "estimate_mount", "fit_circle", "fit_obstacles", "laser_mount", "map_scans",
    "occupied_clusters", "project_scans", "read_bag", "reference_csv", "run", "ScanMap", "scenario_from_bag",
]
