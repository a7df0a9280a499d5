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

Beside it: search_options.py (the options and SearchSettings), search_progress.py (the live
line), search_payload.py (the report as plain data), search_summary.py (the terminal summary),
search_report.py (pictures and the HTML report).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from .search_options import (DEFAULT_BUDGET, DEFAULT_HOLD, DEFAULT_OUT, DEFAULT_SHRINK_BUDGET,  # noqa: F401 (re-exported)
                             DEFAULT_STUCK_AFTER, OLD_OUT_INI, OPTIONS, STRATEGY_NAMES, SearchSettings,
                             _INT_OPTIONS, find_seed, read_search_settings)
from .options import ini_type
from .search_payload import payload_to_report, report_to_payload  # noqa: F401 (re-exported)
from .search_progress import _Progress
from .search_summary import format_entry  # noqa: F401 (re-exported)


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
