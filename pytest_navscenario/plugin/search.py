"""pytest hooks of the failure search: ``pytest --navsearch boxes1 --budget 100``.

With ``--navsearch`` the session runs one search item per seed name instead of the scenario
items. ``-n N`` does not start xdist workers here: this process runs the searches one after the
other, each evaluating its generations on N local worker processes (plugin/parallel.py), so one
search uses every core with the results of a serial run; ``--nav-ray`` evaluates them as Ray
tasks. The search result goes on the call report as ``report.navsearch`` (plain data), from
which this process writes the frozen failures, the search log, the JUnit file and the suite
folder (also after Ctrl-C: what was found is kept). Progress is shown live through the terminal
reporter with capture suspended (as live logging does): rewritten in place on a terminal, a
plain line every tenth of the budget (and on each new failure) in a CI log.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from .options import ini_type, ini_value

DEFAULT_BUDGET = 100
DEFAULT_SHRINK_BUDGET = "25%"   # = search.engine.DEFAULT_SHRINK_BUDGET
DEFAULT_OUT = "scenarios/regressions"
DEFAULT_STUCK_AFTER = 15.0   # = search.engine.DEFAULT_STUCK_AFTER
DEFAULT_HOLD = 0.9           # = search.holding.DEFAULT_HOLD
STRATEGY_NAMES = ("evolve", "random", "hillclimb")   # = search.engine.STRATEGIES (not imported: plugin load stays light)
OLD_OUT_INI = "nav_regressions_dir"     # the old name of the ini option navsearch_out, still read

# (option, dest / ini name, metavar, help)
OPTIONS = (
    ("--navsearch", "navsearch", "NAME",
     "search for failures around the seed scenario NAME (a file NAME.yaml under the "
     "nav_scenario_paths folders, or a path to a scenario file); repeatable. Runs searches "
     "instead of the scenario items."),
    ("--budget", "navsearch_budget", "N",
     f"simulations per search (valid candidates only; default {DEFAULT_BUDGET})."),
    ("--navsearch-seed", "navsearch_seed", "N",
     "random seed of the search (integer >= 0, default 0); the same seed, subject and budget "
     "repeat a search exactly."),
    ("--navsearch-strategy", "navsearch_strategy", "{" + ",".join(STRATEGY_NAMES) + "}",
     "evolve (default: quality-diversity search drawn by Hypothesis; looks for new ways of "
     "failing), random (uniform sampling over the same space, a baseline) or hillclimb (the "
     "Surrealist baseline: adaptive-step hill-climb on one obstacle at a time, minimising "
     "clearance)."),
    ("--navsearch-shrink-budget", "navsearch_shrink_budget", "SHARE",
     f"simulations for shrinking the distinct failures toward the seed, on top of the budget: "
     f"a share of the budget (default {DEFAULT_SHRINK_BUDGET}), shared out before shrinking "
     f"starts, most severe and earliest failure first (failures it does not reach are kept as "
     f"found); 0 = keep every failure as found; a whole number N = at most N simulations for "
     f"each failure (the old form)."),
    ("--navsearch-hold", "navsearch_hold", "P",
     f"a failure counts (is distinct, shrunk and frozen) only when it holds: when repeats under fresh "
     f"noise seeds (confirmation runs, simulations of the budget) decide, by a sequential test, that "
     f"it fails with probability at least P rather than at most the P whose odds are 9 times smaller "
     f"(default {DEFAULT_HOLD}: 0.9 against 0.5); 0 = every failure counts after one run. A seed "
     f"without randomness (no sensor noise, drift or perturbation) needs no confirmation."),
    ("--navsearch-stuck-after", "navsearch_stuck_after", "SECONDS",
     f"end a search episode early, as a timeout, when the robot has covered no new ground for "
     f"this long (default {DEFAULT_STUCK_AFTER:g}; 0 = run every episode to its timeout)."),
    ("--navsearch-out", "navsearch_out", "DIR",
     f"folder for frozen failures, one subfolder per seed, plus each search's log "
     f"(default {DEFAULT_OUT}; the ini option's old name {OLD_OUT_INI} is still read)."),
    ("--navsearch-junit", "navsearch_junit", "PATH",
     "also write the generated suite (every simulated candidate) as a JUnit XML file."),
    ("--navsearch-suite", "navsearch_suite", "DIR",
     "also keep the generated suite as scenario files: every candidate simulated in the search "
     "phase (failing or not; not the shrink phase) as DIR/<seed>/<seed>-sim<N>-<hash>.yaml, "
     "family = seed, replacing that seed's earlier suite there; written also when the run is cut "
     "short. Re-run it against any planner: pytest DIR --nav-subject=..."),
)


_INT_OPTIONS = ("navsearch_budget", "navsearch_seed")   # ini type int


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("navsearch", "navigation failure search (pytest-navscenario)")
    for opt, dest, metavar, text in OPTIONS:
        kwargs: dict[str, Any] = {"action": "append"} if dest == "navsearch" else {}
        group.addoption(opt, dest=dest, default=None, metavar=metavar,   # argparse %-formats help: 25% -> 25%%
                        help=f"{text} [ini: {dest}]".replace("%", "%%"), **kwargs)
        kind = ("args" if dest == "navsearch" else ini_type("int") if dest in _INT_OPTIONS
                else ini_type("float") if dest in ("navsearch_stuck_after", "navsearch_hold") else "string")
        parser.addini(dest, text, type=kind,
                      default=[] if dest == "navsearch" else "")

    parser.addini(OLD_OUT_INI, "old name of navsearch_out, still read (navsearch_out wins when both "
                  "are set to the same folder; different folders are a usage error)", default="")


_CONFIGS: list[pytest.Config] = []   # the running session's config (a stack: pytester nests runs)


def pytest_configure(config: pytest.Config) -> None:
    _CONFIGS.append(config)


def pytest_unconfigure(config: pytest.Config) -> None:
    if config in _CONFIGS:
        _CONFIGS.remove(config)


# -- settings ------------------------------------------------------------------------------------
@dataclass
class SearchSettings:
    names: list[str]
    budget: int
    seed: int
    strategy: str
    shrink_budget: str
    out: Path
    junit: Path | None
    stuck_after: float | None = DEFAULT_STUCK_AFTER
    suite: Path | None = None
    hold: float = DEFAULT_HOLD


@dataclass
class Job:
    name: str
    path: Path
    seed: Any          # Scenario
    space: Any         # SearchSpace


@dataclass
class SearchState:
    settings: SearchSettings
    jobs: dict[str, Job]
    is_worker: bool
    done: list[dict[str, Any]] = field(default_factory=list)   # controller: summary entries
    junit_items: list[Any] = field(default_factory=list)
    recorders: dict[str, Any] = field(default_factory=dict)   # seed name -> its search's SearchRecorder
    html_error: str = ""


STATE_KEY = pytest.StashKey[SearchState]()


def _raw(config: pytest.Config, dest: str) -> tuple[Any, str, Path]:
    cli = config.getoption(dest)
    if cli is not None:
        return cli, f"--{dest.replace('_', '-')}" if dest != "navsearch_budget" else "--budget", \
            Path(config.invocation_params.dir)
    return ini_value(config, dest), f"ini option {dest}", Path(config.rootpath)


def _int(config: pytest.Config, dest: str, default: int, minimum: int, what: str) -> int:
    raw, where, _ = _raw(config, dest)
    if raw in ("", None):
        return default
    try:
        value = int(str(raw).strip())
    except ValueError:
        raise pytest.UsageError(f"{where}: {what} must be a whole number, got {raw!r}") from None
    if value < minimum:
        raise pytest.UsageError(f"{where}: {what} must be >= {minimum}, got {value}"
                                + (" (e.g. --budget 100)" if dest == "navsearch_budget" else ""))
    return value


def _out_raw(config: pytest.Config) -> tuple[Any, str, Path]:
    """--navsearch-out, else the ini option navsearch_out, else its old name nav_regressions_dir;
    the two ini names set to different folders is a usage error."""
    raw, where, base = _raw(config, "navsearch_out")
    if config.getoption("navsearch_out") is not None:
        return raw, where, base
    old = str(config.getini(OLD_OUT_INI)).strip()
    if old and str(raw).strip() and str(raw).strip() != old:
        raise pytest.UsageError(f"ini options navsearch_out = {str(raw).strip()!r} and {OLD_OUT_INI} = "
                                f"{old!r} disagree; {OLD_OUT_INI} is the old name of navsearch_out: "
                                f"keep only navsearch_out")
    if old and not str(raw).strip():
        return old, f"ini option {OLD_OUT_INI}", base
    return raw, where, base


def read_search_settings(config: pytest.Config) -> SearchSettings:
    """Every search option, checked (in every session, so a bad ini value is reported at once;
    the search package is imported only for a value that needs it)."""
    raw, _, _ = _raw(config, "navsearch")
    names = list(dict.fromkeys(n.strip() for n in (raw or []) if n and n.strip()))
    budget = _int(config, "navsearch_budget", DEFAULT_BUDGET, 1, "the budget (simulations per search)")
    seed = _int(config, "navsearch_seed", 0, 0, "the search seed")
    raw, where, _ = _raw(config, "navsearch_strategy")
    strategy = (str(raw).strip() or "evolve").lower()
    if strategy not in STRATEGY_NAMES:
        raise pytest.UsageError(f"{where}: unknown strategy {raw!r}; use one of {', '.join(STRATEGY_NAMES)}")
    shrink = _shrink_budget(config)
    raw, where, base = _out_raw(config)
    raw = str(raw).strip() or DEFAULT_OUT
    out = Path(os.path.expanduser(raw))
    out = out if out.is_absolute() else base / out
    if out.exists() and not out.is_dir():
        raise pytest.UsageError(f"{where}: {raw!r} exists and is not a folder; give a folder for the frozen failures")
    raw, where, base = _raw(config, "navsearch_junit")
    raw = str(raw or "").strip()
    junit = None
    if raw:
        junit = Path(os.path.expanduser(raw))
        junit = junit if junit.is_absolute() else base / junit
        if junit.is_dir():
            raise pytest.UsageError(f"{where}: {raw!r} is a folder; give a file name such as navsearch.xml")
    return SearchSettings(names, budget, seed, strategy, shrink, out, junit, _stuck_after(config),
                          _suite_dir(config, out), _hold(config))


def _hold(config: pytest.Config) -> float:
    """--navsearch-hold / navsearch_hold: a failure probability from 0 (off) to below 1."""
    raw, where, _ = _raw(config, "navsearch_hold")
    if raw in ("", None):
        return DEFAULT_HOLD
    try:
        value = float(str(raw).strip())
    except ValueError:
        value = math.nan
    if not 0.0 <= value < 1.0:
        raise pytest.UsageError(f"{where}: the hold threshold is a failure probability from 0 to below 1, "
                                f"got {raw!r} (e.g. 0.9, the default; 0 counts every failure after one run)")
    return value


def _suite_dir(config: pytest.Config, out: Path) -> Path | None:
    """--navsearch-suite DIR: a folder (made if missing), not the frozen failures' folder."""
    raw, where, base = _raw(config, "navsearch_suite")
    raw = str(raw or "").strip()
    if not raw:
        return None
    suite = Path(os.path.expanduser(raw))
    suite = suite if suite.is_absolute() else base / suite
    if suite.exists() and not suite.is_dir():
        raise pytest.UsageError(f"{where}: {raw!r} exists and is not a folder; give a folder for the "
                                f"generated suite, e.g. suites/dwa")
    if suite.resolve() == out.resolve():
        raise pytest.UsageError(f"{where}: {raw!r} is also the folder of the frozen failures "
                                f"(--navsearch-out); give the suite a folder of its own, e.g. suites/dwa, "
                                f"so that re-running it does not run the frozen failures too")
    return suite


