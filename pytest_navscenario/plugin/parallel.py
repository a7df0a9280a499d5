"""Where episodes run: ``--nav-ray`` (Ray tasks) and ``-n N`` next to ``--navsearch`` (local
worker processes that evaluate each search's generations).

``--nav-ray``: the scenario items' episodes run as Ray tasks, pytest still reports them.

At the start of the run loop every scenario item's episode is submitted, in item order; each item
then waits for its own result, so pytest reports one item per scenario in the usual order, with the
results a serial run gives (an episode is a pure function of scenario, subject and seed). Ray is
set up at session start, before any episode: a missing Ray, an unreachable address, or a node that
cannot load the subject is a UsageError naming the node and what it lacks.

``-n N`` (pytest-xdist) next to ``--nav-ray=auto`` gives the local Ray instance N CPUs instead of
starting N pytest workers (Ray spreads the episodes; xdist workers would only wait on it).

``-n N`` next to ``--navsearch`` runs the searches in this process, one after the other, each
evaluating its generations on N local worker processes (``dispatch.ProcessExecutor``), instead of
N xdist workers each running whole searches: one search then uses every core, the results are
those of a serial run, and Ctrl-C keeps what each search found (this process writes the files).

``--nav-workers N`` (and ``-n N`` on a run whose paths hold scenario files and no Python test
files) runs the scenario items' episodes on N local worker processes, exactly as ``--nav-ray``
runs them on Ray: this process collects once and reports, the workers only simulate. xdist's
workers would each start pytest, import everything and collect and validate every file again,
and send three reports per item back (issue 14 measured ~30 % more CPU than a serial run).
``--dist``/``--tx`` given explicitly keep pytest-xdist.
"""
from __future__ import annotations

import fnmatch
import os
from pathlib import Path
from typing import Any

import pytest

from .state import STATE_KEY

NUM_CPUS_KEY = pytest.StashKey[int]()
SEARCH_WORKERS_KEY = pytest.StashKey[int]()
SUBMIT_CHUNK = 16   # scenario items checked and submitted at a time at the start of the run loop
SUITE_WORKERS_KEY = pytest.StashKey[tuple[int, str]]()   # (workers, which option asked for them)
ISOLATE = "--nav-isolate"    # the reason given for one worker process asked for by --nav-isolate


def _numprocesses(config: pytest.Config) -> Any:
    return getattr(config.option, "numprocesses", None)


def take_over_xdist(config: pytest.Config, what: str) -> int | None:
    """Turn pytest-xdist's ``-n N`` into a worker count for ``what`` and switch xdist off (its
    workers would only wait); None without ``-n``. UsageError for a count below zero."""
    n = _numprocesses(config)
    if n is None:
        return None
    if isinstance(n, int) and n < 0:
        raise pytest.UsageError(f"-n {n}: the number of worker processes must be 0 or more "
                                f"(0: everything in this process; auto: one per core)")
    tx = list(getattr(config.option, "tx", None) or [])
    if tx and any(t != "popen" for t in tx):
        raise pytest.UsageError(f"{what} cannot be combined with xdist --tx gateways; use -n N")
    config.option.dist = "no"
    config.option.tx = []
    return int(n)


@pytest.hookimpl(tryfirst=True)
def pytest_configure(config: pytest.Config) -> None:
    """Before xdist starts workers: decide what ``-n`` and ``--nav-workers`` mean here."""
    if hasattr(config, "workerinput"):
        return
    from .options import read_ray_address

    address = read_ray_address(config)
    if address is not None:
        _no_workers_with_ray(config)
        if _numprocesses(config) is not None:
            _ray_cpus_from_n(config, address)
        return
    if not _wants_search(config):
        _choose_suite_workers(config)
        return
    workers = _nav_workers_alone(config)
    if _numprocesses(config) is not None:
        workers = take_over_xdist(config, "--navsearch")
    if (workers or 0) <= 1 and _isolated(config):
        workers = 1
    if workers is not None:
        config.stash[SEARCH_WORKERS_KEY] = workers


def _isolated(config: pytest.Config) -> bool:
    """--nav-isolate / ini nav_isolate: episodes on a worker process even in a serial run."""
    from .options import read_yes_no
    return read_yes_no(config, "nav_isolate")


