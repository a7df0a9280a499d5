"""Sim: one episode in MuJoCo, the only part of the package that imports ``mujoco``.

In: a ``Scenario`` and a planner (any object of the protocol in ``subjects.protocol``). Out: a
``SimResult``: the recorded ``Trajectory`` (sim/trajectory.py) and the event that ended the
episode (collision, safety stop, subject failure), bit-identical for the same scenario and seed.

Read first: ``episode.py`` (the control loop as an ``Episode``: observe, safety check, act, record,
step physics), then ``world.py`` (the MuJoCo model built from the scenario, compiled and cached),
``lidar.py`` (beam tables and the scan), ``command.py`` (calling the planner, validating its answer,
the drive limits), ``safety.py`` (the collision safety layer), ``moving.py`` (moving obstacles:
their mocap positions every physics step, their velocities for the safety layer, who moved in a
collision), ``faults.py`` (localisation drift and latency: what the planner is handed) and
``deadline.py`` (the per-tick time limit). A body that rides the ground: ``body_world.py`` (its
world) and the subpackages ``bodies/`` (wheeled, legged, the user's MJCF) and ``ground/`` (the
terrain in MuJoCo, heightfields and their ray cast, riding, the ground's safety layer). Many
episodes at once: ``batching/`` (the batch engines: CPU lockstep and MuJoCo Warp).

Terrain and bodies (a robot that rides the ground): ``body_world.py`` (its world: gravity, the
terrain, which chassis contact is a collision), ``bodies/`` (wheeled, legged, MJCF; ``base.py``
first), ``terrain.py`` and ``heightfield.py`` (the terrain as geoms), ``riding.py`` (the ground
under the robot, the watch for falls, tip-overs, being stuck), ``ground_safety.py`` and
``lidar3d.py`` (the 3D lidar and the safety layer's view of the ground), ``hfield_rays.py``; the
episode is ``episode.RidingEpisode``.

Batches: ``batch.py`` (the engine interface), ``lockstep.py`` and ``cohort.py`` (the CPU engine,
bit-identical to running alone), ``warp_engine.py``, ``warp_worlds.py`` and ``warp_loop.py`` (MuJoCo
Warp, optional extra ``gpu``); ``profiler.py`` keeps MuJoCo's profiler off.

Names are imported lazily so that importing this package does not import MuJoCo.
"""
from __future__ import annotations

from ..core.lazy import lazy_exports

_EXPORTS = {name: "world" for name in (
    "compiled_world", "clear_model_cache", "build_spec", "World", "steps_per_tick",
    "wrap_angle", "LIDAR_HEIGHT", "ROBOT_HEIGHT", "ROBOT_MASS", "TRACKING_TAU", "FORCE_HEADROOM",
    "MODEL_CACHE_SIZE", "TWO_PI")}
_EXPORTS.update(model_xml="body_world", any_world="body_world", simulate="episode", SimResult="episode", Episode="episode", STILL="episode",
                validate_command="command", lidar_angles="lidar",
                SafetyLayer="safety", TickDeadline="deadline", PlannerTimeout="deadline",
                Trajectory="trajectory", Collision="trajectory", SafetyStop="trajectory",
                SubjectFailure="trajectory")
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_exports(
    __name__, _EXPORTS, " (see its modules episode, world, lidar, command, safety, deadline, trajectory)")