def _shrink_budget(config: pytest.Config) -> str:
    """--navsearch-shrink-budget / navsearch_shrink_budget, checked: "25%", "0" or "40"."""
    cli = config.getoption("navsearch_shrink_budget")
    if cli is not None:
        raw, where = cli, "--navsearch-shrink-budget"
    else:
        raw = ini_value(config, "navsearch_shrink_budget",
                        'a share of the budget such as "25%", or a whole number such as "40" (quoted in TOML)')
        where = "ini option navsearch_shrink_budget"
    if raw in ("", None):
        return DEFAULT_SHRINK_BUDGET
    from ..search.engine import ShrinkBudget
    try:
        ShrinkBudget.parse(raw)
    except ValueError as exc:
        raise pytest.UsageError(f"{where}: {exc}") from None
    return str(raw).strip()


def _stuck_after(config: pytest.Config) -> float | None:
    raw, where, _ = _raw(config, "navsearch_stuck_after")
    if raw in ("", None):
        return DEFAULT_STUCK_AFTER
    try:
        value = float(str(raw).strip())
    except ValueError:
        raise pytest.UsageError(f"{where}: the stuck time must be a number of seconds, got {raw!r} "
                                f"(e.g. 10; 0 turns the early stop off)") from None
    if not math.isfinite(value) or value < 0:
        raise pytest.UsageError(f"{where}: the stuck time must be >= 0 seconds, got {raw!r} "
                                f"(0 turns the early stop off)")
    return value or None


