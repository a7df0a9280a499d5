"""The results file: one JSON object per line and per episode (``--nav-results=PATH``).

Record fields (format_version 1)::

    format            "navscenario-results"
    format_version    1
    tool_version      package version that wrote it
    mujoco_version    the MuJoCo release that simulated the episode (its bits are that release's)
    nodeid            pytest node id, e.g. "scenarios/boxes1.yaml::boxes1"
    path              scenario file, relative to the rootdir (posix separators)
    scenario          scenario name
    family            scenario family
    scenario_hash     scenario.content_hash(): pairs the same layout across files
    subject           subject name (its ``name`` attribute) or spec; subject_version (or null)
    subject_spec      what to pass to --nav-subject to run the same subject again (or null when a
                      conftest hook provided it)
    seed              the episode's effective noise seed
    repeat            repeat index (0 unless --nav-repeat)
    outcome           "success" | "collision" | "fall" | "safety-stop" | "timeout" | "subject-error"
    passed            outcome == success
    message           one line: why this outcome
    metrics           Metrics.as_dict(); non-finite floats written as null (strict JSON)
    collision         null, or who hit whom: {"obstacle", "time", "robot_moving" (false: the robot
                      stood still and was hit), "robot_speed", "obstacle_speed"} (m/s)
    wall_time         s
    error             only in the record of an episode that never finished: what ended it
                      ("WorkerDied": its process died 3 times; "RayTaskLost"; or the exception's
                      type); its outcome is "subject-error" and its metrics are null

Every scenario item that ran has a record, crashed or not, so the rates count it.

Files are written whole and atomically (``atomic_write_text``), so an interrupted run leaves
either the previous file or a complete new one.
"""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Iterable

from ..core.errors import NavScenarioError
from ..core.files import atomic_write_text, json_safe
from ..core.versions import mujoco_version
from ..verdict.result import EpisodeResult
from ..scenario.model import content_hash

FORMAT = "navscenario-results"
FORMAT_VERSION = 1
REQUIRED_FIELDS = ("nodeid", "scenario", "family", "scenario_hash", "subject", "outcome", "metrics")
OUTCOMES = ("success", "collision", "fall", "safety-stop", "timeout", "subject-error")


class ResultsFileError(NavScenarioError):
    """A results file cannot be read: wrong format, other version, missing fields."""


def _tool_version() -> str:
    from .. import __version__
    return __version__


def make_record(result: EpisodeResult, *, nodeid: str, path: str, repeat: int = 0,
                subject_spec: str | None = None) -> dict[str, Any]:
    """The results-file record of one episode."""
    s = result.scenario
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "tool_version": _tool_version(),
        "mujoco_version": mujoco_version(),
        "nodeid": nodeid,
        "path": path,
        "scenario": s.name,
        "family": s.family,
        "scenario_hash": content_hash(s),
        "subject": result.subject,
        "subject_version": result.subject_version,
        "subject_spec": subject_spec,
        "seed": result.seed,
        "repeat": repeat,
        "outcome": result.outcome.value,
        "passed": result.passed,
        "message": result.message,
        "metrics": json_safe(result.metrics.as_dict()),
        "collision": _collision_record(result),
        "wall_time": result.wall_time,
        **({"error": result.error} if result.error is not None else {}),
    }


def _collision_record(result: EpisodeResult) -> dict[str, Any] | None:
    c = result.collision
    if c is None:
        return None
    return {"obstacle": c.obstacle, "time": c.time, "robot_moving": bool(c.robot_moving),
            "robot_speed": c.robot_speed, "obstacle_speed": c.obstacle_speed}


def write_results(path: str | os.PathLike, records: Iterable[dict[str, Any]]) -> None:
    """Write records as JSON Lines, sorted by (nodeid, repeat) so files diff cleanly."""
    ordered = sorted(records, key=lambda r: (r["nodeid"], r.get("repeat", 0)))
    atomic_write_text(path, "".join(json.dumps(r, sort_keys=True, allow_nan=False) + "\n" for r in ordered))


def read_results(path: str | os.PathLike) -> list[dict[str, Any]]:
    """Read and check a results file; raise ResultsFileError naming the file, line and problem."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        raise ResultsFileError(f"{path}: no such results file (write one with pytest --nav-results={path})") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ResultsFileError(f"{path}: cannot read: {exc}") from None
    records = []
    for lineno, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
        except (json.JSONDecodeError, RecursionError) as exc:
            why = exc.msg if isinstance(exc, json.JSONDecodeError) else "nested too deeply"
            raise ResultsFileError(f"{path}:{lineno}: not JSON ({why}); is this a --nav-results file?") from None
        if not isinstance(rec, dict) or rec.get("format") != FORMAT:
            raise ResultsFileError(f"{path}:{lineno}: not a navscenario results record (no \"format\": \"{FORMAT}\")")
        version = rec.get("format_version")
        if version != FORMAT_VERSION:
            raise ResultsFileError(
                f"{path}:{lineno}: results format version {version!r} (written by pytest-navscenario "
                f"{rec.get('tool_version', '?')}), this version reads {FORMAT_VERSION}: re-run the suite "
                f"with this version to write a comparable file")
        missing = [f for f in REQUIRED_FIELDS if f not in rec]
        if missing:
            raise ResultsFileError(f"{path}:{lineno}: record lacks field(s) {', '.join(missing)}")
        if rec["outcome"] not in OUTCOMES:
            raise ResultsFileError(f"{path}:{lineno}: unknown outcome {rec['outcome']!r} (expected one of {', '.join(OUTCOMES)})")
        records.append(rec)
    return records
