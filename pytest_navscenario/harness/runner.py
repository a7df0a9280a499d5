"""Public entry: run one scenario against one planner and get an EpisodeResult.

    >>> from pytest_navscenario import load_scenario, run_scenario
    >>> result = run_scenario(load_scenario("scenarios/boxes1.yaml"), "dwa")
    >>> result.outcome, result.metrics.min_clearance

The simulation (``sim.simulate``, sim/episode.py) yields the raw facts; the oracle
(verdict/oracle.py) gives the outcome and one-line message; verdict/metrics.py the per-episode
figures.
"""
from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..core import processes
from ..subjects.external import running_pids
from ..subjects.loading import BUILTIN_SUBJECTS, DEFAULT_SUBJECT, make_planner, subject_identity
from ..verdict.result import EpisodeResult
from ..scenario.model import Scenario
from ..scenario.perturb import perturbed


def check_feasibility(scenario: Scenario) -> tuple[Any, float]:
    """(``feasibility.infeasible(scenario)``: None, or why the scenario is no test with the field to
    fix, the seconds it took). Its shortest path is the one the episode's metrics need (cached per
    process): the time belongs to the episode's evaluation."""
    from ..verdict import feasibility

    t0 = time.perf_counter()
    found = feasibility.infeasible(scenario)
    return found, time.perf_counter() - t0


def add_check_time(result: EpisodeResult, seconds: float) -> EpisodeResult:
    """Count the feasibility check's time (its shortest path, reused by the metrics) in the
    episode's ``wall_time`` and ``timings["metrics"]``, wherever the check ran."""
    if seconds:
        result.wall_time += seconds
        result.timings["metrics"] = result.timings.get("metrics", 0.0) + seconds
    return result


def unfinished_result(scenario: Scenario, exc: BaseException, *, seed: int, subject: str) -> EpisodeResult:
    """The record of an episode that never finished because running it raised ``exc`` (its worker
    process died: ``WorkerDied``, ``RayTaskLost``; or the harness failed): outcome subject-error,
    ``error`` the exception's type, no trajectory, every metric undefined. So every item that ran
    has a record and counts in the rates (issue 32): a crash is not a missing row."""
    from ..sim.trajectory import SubjectFailure, Trajectory
    from ..verdict.result import Metrics, Outcome

    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    kind = text.split(":", 1)[0] if text.startswith(("WorkerDied:", "RayTaskLost:", "WorkerCrashed:")) else type(exc).__name__
    detail = text.split(":", 1)[1].strip() if kind != type(exc).__name__ else text
    message = f"the episode did not finish ({kind}): {detail}" if detail else f"the episode did not finish ({kind})"
    nan = float("nan")
    metrics = Metrics(**{f: ("" if f in ("min_clearance_obstacle", "min_gap_obstacles") else nan)
                         for f in Metrics.__dataclass_fields__})
    return EpisodeResult(scenario=scenario, outcome=Outcome.SUBJECT_ERROR, metrics=metrics,
                         trajectory=Trajectory.empty(), seed=seed, subject=subject, message=message,
                         subject_failure=SubjectFailure(message, -1, nan), error=kind)


def effective_seed(scenario_seed: int, base_seed: int | None) -> int:
    """The episode's noise seed: the scenario's own seed when ``base_seed`` is None or 0 (so
    pytest's default run, the search and nav_run all see the same bits), else a deterministic mix."""
    if not base_seed:
        return int(scenario_seed)
    mixed = np.random.SeedSequence([int(scenario_seed) % 2**64, int(base_seed) % 2**64])
    return int(mixed.generate_state(1)[0])


_BUILT_IN_MODULES = frozenset(target.partition(":")[0] for target in BUILTIN_SUBJECTS.values())


def starts_no_process(planner: Any) -> bool:
    """True for a built-in planner (None, its name, its class or an instance of it; not a
    subclass nor a factory): it starts no process, so its episode skips the two scans of /proc
    for the children a planner left running (~0.15 ms an episode, 1.3 % of a seed episode:
    issue 35)."""
    if planner is None or isinstance(planner, str):
        return (planner or DEFAULT_SUBJECT).strip() in BUILTIN_SUBJECTS
    kind = planner if isinstance(planner, type) else type(planner)
    return getattr(kind, "__module__", None) in _BUILT_IN_MODULES