def _scenario_files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.glob("*.y*ml") if p.suffix in (".yaml", ".yml"))


def find_seed(name: str, scenario_paths: tuple[Path, ...], rootdir: Path) -> Path:
    """The seed file for ``name``: NAME.yaml / NAME.yml in a scenario folder, or a file path."""
    as_path = Path(os.path.expanduser(name))
    for candidate in (as_path, rootdir / as_path):
        if candidate.suffix in (".yaml", ".yml") and candidate.is_file():
            return candidate
    for folder in scenario_paths:
        for ext in (".yaml", ".yml"):
            if (folder / f"{name}{ext}").is_file():
                return folder / f"{name}{ext}"
    available = sorted({p.stem for folder in scenario_paths if folder.is_dir() for p in _scenario_files(folder)})
    where = ", ".join(str(p) for p in scenario_paths) or "(none configured)"
    raise pytest.UsageError(
        f"--navsearch {name}: no seed scenario named {name!r} in {where}. "
        + (f"Available: {', '.join(available)}. " if available else "No scenario files there. ")
        + "Give one of these names, a path to a scenario file, or add the folder to the ini option "
          "nav_scenario_paths.")


def _make_job(name: str, path: Path, sensor_model: Any = None, requirements: Any = None) -> Job:
    from ..core.errors import NavScenarioError
    from ..scenario.loader import load_scenario
    from ..scenario.requirement_reading import with_shared
    from ..scenario.sensor_model import with_sensor_model
    from ..search.space import SearchSpace, invalid_reason

    try:
        seed = with_sensor_model(load_scenario(path), sensor_model)   # --nav-sensor-model
        seed = with_shared(seed, requirements)                         # --nav-requirements
        if not seed.name:
            import dataclasses
            seed = dataclasses.replace(seed, name=path.stem)
        space = SearchSpace(seed)
    except NavScenarioError as exc:
        raise pytest.UsageError(f"--navsearch {name}: {exc}") from None
    reason = invalid_reason(seed)
    if reason is not None:
        raise pytest.UsageError(f"--navsearch {name}: the seed {path} is itself not a valid test "
                                f"({reason}): fix the seed so the robot can reach the goal")
    if not space.params:
        raise pytest.UsageError(f"--navsearch {name}: the search space of {path} is empty (every part "
                                f"is frozen or has bounds [0, 0]); widen its search: bounds")
    return Job(name, path, seed, space)


