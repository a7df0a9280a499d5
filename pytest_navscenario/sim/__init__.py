"""Sim: one episode in MuJoCo, the only part of the package that imports ``mujoco``.

In: a ``Scenario`` and a planner (any object of the protocol in ``subjects.protocol``). Out: a
``SimResult``: the recorded ``Trajectory`` (sim/trajectory.py) and the event that ended the
episode (collision, safety stop, subject failure), bit-identical for the same scenario and seed.

Read first: ``episode.py`` (the control loop: observe, safety check, act, step physics, record),
then ``safety.py`` (the collision safety layer) and ``deadline.py`` (the per-tick time limit).

Names are imported lazily so that importing this package does not import MuJoCo.
"""
from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {name: "episode" for name in (
    "simulate", "SimResult", "validate_command", "compiled_world", "clear_model_cache", "build_spec",
    "model_xml", "World", "lidar_angles", "steps_per_tick", "wrap_angle", "LIDAR_HEIGHT", "ROBOT_HEIGHT",
    "ROBOT_MASS")}
_EXPORTS.update(SafetyLayer="safety", TickDeadline="deadline", PlannerTimeout="deadline",
                Trajectory="trajectory", Collision="trajectory", SafetyStop="trajectory",
                SubjectFailure="trajectory")
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f".{module}", __name__), name)