def _ray_cpus_from_n(config: pytest.Config, address: str) -> None:
    """-n N next to --nav-ray=auto: the local instance's CPUs (a cluster decides for itself)."""
    if address != "auto":
        raise pytest.UsageError(f"--nav-ray={address} runs the episodes on the cluster, which decides how "
                                f"many run at once; drop -n")
    n = take_over_xdist(config, "--nav-ray")
    if n == 0:
        raise pytest.UsageError("-n 0 with --nav-ray=auto would give the local Ray instance no CPU; "
                                "give -n N (N >= 1) or drop -n to use every core")
    assert n is not None
    config.stash[NUM_CPUS_KEY] = n


def read_workers(config: pytest.Config) -> int | None:
    """--nav-workers / ini nav_workers: a worker count (``auto``: one per core), None if unset."""
    from .options import option_value

    raw, where, _ = option_value(config, "nav_workers", "a whole number >= 0 or auto")
    value = raw.strip().lower()
    if value in ("", "none"):
        return None
    if value == "auto":
        from ..dispatch.local import available_cores
        return available_cores()
    try:
        n = int(value)
    except ValueError:
        n = -1
    if n < 0:
        raise pytest.UsageError(f"{where}: expected a whole number of worker processes >= 0 or 'auto' "
                                f"(one per core), got {raw!r} (e.g. --nav-workers=2; 0: in this process)")
    return n


def _nav_workers_alone(config: pytest.Config) -> int | None:
    """--nav-workers N (None if not given); a usage error next to -n N."""
    workers = read_workers(config)
    if workers is not None and _numprocesses(config) is not None:
        raise pytest.UsageError("give either -n N (pytest-xdist) or --nav-workers N, not both")
    return workers


def _no_workers_with_ray(config: pytest.Config) -> None:
    if read_workers(config) is not None:
        raise pytest.UsageError("--nav-workers runs episodes on local worker processes and --nav-ray on Ray; "
                                "give one of them (with --nav-ray=auto, -n N sets the local instance's CPUs)")


def _xdist_asked_for(config: pytest.Config) -> bool:
    """True if the command line chose xdist's distribution itself (--dist, -d, --tx)."""
    args = [str(a) for a in config.invocation_params.args]
    return any(a == "-d" or a.startswith(("--dist", "--tx")) for a in args)


def _choose_suite_workers(config: pytest.Config) -> None:
    """--nav-workers N, or -n N on a scenario-only run: the scenario items' episodes on N local
    worker processes (see the module docstring); xdist is switched off for it."""
    workers = _nav_workers_alone(config)
    if workers is not None and (workers > 1 or not _isolated(config)):
        config.stash[SUITE_WORKERS_KEY] = (workers, f"--nav-workers {workers}")
        return
    n = _numprocesses(config)
    if n is None or _xdist_asked_for(config) or config.option.collectonly or not _scenario_only(config):
        if n is None and _isolated(config):     # xdist's own workers isolate themselves
            config.stash[SUITE_WORKERS_KEY] = (1, ISOLATE)
        return
    n = take_over_xdist(config, "-n")
    assert n is not None
    config.stash[SUITE_WORKERS_KEY] = (n, f"-n {n} on scenario files only")
    if n <= 1 and _isolated(config):
        config.stash[SUITE_WORKERS_KEY] = (1, ISOLATE)


def _scenario_only(config: pytest.Config) -> bool:
    """True when every path of the run is, or holds, scenario files and no Python file pytest
    would collect (python_files, or any .py with --doctest-modules): only then can the plugin run
    every item itself. A node id (path::name) counts by its path; a missing path is pytest's to
    report, so it answers False."""
    patterns = ["*.py"] if getattr(config.option, "doctestmodules", False) else list(config.getini("python_files"))
    skip = list(config.getini("norecursedirs"))
    base = Path(config.invocation_params.dir)
    for arg in config.args:
        path = base / str(arg).split("::", 1)[0]
        if path.is_file():
            if path.suffix == ".py":
                return False
            continue
        if not path.is_dir():
            return False
        for folder, dirs, files in os.walk(path):
            dirs[:] = [d for d in dirs if not any(fnmatch.fnmatch(d, p) for p in skip)]
            if any(f != "conftest.py" and any(fnmatch.fnmatch(f, p) for p in patterns) for f in files):
                return False
    return True


