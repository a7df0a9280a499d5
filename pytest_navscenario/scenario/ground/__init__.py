"""Scenario/ground: the scenario's ground as geometry, MuJoCo-free.

Read first: ``surface.py`` (the height under any (x, y), each terrain element's outline and convex
pieces, and the loader's terrain checks), then ``heightmap.py`` (height grids: rough ground and
PNG/npy files, read, checked and cached), ``crossing.py`` (what a body can cross: its capability,
the barriers along a profile, the steep areas of a grid) and ``chassis.py`` (a wheeled body's
layout and whether it can stand and brake without tipping).

Why here and not in ``sim/``: these are pure functions of the ``Scenario``, read by the loader's
checks, the verdict, the pictures, the search, the ROS import and the simulation alike; the
scenario layer is the lowest one that knows the terrain model, and none of those readers may
import MuJoCo (import-linter's contracts).
"""
