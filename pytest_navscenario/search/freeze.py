"""Freezing search results: failures as ordinary scenario YAML, the search log, a JUnit file.

Layout under the regressions folder (``--navsearch-out`` / ini ``navsearch_out``)::

    <out>/<seed name>/<seed name>-<content hash>.yaml   one per distinct (shrunk) failure
    <out>/<seed name>/search-log.jsonl                   every search's simulated candidates, appended

A frozen file's name comes from ``scenario.content_hash()``, so the same failure found again
maps to the same file: it is not duplicated (the first file, and its provenance, are kept).
Failures whose shrunk layouts fail the same way (the same cause signature, fitness.py) are
frozen once: no near-copies.

``SearchRecorder`` writes while the search runs (``run_search(..., recorder=...)``): each
distinct failure the moment it is found (provenance ``status: found``), replaced by its final
form once shrunk (``shrunk``, or ``unshrunk`` when kept as found), and each simulated candidate as
one appended line of the log, after the file of the failure it found. So a search killed at any
moment (SIGKILL, a crash, a power cut after the last fsync) has on disk every failure it had
found. Every frozen file is written atomically, so no run ever leaves half a file; the log is
appended one whole line per write, and each search's lines carry its own id between a start
and an end record, so two searches writing into one folder keep both.
"""
from __future__ import annotations

import datetime as _dt
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Iterable

from ..core.files import atomic_write_text
from ..core.versions import mujoco_version
from ..scenario.model import Scenario, content_hash
from ..verdict.result import headline
from .report import Candidate, Failure, SearchReport
from .holding import Estimate
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
    estimate: Estimate | None = None   # how often it fails under the seed's randomness (holding.py)


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
        "mujoco_version": mujoco_version(),    # the release whose bits it records (core/versions.py)
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
    """Write ``scenario`` to ``path`` atomically, its mesh and heightfield files copied beside it."""
    from ..scenario.dump import save_scenario
    from ..scenario.modeline import ensure_project_schema

    path.parent.mkdir(parents=True, exist_ok=True)
    scenario = _with_body_copy(scenario, seed, path.parent)
    save_scenario(_with_mesh_copies(scenario, seed, path.parent), path)
    ensure_project_schema(path)     # the schema its modeline names, so an editor reads it at once


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat()


