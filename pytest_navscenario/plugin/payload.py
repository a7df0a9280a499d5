"""``report.nav``: one episode as a plain, JSON-able dict, so that it crosses from an xdist worker
to the controller (execnet only carries plain types) and feature plugins need no simulation.

Format (set on the *call* report of every scenario item that ran an episode)::

    {
      "record":     results.make_record(...)       # the results-file record (outcome, metrics, ...)
      "scenario":   loader.scenario_to_dict(...)   # the scenario exactly as run
      "source":     "scenarios/boxes1.yaml"        # scenario file, relative to the rootdir
      "events":     {"collision": {...} | None, "safety_stop": {...} | None,
                     "subject_failure": {...} | None, "terrain": {...} | None}
      "metrics":    Metrics.as_dict()              # exact (inf/nan kept; the record has null)
      "timings":    {"physics": s, ...}            # the runner's timing breakdown
      "trajectory": result.trajectory_to_dict(...) # ONLY when requested, else None (the 3D
                                                   # lidar's scans only on request_clouds)
    }

Feature plugins ask for trajectories with ``request_trajectories(config, "failed" | "all")`` in
their ``pytest_configure`` ("failed" = episodes whose outcome is not success); the request is made
in every process (xdist workers run the same ``pytest_configure``), so workers include them.
On the controller, ``episode_from_payload(report.nav)`` rebuilds an EpisodeResult.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Any

import pytest

from ..sim.trajectory import (
    Collision,
    SafetyStop,
    SubjectFailure,
    TerrainEvent,
    Trajectory,
    trajectory_from_dict,
    trajectory_to_dict,
)
from ..verdict.result import EpisodeResult, Metrics, Outcome

TRAJECTORY_CHOICES = ("none", "failed", "all")
_REQUEST_KEY = pytest.StashKey[str]()


def request_trajectories(config: pytest.Config, which: str) -> None:
    """Ask the core plugin to put trajectories into ``report.nav``: "failed" or "all".

    Requests only widen ("all" beats "failed"); call it from ``pytest_configure``.
    """
    if which not in ("failed", "all"):
        raise ValueError(f"request_trajectories: which must be 'failed' or 'all', got {which!r}")
    current = config.stash.get(_REQUEST_KEY, "none")
    if TRAJECTORY_CHOICES.index(which) > TRAJECTORY_CHOICES.index(current):
        config.stash[_REQUEST_KEY] = which


_CLOUDS_KEY = pytest.StashKey[bool]()


def request_clouds(config: pytest.Config) -> None:
    """Ask for the 3D lidar's scans in the trajectories of ``report.nav`` too (bags show them; they
    are megabytes an episode, so only on request). Call it from ``pytest_configure``."""
    config.stash[_CLOUDS_KEY] = True


def clouds_requested(config: pytest.Config) -> bool:
    return config.stash.get(_CLOUDS_KEY, False)


def trajectories_requested(config: pytest.Config) -> str:
    """"none", "failed" or "all": what the feature plugins have asked for so far."""
    return config.stash.get(_REQUEST_KEY, "none")


def _shallow(value: Any) -> dict[str, Any]:
    """dataclasses.asdict for flat dataclasses of plain values, without its deep copies (~20x faster)."""
    return {f.name: getattr(value, f.name) for f in dataclasses.fields(value)}


def _event(value: Any) -> dict[str, Any] | None:
    return _shallow(value) if value is not None else None


def episode_to_payload(result: EpisodeResult, *, nodeid: str, path: str,
                       with_trajectory: bool, repeat: int = 0,
                       subject_spec: str | None = None, with_cloud: bool = False) -> dict[str, Any]:
    """The ``report.nav`` dict of one episode (see the module docstring)."""
    from ..scenario.dump import scenario_to_dict
    from ..report.results_file import make_record

    return {
        "record": make_record(result, nodeid=nodeid, path=path, repeat=repeat,
                              subject_spec=subject_spec),
        "scenario": scenario_to_dict(result.scenario),
        "source": path,
        "events": {
            "collision": _event(result.collision),
            "safety_stop": _event(result.safety_stop),
            "subject_failure": _event(result.subject_failure),
            "terrain": _event(result.terrain_event),
        },
        "metrics": _shallow(result.metrics),
        "timings": dict(result.timings),
        "trajectory": trajectory_to_dict(result.trajectory, cloud=with_cloud) if with_trajectory else None,
    }


def _metrics(data: dict[str, Any]) -> Metrics:
    names = {f.name for f in dataclasses.fields(Metrics)}
    return Metrics(**{k: (math.nan if v is None else v) for k, v in data.items() if k in names})


def episode_from_payload(payload: dict[str, Any]) -> EpisodeResult:
    """Rebuild the EpisodeResult from ``report.nav`` (controller side).

    Without a trajectory in the payload the result has an empty Trajectory (zero rows).
    Metrics written as null (non-finite) come back as NaN.
    """
    from ..scenario.loader import scenario_from_dict

    rec = payload["record"]
    events = payload.get("events") or {}
    traj = payload.get("trajectory")

    def ev(cls: type, key: str) -> Any:
        data = events.get(key)
        return cls(**data) if data is not None else None

    return EpisodeResult(
        scenario=scenario_from_dict(payload["scenario"], source=payload.get("source")),
        outcome=Outcome(rec["outcome"]),
        metrics=_metrics(payload.get("metrics") or rec["metrics"]),
        trajectory=trajectory_from_dict(traj) if traj is not None else Trajectory.empty(),
        seed=rec["seed"],
        subject=rec.get("subject", ""),
        subject_version=rec.get("subject_version"),
        message=rec.get("message", ""),
        collision=ev(Collision, "collision"),
        safety_stop=ev(SafetyStop, "safety_stop"),
        subject_failure=ev(SubjectFailure, "subject_failure"),
        wall_time=rec.get("wall_time", 0.0),
        timings=dict(payload.get("timings") or {}),
        terrain_event=ev(TerrainEvent, "terrain"),
    )


def crashed_item_payload(config: pytest.Config, report: pytest.TestReport) -> dict[str, Any] | None:
    """Controller: the ``report.nav`` of a scenario item whose xdist worker process died while
    running it (xdist reports it with ``when == "???"`` and no payload), rebuilt from its scenario
    file: outcome subject-error, ``error`` "WorkerCrashed", so that the item has a record and counts
    in the rates like every other (issue 32). None for what is not a scenario item."""
    import re

    from ..core.errors import NavScenarioError
    from ..harness.runner import effective_seed, unfinished_result
    from ..scenario.loader import load_scenario
    from .state import get_state

    path, _, name = report.nodeid.partition("::")
    if not name or not path.endswith((".yaml", ".yml")):
        return None
    found = re.fullmatch(r"(.*)\[r(\d+)\]", name)
    repeat = int(found.group(2)) if found else 0
    try:
        scenario = load_scenario(config.rootpath / path)
    except (NavScenarioError, OSError):
        return None
    if not scenario.family:
        scenario = dataclasses.replace(scenario, family=(config.rootpath / path).parent.name)
    state = get_state(config)
    from ..core.seeds import repeat_seed
    seed = effective_seed(scenario.simulation.seed, repeat_seed(state.settings.seed, repeat))
    crash = RuntimeError("WorkerCrashed: the pytest-xdist worker running this item died (a planner "
                         "that ended its process, a crash in C code, the out-of-memory killer)")
    result = unfinished_result(scenario, crash, seed=seed, subject=state.subject.spec or state.subject.label)
    spec = state.subject.spec if state.subject.origin != "hook" else None
    return episode_to_payload(result, nodeid=report.nodeid, path=path, with_trajectory=False,
                              repeat=repeat, subject_spec=spec)