def run_scenario(scenario: Scenario, planner: Any = None, *, seed: int | None = None,
                 tick_limit: float | None = None, reset_timeout: float | None = None,
                 stuck_after: float | None = None) -> EpisodeResult:
    """Run ``scenario`` once against ``planner`` and return outcome, metrics and trajectory.

    ``planner``: None (the built-in default, "dwa"), a spec such as ``"potential-field"`` or
    ``"pkg.mod:Planner"``, a class or zero-argument factory (called once), or a planner object.
    ``seed``: the run's base seed, mixed with ``scenario.simulation.seed`` (None/0: the scenario's
    own seed). ``tick_limit``: seconds a planner tick may take before it counts as a subject error.
    ``reset_timeout``: seconds an external (exec:) planner may take to answer reset (default 10).
    ``stuck_after``: end the episode early as a timeout when the robot has covered no new ground
    for that many seconds (None: run to the timeout; the search uses it to save time).
    Raises SubjectLoadError if the planner cannot be made, SimulationDivergedError if the physics
    blows up.
    """
    from ..sim.episode import simulate

    t0 = time.perf_counter()
    watched = not starts_no_process(planner)
    before = processes.children() if watched else set()
    instance, spec = make_planner(planner)
    if tick_limit and hasattr(instance, "tick_timeout"):  # adapters that enforce the limit themselves
        instance.tick_timeout = tick_limit
    if reset_timeout and hasattr(instance, "reset_timeout"):
        instance.reset_timeout = reset_timeout
    ep_seed = effective_seed(scenario.simulation.seed, seed)
    ran = perturbed(scenario, ep_seed)   # simulation.perturb: this episode's start and timing (else itself)
    facts = simulate(ran, instance, ep_seed, tick_limit=tick_limit, stuck_after=stuck_after)
    name, version = subject_identity(instance, spec)  # after reset: a planner may name itself there
    del instance    # a planner that ends its helpers when it is dropped has done so before the check
    left = processes.note_left_behind(before, scenario.name or "the episode", ours=running_pids()) if watched else ()
    return verdict(scenario, facts, ep_seed, name, version, stuck_after, t0, left, ran=ran)


def verdict(scenario: Scenario, facts: Any, ep_seed: int, name: str, version: str | None,
            stuck_after: float | None, t0: float, left: Any = (), ran: Scenario | None = None) -> EpisodeResult:
    """The EpisodeResult of an episode's raw facts (``sim.SimResult``): the oracle's outcome and
    message, the metrics; ``wall_time`` counted from ``t0``; ``left``: the processes it left
    running (core/processes.py). ``ran``: the scenario as simulated (``perturbed(scenario,
    ep_seed)``, computed when not given): judged and measured; ``scenario`` is reported."""
    from ..verdict import metrics, oracle
    from ..verdict.requirements import check_requirements

    if ran is None:
        ran = perturbed(scenario, ep_seed)

    t1 = time.perf_counter()
    checked = check_requirements(ran, facts.trajectory)
    outcome, message = oracle.classify(
        ran, facts.trajectory, collision=facts.collision, safety_stop=facts.safety_stop,
        subject_failure=facts.subject_failure, goal_reached=facts.goal_reached,
        stuck_after=stuck_after if facts.end == "stuck" else None, terrain_event=facts.terrain_event,
        requirements=checked)
    figures = metrics.compute_metrics(ran, facts.trajectory, collision=facts.collision)
    t2 = time.perf_counter()
    timings = dict(facts.timings)
    timings["metrics"] = t2 - t1
    return EpisodeResult(
        scenario=scenario, outcome=outcome, metrics=figures, trajectory=facts.trajectory, seed=ep_seed,
        subject=name, subject_version=version, message=message, collision=facts.collision,
        safety_stop=facts.safety_stop, subject_failure=facts.subject_failure,
        wall_time=t2 - t0, timings=timings, terrain_event=facts.terrain_event,
        left_running=tuple(f"pid {p.pid}: {p.command}" for p in left), requirements=checked)
