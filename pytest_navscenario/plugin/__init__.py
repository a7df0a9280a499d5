"""Plugin: the pytest glue, the top layer (``pytest11`` entry point ``navscenario``: this module).

In: pytest's hooks, the command line and ini. Out: one item per scenario file (``collect.py``),
``report.nav`` payloads on each call report (``payload.py``), and on the controller the results
file, artifacts and the summary. This module holds the core hooks only; the work is in small
modules: ``options.py`` (every option and its ini twin), ``state.py`` (session state in
``config.stash``), ``collect.py``, ``payload.py``, ``artifacts.py``, ``fixtures.py`` (``nav_run``,
``nav_subject``), ``hookspecs.py`` (new hooks), and the feature plugins ``search.py``
(``--navsearch``), ``reports.py`` (plots, HTML, baseline gate), ``bags.py`` (``--nav-bag``) and
``parallel.py`` (``--nav-ray``: episodes as Ray tasks), registered through ``pytest_plugins``.

Heavy modules (the loader, the runner and MuJoCo) are imported only when a scenario is collected
or run, so that loading the plugin into an unrelated pytest run stays cheap. With xdist, workers
run the episodes and attach ``report.nav`` (a plain dict) to each call report; the controller
gathers the records and writes every file, so workers never race on one.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from . import hookspecs
from .options import pytest_addoption  # noqa: F401  (a hook: options + ini twins)

pytest_plugins = [
    "pytest_navscenario.plugin.fixtures",
    "pytest_navscenario.plugin.search",
    "pytest_navscenario.plugin.reports",
    "pytest_navscenario.plugin.bags",
    "pytest_navscenario.plugin.parallel",
]

WORKER_SEED_KEY = "navscenario_seed"


def pytest_addhooks(pluginmanager: pytest.PytestPluginManager) -> None:
    pluginmanager.add_hookspecs(hookspecs)


class XdistHooks:
    """Registered only when pytest-xdist is installed (its hook names are unknown otherwise)."""

    def pytest_configure_node(self, node: Any) -> None:
        from .state import STATE_KEY
        state = node.config.stash.get(STATE_KEY, None)
        if state is not None:
            node.workerinput[WORKER_SEED_KEY] = state.settings.seed

    def pytest_testnodedown(self, node: Any, error: Any) -> None:
        """Controller: the workers collected; take over their list of skipped YAML files."""
        from .skipped import WORKER_KEY
        from .state import STATE_KEY
        state = node.config.stash.get(STATE_KEY, None)
        sent = getattr(node, "workeroutput", {}).get(WORKER_KEY)
        if state is not None and sent:
            state.not_scenarios.extend((p, r) for p, r in sent["files"])
            state.scenario_folders.update(sent["folders"])


def pytest_configure(config: pytest.Config) -> None:
    config.pluginmanager.register(Controller(config), "navscenario-controller")
    if config.pluginmanager.hasplugin("xdist") or config.pluginmanager.hasplugin("xdist.plugin"):  # -p xdist.plugin
        config.pluginmanager.register(XdistHooks(), "navscenario-xdist")
    _stop_gracefully_on_sigterm(config)


def _stop_gracefully_on_sigterm(config: pytest.Config) -> None:
    """SIGTERM (a CI job cancelled, ``kill``) ends the run like Ctrl-C: pytest's own interruption
    path, so the results file, frozen failures and the summary of what finished are still written.
    SIGTERM only in the controller, and only when nobody else handles it. Both Ctrl-C and SIGTERM
    raise core.interrupts.UserInterrupt, so that a planner's own ``raise KeyboardInterrupt`` or
    ``sys.exit()`` can be told apart from the user's and ends only its episode (issue 15)."""
    from ..core.interrupts import install

    restore = install(sigterm=not _is_worker(config))
    if restore is not None:
        config.add_cleanup(restore)


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_keyboard_interrupt(excinfo: pytest.ExceptionInfo) -> Any:
    """Before pytest reports an interruption: every frame of it numbered
    (``core.interrupts.with_line_numbers``), so that the report does not fail on a frame a signal
    left without a line number and the run ends as interrupted (status 2) with its summary."""
    from ..core.interrupts import with_line_numbers

    if with_line_numbers(excinfo.value) and excinfo.value.__traceback__ is not None:
        excinfo.traceback = type(excinfo.traceback)(excinfo.value.__traceback__)
    return (yield)


def _is_worker(config: pytest.Config) -> bool:
    return hasattr(config, "workerinput")


