"""Freezing search results: failures as ordinary scenario YAML, the search log, a JUnit file.

Layout under the regressions folder (``--navsearch-out`` / ini ``navsearch_out``)::

    <out>/<seed name>/<seed name>-<content hash>.yaml   one per distinct (shrunk) failure
    <out>/<seed name>/search-log.jsonl                   every simulated candidate of the last search

A frozen file's name comes from ``scenario.content_hash()``, so the same failure found again
maps to the same file: it is not duplicated (the first file, and its provenance, are kept).
Failures whose shrunk layouts fail the same way (the same cause signature, fitness.py) are
frozen once: no near-copies.
Every file is written atomically, so an interrupted run never leaves half a file.
"""
from __future__ import annotations

import datetime as _dt
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Iterable

from ..core.files import atomic_write_text
from ..scenario.model import Scenario, content_hash
from .engine import Candidate, Failure, SearchReport
from .space import SearchSpace

DEFAULT_OUT = "scenarios/regressions"
LOG_NAME = "search-log.jsonl"
PROVENANCE_METRICS = ("min_clearance", "min_clearance_obstacle", "path_length", "duration",
                      "path_efficiency", "min_obstacle_gap")


@dataclass
class FrozenFile:
    path: Path
    new: bool                # False: the same failure was already frozen (file kept as it was)
    outcome: str
    clearance: float


def _clean(value: Any) -> Any:
    if isinstance(value, float):
        return None if not math.isfinite(value) else round(value, 6)
    return value


def _portable(path: str | None, root: str | Path | None) -> str | None:
    """``path`` relative to ``root`` (posix separators) when it lies inside it."""
    if not path or root is None:
        return path
    try:
        return Path(path).resolve().relative_to(Path(root).resolve()).as_posix()
    except (ValueError, OSError):
        return path


def candidate_provenance(report: SearchReport, cand: Candidate, space: SearchSpace, *,
                         subject: str | None = None, root: str | Path | None = None) -> dict[str, Any]:
    """Where a simulated candidate came from and what it did (the ``provenance`` of a frozen
    failure or of a generated suite case): deterministic, no date or timing."""
    seed = space.seed
    return {
        "seed": seed.name,
        "seed_file": _portable(seed.source, root),
        "subject": subject or report.subject,
        "subject_version": report.subject_version,
        "outcome": cand.outcome,
        "message": cand.message,
        "culprit": cand.culprit,
        "metrics": {k: _clean(cand.metrics.get(k)) for k in PROVENANCE_METRICS if k in cand.metrics},
        "offsets": space.as_mapping(cand.offsets),
        "search_seed": report.seed_value,
        "strategy": report.strategy,
        "budget": report.budget,
        "nav_seed": report.episode_seed or 0,
    }


def candidate_scenario(cand: Candidate, space: SearchSpace) -> Scenario:
    """The layout ``cand`` simulated."""
    return cand.scenario if cand.scenario is not None else space.apply(cand.offsets)


def standalone_scenario(scenario: Scenario, seed: Scenario, *, name: str, description: str,
                        provenance: dict[str, Any]) -> Scenario:
    """A candidate's layout as an ordinary scenario of the seed's family (no ``search:`` block,
    no marks), with ``provenance``."""
    return replace(scenario, name=name, family=seed.name, description=description,
                   marks=(), search=None, provenance=provenance, reference=seed.reference)


def save_standalone(scenario: Scenario, seed: Scenario, path: Path) -> None:
    """Write ``scenario`` to ``path`` atomically, its mesh files copied beside it."""
    from ..scenario.dump import save_scenario
    from ..scenario.modeline import ensure_project_schema

    path.parent.mkdir(parents=True, exist_ok=True)
    save_scenario(_with_mesh_copies(scenario, seed, path.parent), path)
    ensure_project_schema(path)     # the schema its modeline names, so an editor reads it at once


def frozen_scenario(report: SearchReport, failure: Failure, space: SearchSpace, *, date: str | None = None,
                    subject: str | None = None, root: str | Path | None = None) -> Scenario:
    """The shrunk failure as a standalone scenario with its provenance (no ``search:`` block)."""
    cand = failure.shrunk
    seed = space.seed
    scenario = candidate_scenario(cand, space)
    provenance = candidate_provenance(report, cand, space, subject=subject, root=root)
    provenance.update({
        "found_offsets": space.as_mapping(failure.found.offsets),
        "found_at_simulation": failure.found.sim,
        "shrink_simulations": failure.shrink_sims,
        "date": date or _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat(),
    })
    if failure.note:
        provenance["note"] = failure.note
    return standalone_scenario(
        scenario, seed, name=f"{seed.name}-{content_hash(scenario)}",
        description=(f"{cand.outcome} of {provenance['subject']} found by navsearch around "
                     f"{seed.name} (search seed {report.seed_value}); culprit {cand.culprit or '-'}"
                     + _where(cand)),
        provenance=provenance)