def _wants_search(config: pytest.Config) -> bool:
    try:
        return bool(config.getoption("navsearch") or config.getini("navsearch"))
    except (ValueError, pytest.UsageError):   # the search plugin is not loaded
        return False


def pytest_sessionstart(session: pytest.Session) -> None:
    """Controller with --nav-ray: start or join Ray and check every node (after the core plugin
    has loaded and checked the subject). With --navsearch -n N or --nav-workers N (or -n N on
    scenario files only): the local worker processes.
    Nothing is started for --collect-only."""
    config = session.config
    state = config.stash.get(STATE_KEY, None)
    if state is None or state.is_worker or config.option.collectonly:
        return
    workers, why = config.stash.get(SUITE_WORKERS_KEY, (0, ""))
    if SEARCH_WORKERS_KEY in config.stash:
        workers, why = config.stash[SEARCH_WORKERS_KEY], "with --navsearch"
    if state.settings.ray is None and (workers > 1 or workers == 1 and (why == ISOLATE or _isolated(config))):
        from ..dispatch.local import ProcessExecutor

        pool = ProcessExecutor(workers)
        if state.subject.spec is None:   # a factory from the conftest hook travels by pickle
            try:
                pool.check_picklable(state.subject.factory)
            except ValueError as exc:
                raise pytest.UsageError(f"navscenario: {workers} worker processes ({why}): {exc}") from None
        state.executor = pool
        config.add_cleanup(lambda: pool.close(cancel=True))   # also if a later check stops the run
        pool.warm()   # the workers start while pytest collects and the search sets up
        return
    if state.settings.ray is None:
        return
    from ..dispatch.on_ray import RayExecutor, RaySetupError

    address = state.settings.ray
    try:
        executor = RayExecutor(address, num_cpus=config.stash.get(NUM_CPUS_KEY, None))
    except RaySetupError as exc:
        raise pytest.UsageError(f"navscenario: {exc}") from None
    state.executor = executor
    config.add_cleanup(lambda: executor.close(cancel=True))   # also if a later check stops the run
    try:
        state.executor_notes = executor.check_nodes(state.subject.runner_arg, os.getcwd())
    except RaySetupError as exc:
        executor.close(cancel=True)
        state.executor = None
        raise pytest.UsageError(f"navscenario: --nav-ray={address}: {exc}") from None


def pytest_report_header(config: pytest.Config) -> list[str]:
    state = config.stash.get(STATE_KEY, None)
    if state is None or state.executor is None:
        return []
    if state.settings.ray is None and SEARCH_WORKERS_KEY in config.stash:
        why = ISOLATE if state.executor.workers == 1 else f"-n {state.executor.workers}"
        return [f"navsearch: each search evaluates its candidates on {state.executor.description} "
                f"({why}); searches run one after the other"]
    if state.settings.ray is None:
        _, why = config.stash[SUITE_WORKERS_KEY]
        return [f"navscenario: episodes run on {state.executor.description} ({why}); this process "
                f"collects and reports"]
    return [f"navscenario: episodes run as Ray tasks on {state.executor.description} (--nav-ray)"] + \
        [f"navscenario: WARNING {note}" for note in state.executor_notes]


def search_subject_and_evaluator(config: pytest.Config) -> tuple[Any, Any]:
    """(planner factory, evaluator) for run_search: the session's own factory and the serial
    evaluator, or, with an executor, a factory every worker can load and its evaluator."""
    state = config.stash[STATE_KEY]
    if state.executor is None:
        return state.subject.factory, None
    from ..dispatch.jobs import SubjectFactory
    from ..search.parallel import executor_evaluator

    subject = state.subject
    factory = SubjectFactory(subject.spec, os.getcwd()) if subject.spec is not None else subject.factory
    return factory, executor_evaluator(state.executor)


def keep_trajectory(config: pytest.Config) -> str:
    """Which episodes must bring their trajectory back (the rule of the call report's payload)."""
    from .payload import trajectories_requested

    want = trajectories_requested(config)
    if want == "all":
        return "all"
    state = config.stash[STATE_KEY]
    return "failed" if want == "failed" or state.settings.artifacts is not None else "none"


