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
"""
from __future__ import annotations

import os
from typing import Any

import pytest

from .state import STATE_KEY

NUM_CPUS_KEY = pytest.StashKey[int]()
SEARCH_WORKERS_KEY = pytest.StashKey[int]()


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
    """Before xdist starts workers: decide what ``-n`` means next to ``--nav-ray``."""
    if hasattr(config, "workerinput"):
        return
    from .options import read_ray_address

    address = read_ray_address(config)
    if address is None and _wants_search(config) and _numprocesses(config) is not None:
        n = take_over_xdist(config, "--navsearch")
        config.stash[SEARCH_WORKERS_KEY] = n if n is not None else 0
        return
    if address is None or _numprocesses(config) is None:
        return
    if address != "auto":
        raise pytest.UsageError(f"--nav-ray={address} runs the episodes on the cluster, which decides how "
                                f"many run at once; drop -n")
    n = take_over_xdist(config, "--nav-ray")
    if n == 0:
        raise pytest.UsageError("-n 0 with --nav-ray=auto would give the local Ray instance no CPU; "
                                "give -n N (N >= 1) or drop -n to use every core")
    assert n is not None
    config.stash[NUM_CPUS_KEY] = n


def _wants_search(config: pytest.Config) -> bool:
    try:
        return bool(config.getoption("navsearch") or config.getini("navsearch"))
    except (ValueError, pytest.UsageError):   # the search plugin is not loaded
        return False


def pytest_sessionstart(session: pytest.Session) -> None:
    """Controller with --nav-ray: start or join Ray and check every node (after the core plugin
    has loaded and checked the subject). With --navsearch -n N: the local worker processes.
    Nothing is started for --collect-only."""
    config = session.config
    state = config.stash.get(STATE_KEY, None)
    if state is None or state.is_worker or config.option.collectonly:
        return
    workers = config.stash.get(SEARCH_WORKERS_KEY, 0)
    if state.settings.ray is None and workers > 1:
        from ..dispatch.local import ProcessExecutor

        pool = ProcessExecutor(workers)
        if state.subject.spec is None:   # a factory from the conftest hook travels by pickle
            try:
                pool.check_picklable(state.subject.factory)
            except ValueError as exc:
                raise pytest.UsageError(f"navscenario: -n {workers} with --navsearch: {exc}") from None
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
    if state.settings.ray is None:
        return [f"navsearch: each search evaluates its candidates on {state.executor.description} "
                f"(-n {state.executor.workers}); searches run one after the other"]
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
    """True if the item will not run its episode: a skip mark, or a scenario its setup rejects
    as impassable (verdict/feasibility.py; cached, so asking twice is free)."""
    from ..verdict.feasibility import impassable_reason

    if item.get_closest_marker("skip") is not None or impassable_reason(item.scenario) is not None:
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
    if executor is not None and not session.config.option.collectonly:
        # scenario items (collect.ScenarioItem, known by its method: no import, no cycle)
        items = [i for i in session.items if hasattr(i, "episode_job") and not _skipped(i)]
        keep = keep_trajectory(session.config)
        for item, pending in zip(items, executor.submit([i.episode_job(keep) for i in items])):
            item.nav_pending = pending
    return (yield)


@pytest.hookimpl(tryfirst=True)
def pytest_sessionfinish(session: pytest.Session) -> None:
    """Cancel what did not run (-x, Ctrl-C) and leave Ray; a local instance is stopped."""
    state = session.config.stash.get(STATE_KEY, None)
    if state is not None and state.executor is not None:
        executor, state.executor = state.executor, None
        executor.close(cancel=True)
