"""Sim/ground: a robot that rides the ground, in MuJoCo.

Read first: ``terrain.py`` (floor, ramps, steps, platforms and pits as MuJoCo primitives, and the
contact settings every body rides on), then ``heightfield.py`` (rough ground and height files as
``hfield`` geoms), ``hfield_rays.py`` (the lidars' own ray cast over height grids;
``hfield_march.py`` the same cast compiled), ``riding.py`` (the ground under a point, the pose a
body rests in, the watch that tells a fall, a tip-over or being stuck) and ``ground_safety.py``
(what the safety layer predicts with on the ground).

``sim/body_world.py`` puts these and a body from ``sim/bodies/`` together into the world of a
riding body. The geometry all of this builds from is MuJoCo-free and lives in
``scenario/ground/`` (the loader, the verdict, the pictures and the search read it too).
"""