@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart(session: pytest.Session) -> None:
    """Read the options and load the subject; a bad one stops the run before any test."""
    import dataclasses

    from ..core.errors import SubjectLoadError
    from .options import read_settings
    from .state import STATE_KEY, NavState
    from ..subjects.resolve import resolve_subject

    config = session.config
    settings = read_settings(config)
    worker = _is_worker(config)
    if worker and WORKER_SEED_KEY in config.workerinput:  # type: ignore[attr-defined]
        settings = dataclasses.replace(settings, seed=int(config.workerinput[WORKER_SEED_KEY]))  # type: ignore[attr-defined]
    origin = "--nav-subject" if config.getoption("nav_subject") else "ini nav_subject"
    subject = resolve_subject(config, settings.subject_spec, origin)
    subject.locate()   # in every process, before any worker starts: workers copy sys.path
    config.stash[STATE_KEY] = NavState(settings=settings, subject=subject, is_worker=worker)
    # With --nav-ray the subject need only load on the nodes: parallel.py checks each of them.
    if not worker and subject.origin != "built-in default" and settings.ray is None:
        distributed = bool(getattr(config.option, "numprocesses", None))   # xdist workers run episodes
        try:
            subject.check(keep_running=not distributed)
        except SubjectLoadError as exc:
            raise pytest.UsageError(f"navscenario: {exc}") from None
    if not worker and settings.results is not None:
        try:
            settings.results.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise pytest.UsageError(f"navscenario: cannot create the folder of the results file "
                                    f"{settings.results}: {exc}") from None
        if not config.option.collectonly and not _search_run(config):
            _lock_results(config, settings.results)


def _search_run(config: pytest.Config) -> bool:
    from .parallel import _wants_search
    return _wants_search(config)


def _lock_results(config: pytest.Config, path: Path) -> None:
    """One run at a time writes a results file: two runs would each write their own records
    whole, and the file would keep only the last run's (issue 26). A second run is refused at
    once, naming the first; the lock goes when this run ends (or dies: the OS drops it)."""
    import datetime
    import os
    import shlex
    import socket

    from ..core.files import FileBusy, WriterLock

    started = datetime.datetime.now().strftime("%Y-%m-%d %H:%M:%S")
    command = shlex.join(["pytest", *map(str, config.invocation_params.args)])
    me = f"pid {os.getpid()} on {socket.gethostname()}, started {started}: {command}"
    try:
        lock = WriterLock(path, me)
    except FileBusy as busy:
        raise pytest.UsageError(
            f"navscenario: another run is writing the results file {path} ({busy.holder or 'its pid is unknown'}); "
            f"two runs writing one results file would leave only one run's records in it. Wait for "
            f"that run to end, or give this one a file of its own, e.g. --nav-results="
            f"{path.with_name(path.stem + '-2' + path.suffix).name}") from None
    except OSError as exc:
        raise pytest.UsageError(f"navscenario: cannot lock the results file {path} against a second "
                                f"writer ({exc}); is its folder writable?") from None
    config.add_cleanup(lock.release)


def pytest_report_header(config: pytest.Config) -> list[str]:
    from .state import STATE_KEY
    state = config.stash.get(STATE_KEY, None)
    if state is None:
        return []
    s = state.settings
    limit = f"{s.tick_limit:g} s" if s.tick_limit else "none"
    from ..core.versions import mujoco_version
    lines = [f"navscenario: subject {state.subject.label}, seed {s.seed} (--nav-seed), "
             f"tick limit {limit}, MuJoCo {mujoco_version()}"]
    lines += [f"navscenario: subject note: {note}" for note in state.subject.notes]
    if s.repeat > 1:
        lines.append(f"navscenario: {s.repeat} runs per scenario with different noise seeds "
                     f"(--nav-repeat; scenarios without sensor noise repeat identically)")
    extra = []
    if s.results is not None:
        extra.append(f"results {s.results}")
    extra.append(f"artifacts {s.artifacts if s.artifacts is not None else 'off'}")
    lines.append("navscenario: " + ", ".join(extra))
    return lines


