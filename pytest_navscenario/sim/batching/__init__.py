"""Sim/batching: many episodes stepped together, each one's trajectory the bits it has alone.

Read first: ``batch.py`` (the ``BatchEngine`` interface, ``simulate_batch`` and the engine
registry), then ``lockstep.py`` (the CPU engine's loop: every running ``Episode`` a tick at a time,
one planner call a tick), ``cohort.py`` (the observation step done for many planar episodes at
once where that cannot change a bit), and the optional GPU engine: ``warp_engine.py`` (what it
runs, what it refuses), ``warp_loop.py`` (the lockstep loop with the physics on the device) and
``warp_worlds.py`` (the batch's worlds on a MuJoCo Warp device).
"""
