"""``navscenario from-bag``: a seed scenario from a real robot's bag.

Odometry and laser topics are found by type (override with ``--odom-topic`` / ``--scan-topic``).
The scenario's world frame is the odometry frame:

* start and goal: the first and last odometry pose in the time window;
* the driven path: decimated waypoints, or a reference trajectory (CSV ``t,x,y`` beside the
  seed, ``reference.file`` relative to it);
* obstacles: every scan projected with the laser's mount transform (``--laser-pose``, else
  ``/tf_static``, else the first ``/tf`` transforms, else guessed from the scans), accumulated in
  the odometry frame on a grid, clustered, and fitted as cylinders and oriented boxes.

Modules, in the order the data flows: ``reading`` (bag -> arrays), ``mount`` (laser mounting),
``projection`` (scans -> grid), ``obstacles`` (grid -> clusters -> obstacles), ``seed`` (the
scenario), ``cli`` (the command line).
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