def frozen_scenario(report: SearchReport, failure: Failure, space: SearchSpace, *, date: str | None = None,
                    subject: str | None = None, root: str | Path | None = None) -> Scenario:
    """The failure in its current form (shrunk once it is) as a standalone scenario with its
    provenance (no ``search:`` block); ``status`` says which form (engine.Failure)."""
    cand = failure.shrunk
    seed = space.seed
    scenario = candidate_scenario(cand, space)
    provenance = candidate_provenance(report, cand, space, subject=subject, root=root)
    provenance.update({
        "status": failure.status,
        **failure.estimate.provenance(report.episode_seed or 0),
        "found_offsets": space.as_mapping(failure.found.offsets),
        "found_at_simulation": failure.found.sim,
        "shrink_simulations": failure.shrink_sims,
        "date": date or _now(),
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
        written.append(FrozenFile(path, new, failure.shrunk.outcome, failure.shrunk.clearance, failure.estimate))
    return written


def _with_mesh_copies(scenario: Scenario, seed: Scenario, folder: Path) -> Scenario:
    """The frozen scenario with its mesh files copied beside it (``meshes/<stem>-<hash><suffix>``,
    named by their content so equal files are stored once), and its heightfield files
    (``heightmaps/``): a file's path must stay inside the scenario's folder, and the frozen file
    lives elsewhere than its seed."""
    import hashlib
    import shutil

    from ..scenario.model import MeshObstacle

    grids = [el for el in scenario.terrain if el.kind == "heightfield"]
    if not any(isinstance(o, MeshObstacle) for o in scenario.obstacles) and not grids:
        return scenario
    base = Path(seed.source).parent if seed.source else Path.cwd()

    def copied(file: str, kind: str) -> str:
        src = base / file
        digest = hashlib.sha256(src.read_bytes()).hexdigest()[:12]
        rel = Path(kind) / f"{src.stem}-{digest}{src.suffix.lower()}"
        if not (folder / rel).exists():
            (folder / rel.parent).mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, folder / rel)
        return rel.as_posix()

    obstacles = tuple(replace(o, file=copied(o.file, "meshes")) if isinstance(o, MeshObstacle) else o
                      for o in scenario.obstacles)
    # heightfield files likewise (heightmaps/): the grid's digest is the file's content, so the
    # frozen scenario hashes as the one that failed
    terrain = tuple(replace(el, file=copied(el.file, "heightmaps")) if el.kind == "heightfield" else el
                    for el in scenario.terrain)
    return replace(scenario, obstacles=obstacles, terrain=terrain)


def new_search_id() -> str:
    """An id for one search's lines in a shared log: its start time (UTC) and a random part."""
    import secrets
    return _dt.datetime.now(_dt.timezone.utc).strftime("%Y%m%dT%H%M%SZ") + "-" + secrets.token_hex(3)


def _head(report: SearchReport, search_id: str) -> dict[str, Any]:
    return {"search": search_id, "seed": report.seed_name, "subject": report.subject,
            "strategy": report.strategy, "search_seed": report.seed_value, "budget": report.budget}


def start_record(report: SearchReport, search_id: str) -> dict[str, Any]:
    """The log's first line of a search: what was searched, with what, from when."""
    return {"record": "start", **_head(report, search_id), "date": _now(), "shrink_budget": report.shrink_budget,
            "nav_seed": report.episode_seed or 0, "params": list(report.params), "hold": report.hold,
            "randomness": list(report.randomness)}


def candidate_record(report: SearchReport, cand: Candidate, space: SearchSpace, search_id: str) -> dict[str, Any]:
    """One simulated candidate as a log line."""
    return {"record": "candidate", **_head(report, search_id), **cand.to_dict(space)}


def failure_record(report: SearchReport, failure: Failure, search_id: str, path: Path | None) -> dict[str, Any]:
    """A failure's change as a log line: found, confirmed, rejected, shrunk ... and its file."""
    est = failure.estimate
    return {"record": "failure", **_head(report, search_id), "found_at_simulation": failure.found.sim,
            "status": failure.status, "file": path.name if path is not None else None,
            "signature": list(failure.found.signature), "confirmation": est.decision,
            "confirmation_runs": est.runs, "confirmation_failures": est.failed,
            "failure_probability": None if est.probability is None else round(est.probability, 6)}


def end_record(report: SearchReport, search_id: str) -> dict[str, Any]:
    """The log's last line of a search: how the simulations were spent and why it ended."""
    return {"record": "end", **_head(report, search_id), "search_sims": report.sims_used,
            "confirm_sims": report.confirm_sims, "shrink_sims": report.shrink_sims,
            "shrink_budget": report.shrink_total, "failures": len(report.failures),
            "rejected": len(report.rejected), "unconfirmed": len(report.unconfirmed),
            "hold": report.hold, "randomness": list(report.randomness), "interrupted": report.interrupted,
            "stop_reason": report.stop_reason, "wall_time": round(report.wall_time, 3)}


def log_records(report: SearchReport, space: SearchSpace, search_id: str = "") -> list[dict[str, Any]]:
    """A finished search's whole log: its start record, every candidate, its end record."""
    search_id = search_id or new_search_id()
    return ([start_record(report, search_id)] + [candidate_record(report, c, space, search_id)
                                                 for c in report.candidates] + [end_record(report, search_id)])


def _line(record: dict[str, Any]) -> bytes:
    return (json.dumps(record, sort_keys=True, allow_nan=False) + "\n").encode("utf-8")


class _AppendLog:
    """A JSON Lines file opened for appending: each ``write`` is one ``os.write`` of whole lines
    (with O_APPEND, so two processes appending at once interleave whole lines, never bytes)."""

    def __init__(self, path: Path):
        import os

        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self.fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
        if os.fstat(self.fd).st_size and not _ends_with_newline(path):   # a line cut by a kill: end it
            os.write(self.fd, b"\n")

    def write(self, *records: dict[str, Any]) -> None:
        import os

        data = b"".join(_line(r) for r in records)
        while data:
            data = data[os.write(self.fd, data):]

    def close(self) -> None:
        import os

        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1


def _ends_with_newline(path: Path) -> bool:
    with open(path, "rb") as fh:
        fh.seek(-1, 2)
        return fh.read(1) == b"\n"


def write_search_log(report: SearchReport, space: SearchSpace, out_dir: str | Path, search_id: str = "") -> Path:
    """Append a finished search's log (start record, every simulated candidate of the search and
    shrink phases, end record) to ``out_dir/<seed>/search-log.jsonl``, beside the frozen files."""
    log = _AppendLog(Path(out_dir) / space.seed.name / LOG_NAME)
    try:
        log.write(*log_records(report, space, search_id))
    finally:
        log.close()
    return log.path


def read_search_log(path: str | Path) -> dict[str, list[dict[str, Any]]]:
    """The records of a search log, by search id in the order the searches started (each list
    from its start record to its end record; a search killed before its end has none). A line
    cut short by a kill, or that is no JSON object, is skipped."""
    searches: dict[str, list[dict[str, Any]]] = {}
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        try:
            record = json.loads(line)
        except (ValueError, RecursionError):
            continue
        if not isinstance(record, dict):      # not a record of ours
            continue
        searches.setdefault(str(record.get("search", "")), []).append(record)
    return searches


FROZEN_STATUSES = ("found", "confirmed", "shrunk", "unshrunk")   # a failure with a file (engine.Failure)


class SearchRecorder:
    """Writes a search's frozen failures and its log while it runs (``run_search(...,
    recorder=SearchRecorder(space, out))``; see the module docstring). Errors writing (a full disk,
    a folder without write permission) do not stop the search: the first is kept in ``error`` and
    nothing more is written. After ``finish``, ``files`` lists the frozen files (FrozenFile, one per
    distinct file, in the order of the failures) and ``log_path`` the log."""

    def __init__(self, space: SearchSpace, out_dir: str | Path, *, subject: str | None = None,
                 root: str | Path | None = None):
        self.space, self.subject, self.root = space, subject, root
        self.folder = Path(out_dir) / space.seed.name
        self.log_path: Path | None = None
        self.search_id = new_search_id()
        self.error = ""
        self.files: list[FrozenFile] = []
        self._log: _AppendLog | None = None
        self._mine: dict[int, Path] = {}          # failure key -> the file this search wrote for it
        self._held: dict[Path, int] = {}          # path -> the failure whose file it is (ours or kept)
        self._kept: dict[int, Path] = {}          # failure key -> a file of an earlier search it maps to
        self._causes: dict[tuple, int] = {}       # cause signature -> the failure frozen for it

    # -- Recorder ------------------------------------------------------------------------------
    def start(self, report: SearchReport) -> None:
        def go() -> None:
            self._log = _AppendLog(self.folder / LOG_NAME)
            self.log_path = self._log.path
            self._log.write(start_record(report, self.search_id))
        self._guard(go)

    def simulated(self, report: SearchReport, cand: Candidate) -> None:
        if self._log is not None:
            self._guard(lambda: self._log.write(candidate_record(report, cand, self.space, self.search_id)))

    def failure(self, report: SearchReport, failure: Failure) -> None:
        def go() -> None:
            path = self._sync(report, failure)
            if self._log is not None:
                self._log.write(failure_record(report, failure, self.search_id, path))
        self._guard(go)

    def finish(self, report: SearchReport) -> None:
        def go() -> None:
            for failure in report.failures:   # anything not yet on disk (after an error)
                self._sync(report, failure)
            if self._log is not None:
                self._log.write(end_record(report, self.search_id))
        self._guard(go)
        if self._log is not None:
            self._log.close()
        self.files = self._frozen(report)

    # -- files -----------------------------------------------------------------------------------
    def _guard(self, write) -> None:
        if self.error:
            return
        try:
            write()
        except Exception as exc:   # never lose the search: say what could not be written
            self.error = f"could not write under {self.folder}: {type(exc).__name__}: {exc}"

    def _sync(self, report: SearchReport, failure: Failure) -> Path | None:
        """Put ``failure`` on disk in its current form: write its file, unless another failure's
        file holds that layout or way of failing (frozen once) or an earlier search's file holds
        that layout (kept as it was); then remove the file this search wrote for an earlier form
        of it (the new form is on disk first, so a kill in between loses nothing). A failure that
        did not hold loses its file. Returns the failure's file now (None: none)."""
        key = failure.key
        old_mine, old_kept = self._mine.pop(key, None), self._kept.pop(key, None)
        path = None
        if failure.status in FROZEN_STATUSES:
            scenario = frozen_scenario(report, failure, self.space, subject=self.subject, root=self.root)
            path = self.folder / f"{scenario.name}.yaml"
            cause = tuple(failure.shrunk.signature)
            others = {self._held.get(path, key), self._causes.get(cause, key) if cause else key} - {key}
            if others:
                path = None                            # frozen once, as the other failure
            else:
                if path == old_mine or not path.exists():
                    save_standalone(scenario, self.space.seed, path)
                    self._mine[key] = path
                else:
                    self._kept[key] = path
                self._held[path] = key
                if cause:
                    self._causes.setdefault(cause, key)
        else:   # rejected, unconfirmed: its way of failing is free for another failure
            self._causes = {c: k for c, k in self._causes.items() if k != key}
        for old in (old_mine, old_kept):
            if old is not None and old != path:
                self._held.pop(old, None)
                if old == old_mine:
                    old.unlink(missing_ok=True)
        return path

    def _frozen(self, report: SearchReport) -> list[FrozenFile]:
        out, seen = [], set()
        for failure in report.failures:
            path = self._mine.get(failure.key) or self._kept.get(failure.key)
            if path is None or path in seen:
                continue
            seen.add(path)
            out.append(FrozenFile(path, failure.key in self._mine, failure.shrunk.outcome, failure.shrunk.clearance,
                                  failure.estimate))
        return out


def write_junit(items: Iterable[tuple[SearchReport, SearchSpace]], path: str | Path) -> Path:
    """The generated suite as JUnit XML: one test suite per search, one test case per simulated
    candidate of its search phase, failing where the planner failed."""
    from junit_xml import TestCase, TestSuite, to_xml_report_string

    suites = []
    for report, space in items:
        cases = []
        for c in report.candidates:
            if c.phase != "search" or c.run:   # a confirmation run repeats a case: not a case of its own
                continue
            tc = TestCase(name=f"{report.seed_name}[sim{c.sim:04d}-{c.scenario_hash}]",
                          classname=f"navsearch.{report.seed_name}", elapsed_sec=round(c.wall_time, 6),
                          stdout=json.dumps(space.as_mapping(c.offsets), sort_keys=True))
            if c.outcome == "harness-error":
                tc.add_error_info(message=c.message, error_type="harness-error")
            elif c.failed:
                clearance = "nan" if not math.isfinite(c.clearance) else f"{c.clearance:.3f}"
                tc.add_failure_info(message=f"{headline(c.outcome, c.message)} (min clearance {clearance} m)",
                                    failure_type=c.outcome)
            cases.append(tc)
        suites.append(TestSuite(f"navsearch {report.seed_name} vs {report.subject} ({report.strategy}, "
                                f"seed {report.seed_value})", cases))
    atomic_write_text(path, to_xml_report_string(suites))
    return Path(path)


def _with_body_copy(scenario: Scenario, seed: Scenario, folder: Path) -> Scenario:
    """The frozen scenario with its MJCF robot copied beside it (``bodies/<stem>-<hash>/``, named
    by the robot file's content digest, with the files it names in the same layout), as meshes are:
    the frozen file lives elsewhere than its seed, and the robot must lie in its folder."""
    import shutil

    from ..scenario.mjcf_files import mjcf_files

    body = scenario.robot.body
    if body.kind != "mjcf":
        return scenario
    base = (Path(seed.source).parent if seed.source else Path.cwd()) / body.file
    src_dir = base.resolve().parent
    rel_dir = Path("bodies") / f"{base.stem}-{body.digest or 'robot'}"
    for file in mjcf_files(base):
        target = folder / rel_dir / file.relative_to(src_dir)
        if not target.exists():
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(file, target)
    moved = (rel_dir / base.name).as_posix()
    return replace(scenario, robot=replace(scenario.robot, body=replace(body, file=moved)))