def pytest_sessionstart(session: pytest.Session) -> None:
    """Check the search options and seeds before anything runs (after the core plugin)."""
    config = session.config
    settings = read_search_settings(config)
    if not settings.names:
        return
    from .state import get_state

    core = get_state(config)
    jobs = {}
    for name in settings.names:
        path = find_seed(name, core.settings.scenario_paths, Path(config.rootpath))
        jobs[name] = _make_job(name, path, core.settings.sensor_model, core.settings.requirements)
    config.stash[STATE_KEY] = SearchState(settings, jobs, hasattr(config, "workerinput"))


# -- items ------------------------------------------------------------------------------------------
@pytest.hookimpl(tryfirst=True)
def pytest_collection(session: pytest.Session) -> Any:
    """With --navsearch: the session's items are the searches (no scenario collection)."""
    state = session.config.stash.get(STATE_KEY, None)
    if state is None:
        return None
    config = session.config
    items = [NavSearchItem.from_parent(session, name=f"navsearch[{name}]", nodeid=f"navsearch[{name}]",
                                       job_name=name) for name in state.jobs]
    config.hook.pytest_collectreport(report=pytest.CollectReport(session.nodeid, "passed", None, items))
    config.hook.pytest_collection_modifyitems(session=session, config=config, items=items)
    session.items = items
    session.testscollected = len(items)
    config.hook.pytest_collection_finish(session=session)
    return True