def pytest_ignore_collect(collection_path: Path, config: pytest.Config) -> bool | None:
    """The plugin's own output folders (artifacts, plots, bags) are never collected."""
    from .collect import ignore_output_folder
    return ignore_output_folder(collection_path, config)


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> Any:
    from .collect import collect_file
    return collect_file(file_path, parent)


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(session: pytest.Session, config: pytest.Config, items: list[pytest.Item]) -> None:
    """Families of same-named folders stay apart (collect.separate_families); first, before
    -k/-m deselect, so that a selection does not rename a family."""
    from .collect import separate_families
    separate_families(config, items)


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_runtestloop(session: pytest.Session) -> Any:
    """An invalid scenario file is a collection error, but the other items still run.

    pytest stops before running anything when collection had errors (unless
    --continue-on-collection-errors); that rule is kept for Python test modules, and only the
    errors of scenario files are left out of the check. The exit status still reports them.
    """
    from .state import STATE_KEY
    state = session.config.stash.get(STATE_KEY, None)
    hidden = min(session.testsfailed, state.bad_scenario_files) if state is not None else 0
    session.testsfailed -= hidden
    try:
        return (yield)
    finally:
        session.testsfailed += hidden


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Any:
    """Attach ``report.nav`` (payload.py) to the call report of an item that ran an episode."""
    report = yield
    result = getattr(item, "nav_result", None)
    if call.when == "call" and result is not None:
        from .payload import clouds_requested, episode_to_payload, trajectories_requested
        from .state import get_state

        state = get_state(item.config)
        want = trajectories_requested(item.config)
        with_traj = want == "all" or (not result.passed and (
            want == "failed" or state.settings.artifacts is not None))
        spec = state.subject.spec if state.subject.origin != "hook" else None
        report.nav = episode_to_payload(result, nodeid=item.nodeid, path=item.rel_path,  # type: ignore[attr-defined]
                                        with_trajectory=with_traj, repeat=item.repeat,  # type: ignore[attr-defined]
                                        subject_spec=spec, with_cloud=clouds_requested(item.config))
        item.nav_result = None  # type: ignore[attr-defined]  # the payload has it; free the arrays
    return report


_PACKED = "$navscenario-json"


@pytest.hookimpl(wrapper=True)
def pytest_report_to_serializable(config: pytest.Config, report: Any) -> Any:
    """xdist worker: send ``report.nav`` as one JSON string. execnet serialises nested dicts
    element by element in Python (~0.18 ms per payload to write, 0.23 ms to read); one string
    costs ~0.1 + 0.09 ms, on the workers and on the controller that all workers report to."""
    data = yield
    nav = data.get("nav") if isinstance(data, dict) else None
    if isinstance(nav, dict):
        import json
        data["nav"] = {_PACKED: json.dumps(nav, separators=(",", ":"))}   # NaN/inf kept (allow_nan)
    return data


@pytest.hookimpl(wrapper=True)
def pytest_report_from_serializable(config: pytest.Config, data: Any) -> Any:
    """Controller: unpack what pytest_report_to_serializable packed (before the report is built)."""
    nav = data.get("nav") if isinstance(data, dict) else None
    if isinstance(nav, dict) and _PACKED in nav:
        import json
        data["nav"] = json.loads(nav[_PACKED])
    return (yield)


@pytest.hookimpl(trylast=True)
def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    """Once every plugin has seen an episode (and an xdist worker has sent it), keep only its
    record: pytest holds every report until the session ends, so the full payload (scenario,
    metrics, trajectory) would grow memory by ~10 KiB per episode in long runs."""
    nav = getattr(report, "nav", None)
    if nav is not None and len(nav) > 1:
        report.nav = {"record": nav["record"]}  # type: ignore[attr-defined]