def _skipped(item: Any) -> bool:
    """True if the item will not run its episode because of a skip mark. A scenario its setup
    rejects as impassable is submitted all the same: the worker checks it first and sends back
    the reason instead of simulating (``EpisodeJob.check_feasible``), keeping that work off
    this process, which shares the cores with the workers."""
    if item.get_closest_marker("skip") is not None:
        return True
    if item.get_closest_marker("skipif") is None:
        return False
    try:
        from _pytest.skipping import evaluate_skip_marks
        return evaluate_skip_marks(item) is not None
    except Exception:   # an error in the condition is reported by pytest itself at setup
        return False


@pytest.hookimpl(wrapper=True)
def pytest_runtestloop(session: pytest.Session) -> Any:
    """Submit every scenario item's episode, in item order, before the first item runs."""
    state = session.config.stash.get(STATE_KEY, None)
    executor = state.executor if state is not None else None
    if state is not None and executor is None and not session.config.option.collectonly:
        state.serial_items = sum(1 for i in session.items if hasattr(i, "episode_job"))
    if executor is not None and not session.config.option.collectonly:
        # scenario items (collect.ScenarioItem, known by its method: no import, no cycle)
        from ..dispatch.batches import submit_batched
        from ..harness.batch import Batching

        keep = keep_trajectory(session.config)
        # in chunks, so the first episodes run while this process checks the later items
        items = [i for i in session.items if hasattr(i, "episode_job")]
        size = (batch_size(state.settings.batch, len(items), getattr(executor, "workers", 1))
                if state.subject.answers_batches() else 1)
        state.batching = Batching() if size > 1 else None
        step = max(SUBMIT_CHUNK, size)
        for start in range(0, len(items), step):
            chunk = [i for i in items[start:start + step] if not _skipped(i)]
            jobs = [i.episode_job(keep) for i in chunk]
            for item, pending in zip(chunk, submit_batched(executor, jobs, size, state.batching,
                                                       state.settings.batch_engine)):
                item.nav_pending = pending
    return (yield)


def batch_size(batch: int, items: int, workers: int) -> int:
    """Episodes a batch job holds: --nav-batch at most, and few enough that every worker gets one
    (20 items on 2 workers: batches of 10, not one of 16 and one of 4)."""
    return max(1, min(batch, -(-items // max(1, workers))))


def pytest_terminal_summary(terminalreporter: Any, exitstatus: int, config: pytest.Config) -> None:
    """The line saying how the scenario items' episodes were batched on the workers."""
    state = config.stash.get(STATE_KEY, None)
    batching = getattr(state, "batching", None) if state is not None else None
    if batching is None and state is not None and state.serial_items:
        _note_unused_batch_options(terminalreporter, state.settings)
    if batching is None or not (batching.batched or batching.alone):
        return
    engine = state.settings.batch_engine
    flags = f"--nav-batch {state.settings.batch}" + (f", --nav-batch-engine {engine}" if engine != "cpu" else "")
    terminalreporter.write_line(f"navscenario: batches ({flags}): {batching.describe()}")


def _note_unused_batch_options(terminalreporter: Any, settings: Any) -> None:
    """A serial suite runs its items one at a time: say so when --nav-batch (other than its default)
    or --nav-batch-engine warp asked for batches, rather than ignore them silently."""
    from .options import DEFAULT_BATCH

    given = ([f"--nav-batch {settings.batch}"] if settings.batch not in (1, DEFAULT_BATCH) else []) + \
        ([f"--nav-batch-engine {settings.batch_engine}"] if settings.batch_engine != "cpu" else [])
    if given:
        terminalreporter.write_line(f"navscenario: {', '.join(given)} not used: a suite without workers runs its "
                                    f"items one at a time, each on the CPU (batches need -n N, --nav-workers N, "
                                    f"--nav-ray or --nav-isolate)")


@pytest.hookimpl(tryfirst=True)
def pytest_sessionfinish(session: pytest.Session) -> None:
    """Cancel what did not run (-x, Ctrl-C) and leave Ray; a local instance is stopped."""
    state = session.config.stash.get(STATE_KEY, None)
    if state is not None and state.executor is not None:
        executor, state.executor = state.executor, None
        executor.close(cancel=True)