class NavSearchItem(pytest.Item):
    """One search around one seed against the session's subject. Passes when the search ran;
    what it found is in the summary and the files written."""

    def __init__(self, *, job_name: str, **kwargs: Any):
        super().__init__(**kwargs)
        self.job_name = job_name
        self.navsearch_payload: dict[str, Any] | None = None

    def runtest(self) -> None:
        from ..search.engine import run_search
        from .parallel import search_subject_and_evaluator
        from .state import get_state

        core = get_state(self.config)
        state = self.config.stash[STATE_KEY]
        s, job = state.settings, state.jobs[self.job_name]
        subject = core.subject.spec or core.subject.label
        factory, evaluator = search_subject_and_evaluator(self.config)   # -n N / --nav-ray: workers
        batch = core.settings.batch
        if evaluator is None and batch > 1:   # --nav-batch: generations and shrinks in batches
            from ..search.batched import batch_evaluator
            evaluator = batch_evaluator()
        recorder = None
        if not state.is_worker:   # this process writes: each failure and log line as found
            from ..search.freeze import SearchRecorder
            recorder = state.recorders[job.seed.name] = SearchRecorder(job.space, s.out, root=self.config.rootpath)
        report = run_search(job.seed, factory, budget=s.budget, seed_value=s.seed,
                            strategy=s.strategy, shrink_budget=s.shrink_budget, space=job.space,
                            subject=subject, episode_seed=core.settings.seed, stuck_after=s.stuck_after,
                            progress=None if state.is_worker else _Progress(self.config, job.name, s.budget),
                            evaluator=evaluator, recorder=recorder, hold=s.hold, batch=batch,
                            engine=core.settings.batch_engine)
        self.navsearch_payload = report_to_payload(report)
        if report.interrupted and report.stop_reason.startswith("interrupted"):
            from ..core.interrupts import first_signal
            self.session.shouldstop = (f"navsearch {job.name} was cut short by {first_signal() or 'Ctrl-C'} after "
                                       f"{report.sims_used} of {report.budget} simulations; "
                                       f"failures found so far were kept")

    def reportinfo(self) -> tuple[Path, int | None, str]:
        job = self.config.stash[STATE_KEY].jobs[self.job_name]
        return job.path, None, f"navsearch {self.job_name}"

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> Any:
        from ..core.errors import NavScenarioError
        if isinstance(excinfo.value, NavScenarioError):
            return f"navsearch {self.job_name}: {excinfo.value}"
        return super().repr_failure(excinfo)