def _where(cand: Any) -> str:
    """Where along the seed's route the failure happened (from the cause signature)."""
    if len(cand.signature) < 4:
        return ""
    quarters = ("first", "second", "third", "last")
    return (f" (beside the {quarters[cand.signature[2]]} quarter of the route), robot stopped in the "
            f"{quarters[cand.signature[3]]} quarter")


def freeze_failures(report: SearchReport, space: SearchSpace, out_dir: str | Path, *,
                    subject: str | None = None, root: str | Path | None = None) -> list[FrozenFile]:
    """Write each failure of ``report`` under ``out_dir/<seed name>/`` (existing ones kept)."""
    folder = Path(out_dir) / space.seed.name
    written: list[FrozenFile] = []
    seen: set[Path] = set()
    causes: set[tuple] = set()
    for failure in report.failures:
        scenario = frozen_scenario(report, failure, space, subject=subject, root=root)
        path = folder / f"{scenario.name}.yaml"
        cause = tuple(failure.shrunk.signature)
        # two distinct failures that shrank to the same layout, or to the same way of failing
        if path in seen or (cause and cause in causes):
            continue
        seen.add(path)
        causes.add(cause)
        new = not path.exists()
        if new:
            save_standalone(scenario, space.seed, path)
        written.append(FrozenFile(path, new, failure.shrunk.outcome, failure.shrunk.clearance))
    return written


def _with_mesh_copies(scenario: Scenario, seed: Scenario, folder: Path) -> Scenario:
    """The frozen scenario with its mesh files copied beside it (``meshes/<stem>-<hash><suffix>``,
    named by their content so equal files are stored once): a mesh path must stay inside the
    scenario's folder, and the frozen file lives elsewhere than its seed."""
    import hashlib
    import shutil

    from ..scenario.model import MeshObstacle

    if not any(isinstance(o, MeshObstacle) for o in scenario.obstacles):
        return scenario
    base = Path(seed.source).parent if seed.source else Path.cwd()
    obstacles = []
    for obs in scenario.obstacles:
        if isinstance(obs, MeshObstacle):
            src = base / obs.file
            digest = hashlib.sha256(src.read_bytes()).hexdigest()[:12]
            rel = Path("meshes") / f"{src.stem}-{digest}{src.suffix.lower()}"
            if not (folder / rel).exists():
                (folder / rel.parent).mkdir(parents=True, exist_ok=True)
                shutil.copyfile(src, folder / rel)
            obs = replace(obs, file=rel.as_posix())
        obstacles.append(obs)
    return replace(scenario, obstacles=tuple(obstacles))


def log_records(report: SearchReport, space: SearchSpace) -> list[dict[str, Any]]:
    head = {"seed": report.seed_name, "subject": report.subject, "strategy": report.strategy,
            "search_seed": report.seed_value, "budget": report.budget, "search_sims": report.sims_used,
            "shrink_sims": report.shrink_sims, "shrink_budget": report.shrink_total}
    return [{**head, **c.to_dict(space)} for c in report.candidates]


def write_search_log(report: SearchReport, space: SearchSpace, out_dir: str | Path) -> Path:
    """Every simulated candidate (search and shrink phases) as JSON Lines, beside the frozen files."""
    path = Path(out_dir) / space.seed.name / LOG_NAME
    text = "".join(json.dumps(r, sort_keys=True, allow_nan=False) + "\n" for r in log_records(report, space))
    atomic_write_text(path, text)
    return path


def write_junit(items: Iterable[tuple[SearchReport, SearchSpace]], path: str | Path) -> Path:
    """The generated suite as JUnit XML: one test suite per search, one test case per simulated
    candidate of its search phase, failing where the planner failed."""
    from junit_xml import TestCase, TestSuite, to_xml_report_string

    suites = []
    for report, space in items:
        cases = []
        for c in report.candidates:
            if c.phase != "search":
                continue
            tc = TestCase(name=f"{report.seed_name}[sim{c.sim:04d}-{c.scenario_hash}]",
                          classname=f"navsearch.{report.seed_name}", elapsed_sec=round(c.wall_time, 6),
                          stdout=json.dumps(space.as_mapping(c.offsets), sort_keys=True))
            if c.outcome == "harness-error":
                tc.add_error_info(message=c.message, error_type="harness-error")
            elif c.failed:
                clearance = "nan" if not math.isfinite(c.clearance) else f"{c.clearance:.3f}"
                tc.add_failure_info(message=f"{c.outcome}: {c.message} (min clearance {clearance} m)",
                                    failure_type=c.outcome)
            cases.append(tc)
        suites.append(TestSuite(f"navsearch {report.seed_name} vs {report.subject} ({report.strategy}, "
                                f"seed {report.seed_value})", cases))
    atomic_write_text(path, to_xml_report_string(suites))
    return Path(path)