class Controller:
    """Per-config hooks that need the config but whose hookspecs do not pass it."""

    def __init__(self, config: pytest.Config):
        self.config = config

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        """Controller: gather the record, write a failing item's artifacts, tell feature plugins."""
        nav = getattr(report, "nav", None)
        if nav is None and report.when == "???" and report.failed and not _is_worker(self.config):
            from .payload import crashed_item_payload   # xdist: the item's worker died running it
            nav = crashed_item_payload(self.config, report)
            if nav is not None:
                report.nav = nav   # type: ignore[attr-defined]
        if nav is None or report.when not in ("call", "???") or _is_worker(self.config):
            return
        from .state import STATE_KEY
        state = self.config.stash.get(STATE_KEY, None)
        if state is None:
            return
        state.records.append(nav["record"])
        folder = None
        if report.failed and state.settings.artifacts is not None:
            from .artifacts import write_item_artifacts
            folder = write_item_artifacts(self.config, nav)
            if folder is not None:
                state.failed_artifacts.append(str(folder))
        self.config.hook.pytest_navscenario_episode_report(
            config=self.config, report=report, payload=nav, artifact_dir=folder)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Controller: write the results file (also after Ctrl-C: whatever ran is kept)."""
    from .state import STATE_KEY
    config = session.config
    state = config.stash.get(STATE_KEY, None)
    _end_left_running(state)
    if state is not None and state.is_worker and (state.not_scenarios or state.scenario_folders):
        from .skipped import WORKER_KEY
        config.workeroutput[WORKER_KEY] = {  # type: ignore[attr-defined]
            "files": [list(f) for f in state.not_scenarios], "folders": sorted(state.scenario_folders)}
    if state is None or state.is_worker or state.settings.results is None:
        return
    if config.option.collectonly:  # nothing ran: keep an existing results file
        return
    if not state.records and (state.settings.results.exists() or _search_run(config)):
        state.results_kept = True   # a run that recorded no episode (a search, -k matching nothing)
        return                      # leaves the file as it was
    from ..report.flaky import annotate_repeats
    from ..report.results_file import write_results
    try:
        write_results(state.settings.results, annotate_repeats(state.records))
    except OSError as exc:
        # Said in the terminal summary, on a line of its own. The run fails: a CI job whose
        # results are lost must not pass (the gate that reads them later would see nothing).
        state.results_error = (f"navscenario: cannot write the results file {state.settings.results}: "
                               f"{exc}; no results were written")
        if session.exitstatus == pytest.ExitCode.OK:   # a failing run's own status stays (1, 2, ...)
            session.exitstatus = pytest.ExitCode.INTERNAL_ERROR


def _end_left_running(state: Any) -> None:
    """End the processes in-process planners left running in this process (its episodes: the
    controller's in a serial run, an xdist worker's own); the controller says so in its summary."""
    import sys
    processes = sys.modules.get("pytest_navscenario.core.processes")   # loaded once an episode ran
    if processes is None:
        return
    ended = processes.end_left_behind()
    if state is not None and ended:
        state.ended_left_running = [f"pid {p.pid} after {p.episode}" for p in ended]


def pytest_terminal_summary(terminalreporter: Any, exitstatus: int, config: pytest.Config) -> None:
    from .collect import rel_path
    from .state import STATE_KEY
    state = config.stash.get(STATE_KEY, None)
    if state is None or state.is_worker:
        return
    from .skipped import summary_lines
    for line in summary_lines(state, lambda p: rel_path(config, p), config.getoption("verbose") > 0):
        terminalreporter.write_line(line)
    if state.ended_left_running:
        shown = state.ended_left_running[:5] + (["..."] if len(state.ended_left_running) > 5 else [])
        terminalreporter.write_line(f"navscenario: ended {len(state.ended_left_running)} process(es) the planner "
                                    f"had left running ({', '.join(shown)}; see the warnings)", yellow=True)
    if not state.records and state.settings.results is None:
        return
    tr = terminalreporter
    if state.settings.summary and state.records:
        from ..report.summary import format_summary
        tr.write_sep("=", "navscenario summary")
        for line in format_summary(state.records).splitlines():
            tr.write_line(line)
    if state.settings.repeat > 1 and state.records:
        from ..report.flaky import format_flaky, format_holding, holding_rows
        tr.write_sep("=", "navscenario flaky scenarios")
        for line in format_flaky(state.records).splitlines():
            tr.write_line(line)
        rows = holding_rows(state.records, state.frozen) if state.frozen else []
        if rows:
            tr.write_sep("=", "navscenario frozen failures: do they still hold?")
            for line in format_holding(rows).splitlines():
                tr.write_line(line, red="NO LONGER" in line)
    if state.results_error is not None:
        tr.write_line(state.results_error, red=True, bold=True)
    elif state.settings.results is not None and not config.option.collectonly:
        if not state.results_kept:
            tr.write_line(f"navscenario: wrote {len(state.records)} record(s) to {state.settings.results}")
        elif _search_run(config):
            tr.write_line(f"navscenario: a search records its simulations in its own log, not in the "
                          f"results file; {state.settings.results} was left as it was")
        else:
            tr.write_line(f"navscenario: no episode ran, so the results file {state.settings.results} "
                          f"was left as it was")
    if state.failed_artifacts:
        tr.write_line(f"navscenario: artifacts of {len(state.failed_artifacts)} failing item(s) in "
                      f"{state.settings.artifacts}")