class _Progress:
    """Live progress in a serial run, written through the terminal reporter with pytest's
    capture suspended (else it would be swallowed): one line rewritten in place on a terminal,
    else a plain line per tenth of the budget and on each new distinct failure (a CI log)."""

    def __init__(self, config: pytest.Config, name: str, budget: int):
        self.tr = config.pluginmanager.get_plugin("terminalreporter")
        self.capman = config.pluginmanager.get_plugin("capturemanager")
        self.name, self.budget = name, budget
        self.step = max(1, budget // 10)
        self.last_failures = 0
        self.last_sims = -1
        self.tty = bool(self.tr is not None and getattr(self.tr, "isatty", False))
        self.started = False

    def line(self, report: Any) -> str:
        n, nf = report.sims_used, len(report.failures)
        out = f"navsearch {self.name}: {n}/{self.budget} sims, {nf} distinct failure(s)"
        if report.under_test or report.rejected:
            out += f" ({report.under_test} being confirmed, {len(report.rejected)} did not hold)"
        if math.isfinite(report.best_clearance):
            out += f", lowest clearance so far {report.best_clearance:.3f} m"
        rob = report.best_robustness
        if math.isfinite(rob) and not nf:
            out += f", closest to failing {rob:.2f}"
        if report.shrink_sims:
            out += f", shrinking ({report.shrink_sims} sims)"
        return out

    def __call__(self, report: Any) -> None:
        if self.tr is None:
            return
        n, nf = report.sims_used, len(report.failures)
        due = self.tty or nf != self.last_failures or (n % self.step == 0 and n != self.last_sims
                                                        and not report.shrink_sims)
        self.last_failures, self.last_sims = nf, n
        if not due:
            return
        with self._uncaptured():
            if self.tty:
                if not self.started:
                    self.tr.write_line("")
                    self.started = True
                self.tr.rewrite(self.line(report), erase=True)
            else:
                self.tr.ensure_newline()
                self.tr.write_line(self.line(report))
            if hasattr(self.tr, "flush"):
                self.tr.flush()

    def _uncaptured(self) -> Any:
        import contextlib
        if self.capman is None:
            return contextlib.nullcontext()
        return self.capman.global_and_fixture_disabled()


# -- data across processes -------------------------------------------------------------------------
def report_to_payload(report: Any) -> dict[str, Any]:
    """SearchReport as plain data (crosses from xdist workers); offsets kept as exact floats."""
    def cand(c):
        return {"sim": c.sim, "phase": c.phase, "origin": c.origin, "offsets": list(c.offsets),
                "outcome": c.outcome, "clearance": c.clearance if math.isfinite(c.clearance) else None,
                "culprit": c.culprit, "message": c.message,
                "metrics": {k: (v if not isinstance(v, float) or math.isfinite(v) else None)
                            for k, v in c.metrics.items()},
                "scenario_hash": c.scenario_hash, "wall_time": c.wall_time,
                "robustness": c.robustness if math.isfinite(c.robustness) else None,
                "signature": list(c.signature), "progress": c.progress, "run": c.run}
    index = {id(c): i for i, c in enumerate(report.candidates)}

    def failure(f):
        return {"found": index[id(f.found)], "shrunk": index[id(f.shrunk)], "shrink_sims": f.shrink_sims,
                "note": f.note, "status": f.status, "estimate": f.estimate.to_data()}
    return {
        "seed_name": report.seed_name, "seed_source": report.seed_source, "subject": report.subject,
        "subject_version": report.subject_version, "strategy": report.strategy,
        "seed_value": report.seed_value, "budget": report.budget, "shrink_budget": report.shrink_budget,
        "params": report.params, "sims_used": report.sims_used, "shrink_sims": report.shrink_sims,
        "shrink_total": report.shrink_total,
        "discarded": dict(report.discarded), "discard_log": [list(d) for d in report.discard_log],
        "skipped": report.skipped, "interrupted": report.interrupted,
        "stop_reason": report.stop_reason, "wall_time": report.wall_time,
        "episode_seed": report.episode_seed, "first_failure": report.first_failure,
        "batching": report.batching,
        "candidates": [cand(c) for c in report.candidates],
        "failures": [failure(f) for f in report.failures],
        "rejected": [failure(f) for f in report.rejected],
        "unconfirmed": [failure(f) for f in report.unconfirmed],
        "hold": report.hold, "randomness": list(report.randomness), "confirm_sims": report.confirm_sims,
    }


def payload_to_report(data: dict[str, Any], space: Any) -> Any:
    """Inverse of report_to_payload; candidate scenarios are rebuilt from the seed + offsets."""
    from ..search.engine import Candidate, Failure, SearchReport
    from ..search.holding import Estimate

    cands = []
    for c in data["candidates"]:
        offsets = tuple(float(v) for v in c["offsets"])
        metrics = {k: (math.nan if v is None else v) for k, v in c["metrics"].items()}
        cands.append(Candidate(c["sim"], c["phase"], c["origin"], offsets, c["outcome"],
                               math.nan if c["clearance"] is None else c["clearance"], c["culprit"],
                               c["message"], metrics, c["scenario_hash"], c["wall_time"], space.apply(offsets),
                               math.inf if c.get("robustness") is None else c["robustness"],
                               tuple(c.get("signature", ())), c.get("progress", 0.0), run=c.get("run", 0)))
    fields = {k: data[k] for k in ("seed_name", "seed_source", "subject", "subject_version", "strategy",
                                   "seed_value", "budget", "shrink_budget", "params", "sims_used",
                                   "shrink_sims", "discarded", "interrupted", "stop_reason", "wall_time",
                                   "episode_seed")}
    report = SearchReport(**fields)
    report.skipped = data.get("skipped", 0)
    report.discard_log = [(int(n), str(k)) for n, k in data.get("discard_log", [])]
    report.first_failure = data.get("first_failure", 0)
    report.shrink_total = data.get("shrink_total", 0)
    report.batching = data.get("batching", "")
    report.candidates = cands
    report.hold, report.randomness = data.get("hold", 0.0), tuple(data.get("randomness", ()))
    report.confirm_sims = data.get("confirm_sims", 0)

    def failures(key: str) -> list[Any]:
        return [Failure(cands[f["found"]], cands[f["shrunk"]], f["shrink_sims"], f["note"],
                        f.get("status", "found"), Estimate.from_data(f.get("estimate")))
                for f in data.get(key, [])]
    report.failures, report.rejected, report.unconfirmed = failures("failures"), failures("rejected"), \
        failures("unconfirmed")
    return report


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Any:
    report = yield
    payload = getattr(item, "navsearch_payload", None)
    if call.when == "call" and payload is not None:
        report.navsearch = payload  # type: ignore[attr-defined]
        item.navsearch_payload = None  # type: ignore[attr-defined]
    return report


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    """Controller: a finished search's summary entry, its generated suite and the JUnit file (its
    frozen failures and log were written while it ran, by its SearchRecorder). An interrupt that
    comes while this writes waits until it is done."""
    payload = getattr(report, "navsearch", None)
    if payload is None or report.when != "call":
        return
    config = _CONFIGS[-1] if _CONFIGS else None
    if config is None or hasattr(config, "workerinput"):
        return
    state = config.stash.get(STATE_KEY, None)
    if state is None:
        return
    from ..core.interrupts import deferred

    with deferred():
        _finish_search(payload, state, config)


def _finish_search(payload: dict[str, Any], state: SearchState, config: pytest.Config) -> None:
    from ..search.freeze import freeze_failures, write_search_log

    job = next(j for j in state.jobs.values() if j.seed.name == payload["seed_name"])
    search = payload_to_report(payload, job.space)
    entry: dict[str, Any] = {"report": search, "job": job, "files": [], "log": None, "error": "", "suite": None}
    recorder = state.recorders.pop(job.seed.name, None)
    if recorder is not None:
        entry["files"], entry["log"] = recorder.files, recorder.log_path
        entry["error"] = recorder.error
    else:   # the search ran elsewhere (an xdist worker): write what it found now
        try:
            entry["files"] = freeze_failures(search, job.space, state.settings.out, root=config.rootpath)
            entry["log"] = write_search_log(search, job.space, state.settings.out)
        except Exception as exc:  # never lose the summary: say what could not be written
            entry["error"] = (f"could not write the frozen failures under {state.settings.out}: "
                              f"{type(exc).__name__}: {exc}")
    if state.settings.suite is not None:
        _write_suite(entry, state.settings.suite, config)
    from .search_report import failure_rows, wanted
    if wanted(config)[0]:   # --nav-plots / --nav-html: a picture of each frozen failure
        entry["rows"] = failure_rows(config, entry)
    state.done.append(entry)
    state.junit_items.append((search, job.space))
    if state.settings.junit is not None:   # after every search: an interrupted session keeps it too
        from ..search.freeze import write_junit
        try:
            write_junit(state.junit_items, state.settings.junit)
        except Exception as exc:
            entry["error"] += ("; " if entry["error"] else "") + (
                f"could not write the JUnit file {state.settings.junit}: {type(exc).__name__}: {exc}")


def _write_suite(entry: dict[str, Any], folder: Path, config: pytest.Config) -> None:
    from ..search.suite import write_suite

    try:
        entry["suite"] = write_suite(entry["report"], entry["job"].space, folder, root=config.rootpath)
    except Exception as exc:  # never lose the summary: say what could not be written
        entry["error"] += ("; " if entry["error"] else "") + (
            f"could not write the generated suite under {folder}: {type(exc).__name__}: {exc}")


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    state = session.config.stash.get(STATE_KEY, None)
    if state is None or state.is_worker:
        return
    from .search_report import write_html
    try:
        write_html(session.config, state.done)
    except Exception as exc:  # never lose the summary: say what could not be written
        state.html_error = f"could not write the search's HTML report: {type(exc).__name__}: {exc}"


def pytest_terminal_summary(terminalreporter: Any, exitstatus: int, config: pytest.Config) -> None:
    state = config.stash.get(STATE_KEY, None)
    if state is None or state.is_worker:
        return
    tr = terminalreporter
    tr.write_sep("=", "navsearch summary")
    ran = {e["job"].name for e in state.done}
    for entry in state.done:
        for line in format_entry(entry, config):
            tr.write_line(line)
    for name in state.jobs:
        if name not in ran:
            tr.write_line(f"{name}: no result (the search item failed, see above, or the session "
                          f"stopped before it)")
    if state.settings.junit is not None and state.junit_items:
        tr.write_line(f"JUnit file of the generated suite: {state.settings.junit}")
    if state.html_error:
        tr.write_line(f"ERROR {state.html_error}", red=True)
    from ..core.interrupts import held
    if held():
        tr.write_line("a second interrupt came while what was found was being saved: it was held until "
                      "everything was written (a third one stops at once)")


def _rel(config: pytest.Config, path: Path) -> str:
    try:
        return Path(path).resolve().relative_to(Path(config.rootpath).resolve()).as_posix()
    except ValueError:
        return str(path)


def _one_way_everywhere(r: Any) -> str:
    """"outcome: message" when every simulation of the search phase (two at least) was a subject or
    harness error with the same message (its tick aside): a broken subject, not the layouts; else ""."""
    import re

    ran = [c for c in r.candidates if c.phase == "search"]
    if len(ran) < 2 or any(c.outcome not in ("subject-error", "harness-error") for c in ran):
        return ""
    said = {(c.outcome, re.sub(r"^planner error at tick \d+ \(t=[^)]*\): ", "", c.message)) for c in ran}
    return "" if len(said) != 1 else "{}: {}".format(*said.pop())


def _holding_lines(r: Any) -> list[str]:
    """What the confirmation of failures under the seed's randomness did (search/holding.py)."""
    if not r.randomness:
        return ["  the seed has no randomness (no sensor noise, drift or perturbation): one run decides each "
                "failure; search under noise with --nav-sensor-model realistic"] if r.failures else []
    noise = ", ".join(r.randomness)
    if not r.hold:
        return [f"  confirmation off (--navsearch-hold 0): each failure counted after one run, though {noise} "
                f"may make it pass the next time"]
    out = [f"  failures that hold (fail with probability >= {r.hold:g} under {noise}, decided by a "
           f"sequential test): {len(r.failures)}; {r.confirm_sims} confirmation run(s)"
           + (f", {r.confirm_sims / len(r.failures):.1f} per failure that holds" if r.failures else "")]
    if r.rejected:
        out.append(f"  {len(r.rejected)} failure(s) did not hold (failed once, then passed under fresh noise: "
                   f"knife-edges, not frozen)")
    if r.unconfirmed:
        cut = r.interrupted and any(f.status == "found" for f in r.unconfirmed)
        out.append(f"  {len(r.unconfirmed)} failure(s) still under test when the search "
                   + ("was cut short (frozen as found, unconfirmed)" if cut else
                      "ran out of budget (not frozen; a larger --budget confirms them)"))
    return out


def format_entry(entry: dict[str, Any], config: pytest.Config) -> list[str]:
    from .search_report import lowest_clearance_text

    r = entry["report"]
    by = ", ".join(f"{k} {v}" for k, v in sorted(r.failures_by_outcome().items())) or "none"
    disc = ", ".join(f"{k} {v}" for k, v in sorted(r.discarded.items()))
    version = f" {r.subject_version}" if r.subject_version else ""
    lines = [f"{r.seed_name} vs {r.subject}{version} ({r.strategy}, search seed {r.seed_value}): "
             f"{r.sims_used}/{r.budget} sims, {r.discarded_total} discarded" + (f" ({disc})" if disc else "")
             + f", {len(r.failures)} distinct failure(s) ({by}), " + lowest_clearance_text(r)
             + (f", first at sim {r.first_failure}" if r.first_failure else "")
             + f", {r.sims_used} sims searching" + (f" ({r.confirm_sims} of them confirming)" if r.confirm_sims else "")
             + f" + {r.shrink_sims} shrinking"
             + (f" (shrink budget {r.shrink_total})" if r.shrink_total else "") + f", {r.wall_time:.1f} s"]
    lines += _holding_lines(r)
    unshrunk = sum(1 for f in r.failures if f.note.startswith("not shrunk: the shrink budget"))
    if unshrunk:
        lines.append(f"  {unshrunk} of {len(r.failures)} failure(s) frozen as found: the shrink budget "
                     f"({r.shrink_total} simulations) went to the most severe and earliest ones (raise "
                     f"--navsearch-shrink-budget, e.g. 50%, to shrink more)")
    same = _one_way_everywhere(r)
    if same:
        lines.append(f"  every one of the {r.sims_used} simulations ended the same way: {same}; the subject fails "
                     f"whatever the layout: fix it (navscenario check-planner SPEC) before searching")
    if r.batching:
        lines.append(f"  batches (--nav-batch): {r.batching}")
    if r.skipped:
        lines.append(f"  {r.skipped} candidate(s) repeating a simulated one or next to a known failure were "
                     f"redrawn without simulating them")
    if r.interrupted:
        lines.append(f"  CUT SHORT: {r.stop_reason or 'interrupted'}; the failures found so far are kept "
                     f"(unshrunk ones are frozen as found)")
    elif r.stop_reason:
        lines.append(f"  stopped early: {r.stop_reason}")
    for f in entry["files"]:
        state = "new " if f.new else "kept"
        c = f.clearance
        held = f", {f.estimate.describe()}" if f.estimate is not None and f.estimate.runs else ""
        lines.append(f"  {state} {_rel(config, f.path)}  {f.outcome}, clearance "
                     + (f"{c:.3f} m" if math.isfinite(c) else "n/a") + held + ("" if f.new else " (already frozen)"))
    pictures = [row.picture for row in entry.get("rows") or [] if row.picture]
    if pictures:
        folders = sorted({str(Path(p).parent) for p in pictures})
        lines.append(f"  pictures of {len(pictures)} failure(s) in {folders[0] if len(folders) == 1 else ', '.join(folders)}/ "
                     f"(the frozen file's name, .png)")
    if entry["log"] is not None:
        lines.append(f"  log  {_rel(config, entry['log'])}")
    suite = entry.get("suite")
    if suite is not None:
        lines.append(f"  suite {_rel(config, suite.folder)}/: {len(suite.files)} scenario file(s), "
                     f"{suite.failing} failing for {r.subject}"
                     + (f", {suite.replaced} of an earlier suite removed" if suite.replaced else "")
                     + f" (re-run: pytest {_rel(config, suite.folder.parent)} --nav-subject=...)")
    if entry["error"]:
        lines.append(f"  ERROR {entry['error']}")
    return lines
