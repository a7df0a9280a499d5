"""pytest-navscenario: scenario-based regression testing of mobile-robot navigation.

Public API (imported lazily so that loading the pytest plugin stays cheap)::

    load_scenario(path) / loads_scenario(text) / dump_scenario(s) / save_scenario(s, path)
    run_scenario(scenario, planner=None, seed=None) -> EpisodeResult
    check_planner(planner) -> PlannerCheck
    scenarios_around(seed) -> Hypothesis strategy of scenarios near a seed

The package is layered; each subpackage's docstring says what flows in and out. From the pytest
glue at the top down to the scenario model (imports only point down, checked in CI)::

    plugin/  cli/          pytest hooks, options, items; the ``navscenario`` console script
    search/  report/  ros/ failure search and freezing; results, compare, plots, HTML; bags, imports
    dispatch/              batches of episodes on this machine's cores or as Ray tasks
    harness/               run one scenario against one subject; the planner conformance check
    verdict/               oracle (outcome), metrics, shortest paths, the episode result
    sim/                   MuJoCo world, control loop, lidar, safety layer (the only mujoco user)
    subjects/              planner protocol, loading subjects, external planners, built-in planners
    scenario/              the scenario model, YAML loading and dumping, footprint geometry
    stl/                   requirements in signal temporal logic: parsing, robustness (numpy)
    core/                  errors and atomic file writes, shared by all
"""
from __future__ import annotations

from . import _compat
from .core.lazy import lazy_exports

__version__ = "0.1.0"

_EXPORTS = {
    "load_scenario": "scenario.loader", "loads_scenario": "scenario.loader",
    "scenario_from_dict": "scenario.loader",
    "dump_scenario": "scenario.dump", "save_scenario": "scenario.dump", "scenario_to_dict": "scenario.dump",
    "run_scenario": "harness.runner",
    "check_planner": "harness.conformance",
    "scenarios_around": "search.space",
    "Scenario": "scenario.model", "Pose": "scenario.model", "BoxObstacle": "scenario.model",
    "CylinderObstacle": "scenario.model", "Robot": "scenario.model", "Mission": "scenario.model",
    "Footprint": "scenario.model", "content_hash": "scenario.model",
    "Observation": "subjects.protocol", "Command": "subjects.protocol", "Planner": "subjects.protocol",
    "load_subject": "subjects.loading",
    "EpisodeResult": "verdict.result", "Outcome": "verdict.result", "Metrics": "verdict.result",
    "Trajectory": "sim.trajectory",
    "ScenarioError": "core.errors", "SubjectLoadError": "core.errors", "NavScenarioError": "core.errors",
}

__all__ = sorted(_EXPORTS) + ["__version__"]

_compat.install()

__getattr__ = lazy_exports(__name__, _EXPORTS)
