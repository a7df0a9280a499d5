"""pytest-navscenario: scenario-based regression testing of mobile-robot navigation.

Public API (imported lazily so that loading the pytest plugin stays cheap)::

    load_scenario(path) / loads_scenario(text) / dump_scenario(s) / save_scenario(s, path)
    run_scenario(scenario, planner=None, seed=None) -> EpisodeResult
    check_planner(planner) -> PlannerCheck
"""
from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_EXPORTS = {
    "load_scenario": "loader", "loads_scenario": "loader", "dump_scenario": "loader",
    "save_scenario": "loader", "scenario_from_dict": "loader", "scenario_to_dict": "loader",
    "run_scenario": "runner",
    "check_planner": "conformance",
    "Scenario": "scenario", "Pose": "scenario", "BoxObstacle": "scenario", "CylinderObstacle": "scenario",
    "Robot": "scenario", "Mission": "scenario", "Footprint": "scenario", "content_hash": "scenario",
    "Observation": "planner", "Command": "planner", "Planner": "planner", "load_subject": "planner",
    "EpisodeResult": "result", "Outcome": "result", "Metrics": "result", "Trajectory": "result",
    "ScenarioError": "errors", "SubjectLoadError": "errors", "NavScenarioError": "errors",
}

__all__ = sorted(_EXPORTS) + ["__version__"]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'pytest_navscenario' has no attribute {name!r}")
    return getattr(importlib.import_module(f".{module}", __name__), name)
