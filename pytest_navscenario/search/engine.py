"""Failure search around a seed scenario: Hypothesis-driven evolution, random baseline, shrinking.

``run_search(seed, subject_factory, budget=..., seed_value=...)`` simulates exactly ``budget``
valid candidates (invalid ones -- obstacles on the start/goal footprint, no path at all --
are discarded before simulation and counted separately), keeps the *distinct* failures and
shrinks each toward the seed with its own simulation cap.

Fitness (as in the paper): lower minimum robot-obstacle clearance is better and any failing
outcome beats every success. The ``evolve`` strategy is one Hypothesis run (``@given`` with
``target()``); because targeting is weak at budgets of ~100, each example either explores the
whole space or, most of the time, draws a small mutation of an elite from an archive of the
best layouts so far (kept diverse by crowding), so the budget is spent exploiting what works.

Distinct failures: two failures are the same when they have the same outcome, the same
culprit obstacle (the one hit / that triggered the safety stop / nearest at timeout) and
their offset vectors differ by less than ``DISTINCT_DISTANCE`` of every parameter's range.
"""
from __future__ import annotations

import math
import random
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

from ..scenario.model import Scenario
from .space import SearchSpace, invalid_reason, offsets_strategy

STRATEGIES = ("evolve", "random")
DISTINCT_DISTANCE = 0.1    # fraction of each parameter's range
ARCHIVE_SIZE = 8
CROWDING_DISTANCE = 0.05   # archive members closer than this replace each other
DEFAULT_SHRINK_BUDGET = 40
EXPLOIT = 0.7              # after a short warm-up, 70 % of candidates mutate an elite, 30 % explore,
                           # then the share follows each operator's rate of new distinct failures
MUTATION_SCALES = (0.05, 0.15, 0.3)   # Gaussian step sd as a fraction of the parameter's range
MAX_INVALID_FACTOR = 50    # give up after budget * this many discarded candidates in a row


class _Stop(BaseException):
    """Raised inside a Hypothesis run to end it at once (BaseException: Hypothesis does not
    treat it as a test failure, so nothing is replayed or shrunk)."""


@dataclass
class Candidate:
    """One simulated candidate."""
    sim: int                      # 1-based simulation number within its phase
    phase: str                    # "search" or "shrink"
    origin: str                   # seed / explore / mutate / random / shrink
    offsets: tuple[float, ...]
    outcome: str                  # Outcome value, or "harness-error" if the simulation itself failed
    clearance: float              # metrics.min_clearance (nan on harness error)
    culprit: str                  # obstacle hit / stopped for / nearest
    message: str
    metrics: dict[str, Any]
    scenario_hash: str
    wall_time: float
    scenario: Scenario | None = field(default=None, repr=False, compare=False)

    @property
    def failed(self) -> bool:
        return self.outcome not in ("success", "harness-error")

    @property
    def fitness(self) -> tuple[int, float]:
        """Smaller is better: failures first, then lower clearance."""
        c = self.clearance if math.isfinite(self.clearance) else math.inf
        return (0 if self.failed else 1, c)

    def to_dict(self, space: SearchSpace) -> dict[str, Any]:
        return {"sim": self.sim, "phase": self.phase, "origin": self.origin,
                "params": space.as_mapping(self.offsets), "outcome": self.outcome,
                "clearance": _finite(self.clearance), "culprit": self.culprit,
                "message": self.message, "metrics": {k: _finite(v) for k, v in self.metrics.items()},
                "scenario_hash": self.scenario_hash, "wall_time": round(self.wall_time, 6)}


@dataclass
class Failure:
    """A distinct failure: as found, and after shrinking toward the seed."""
    found: Candidate
    shrunk: Candidate
    shrink_sims: int = 0
    note: str = ""                # e.g. "shrink cap reached", "did not reproduce"


@dataclass
class SearchReport:
    seed_name: str
    seed_source: str | None
    subject: str
    subject_version: str | None
    strategy: str
    seed_value: int
    budget: int
    shrink_budget: int
    params: list[str]
    sims_used: int = 0
    shrink_sims: int = 0
    discarded: dict[str, int] = field(default_factory=dict)   # reason -> count
    skipped: int = 0              # repeats and mutants next to a known failure, redrawn without simulating
    candidates: list[Candidate] = field(default_factory=list)  # search + shrink sims, in order
    failures: list[Failure] = field(default_factory=list)
    interrupted: bool = False
    stop_reason: str = ""
    wall_time: float = 0.0
    episode_seed: int | None = None   # the run's base seed (--nav-seed) every episode used

    @property
    def discarded_total(self) -> int:
        return sum(self.discarded.values())

    @property
    def best(self) -> Candidate | None:
        search = [c for c in self.candidates if c.phase == "search"]
        return min(search, key=lambda c: c.fitness) if search else None

    @property
    def best_clearance(self) -> float:
        vals = [c.clearance for c in self.candidates if c.phase == "search" and math.isfinite(c.clearance)]
        return min(vals) if vals else math.nan

    def failures_by_outcome(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for f in self.failures:
            out[f.found.outcome] = out.get(f.found.outcome, 0) + 1
        return out


def _finite(v: Any) -> Any:
    return None if isinstance(v, float) and not math.isfinite(v) else v


# -- one simulation ---------------------------------------------------------------------------
class _Simulator:
    """Runs candidates against the subject and counts them; never raises (except _Stop)."""

    def __init__(self, space: SearchSpace, subject_factory, report: SearchReport, progress, stop,
                 episode_seed: int | None):
        self.space, self.factory, self.report = space, subject_factory, report
        self.progress, self.stop, self.episode_seed = progress, stop, episode_seed
        self.counts = {"search": 0, "shrink": 0}

    def simulate(self, offsets: Sequence[float], scenario: Scenario, phase: str, origin: str) -> Candidate:
        from ..harness.runner import run_scenario
        from ..scenario.model import content_hash

        self.counts[phase] += 1
        t0 = time.perf_counter()
        try:
            planner = self.factory()
            res = run_scenario(scenario, planner, seed=self.episode_seed)
        except KeyboardInterrupt:
            self.counts[phase] -= 1
            raise
        except Exception as exc:  # the harness itself failed: record, never raise inside Hypothesis
            cand = Candidate(self.counts[phase], phase, origin, tuple(offsets), "harness-error", math.nan,
                             "", f"{type(exc).__name__}: {exc}", {}, content_hash(scenario),
                             time.perf_counter() - t0, scenario)
        else:
            culprit = ""
            if res.collision is not None:
                culprit = res.collision.obstacle
            elif res.safety_stop is not None:
                culprit = res.safety_stop.obstacle
            else:
                culprit = res.metrics.min_clearance_obstacle
            if self.report.subject in ("", "?"):
                self.report.subject = res.subject or "?"
            if self.report.subject_version is None and res.subject_version:
                self.report.subject_version = res.subject_version
            cand = Candidate(self.counts[phase], phase, origin, tuple(offsets), res.outcome.value,
                             float(res.metrics.min_clearance), culprit, res.message,
                             res.metrics.as_dict(), content_hash(scenario), time.perf_counter() - t0, scenario)
        self.report.candidates.append(cand)
        if phase == "search":
            self.report.sims_used += 1
        else:
            self.report.shrink_sims += 1
        return cand

    def check_stop(self) -> None:
        if self.stop is not None and self.stop():
            self.report.interrupted = True
            self.report.stop_reason = self.report.stop_reason or "stopped by request"
            raise _Stop()


# -- archive and distinct failures -----------------------------------------------------------
class _Archive:
    """The best layouts so far, kept diverse: a newcomer within CROWDING_DISTANCE of a member
    replaces it only if fitter; otherwise it replaces the worst member if fitter than it."""

    def __init__(self, space: SearchSpace, size: int = ARCHIVE_SIZE):
        self.space, self.size, self.members = space, size, []

    def add(self, cand: Candidate) -> None:
        if cand.outcome == "harness-error":
            return
        for i, m in enumerate(self.members):
            if self.space.normalised_distance(m.offsets, cand.offsets) < CROWDING_DISTANCE:
                if cand.fitness < m.fitness:
                    self.members[i] = cand
                    self.members.sort(key=lambda c: c.fitness)
                return
        self.members.append(cand)
        self.members.sort(key=lambda c: c.fitness)
        del self.members[self.size:]


def is_duplicate(space: SearchSpace, cand: Candidate, kept: Sequence[Candidate]) -> bool:
    """Same outcome, same culprit obstacle and within DISTINCT_DISTANCE of a kept failure."""
    return any(k.outcome == cand.outcome and k.culprit == cand.culprit
               and space.normalised_distance(k.offsets, cand.offsets) < DISTINCT_DISTANCE for k in kept)


def is_near_failure(space: SearchSpace, offsets: Sequence[float], failures: Sequence[Failure]) -> bool:
    return any(space.normalised_distance(f.found.offsets, offsets) < DISTINCT_DISTANCE for f in failures)


# -- strategies -------------------------------------------------------------------------------
def _evolve(space: SearchSpace, sim: _Simulator, budget: int, seed_value: int, on_result) -> None:
    from hypothesis import HealthCheck, Phase, Verbosity, given, reject, settings, target
    from hypothesis import seed as hseed
    from hypothesis import strategies as st

    archive = _Archive(space)
    n = len(space)
    parts: dict[str, list[int]] = {}
    for i, p in enumerate(space.params):
        parts.setdefault(p.part, []).append(i)
    groups = list(parts.values())
    invalid_run = [0]
    counter = [0]
    simulated: set[tuple[float, ...]] = set()
    # operator statistics: [tries, new distinct failures] for uniform exploration and mutation
    stats = {"explore": [0, 0], "mutate": [0, 0]}

    def exploit_share() -> float:
        """Share of mutations: EXPLOIT at first, then following which operator has been finding
        new distinct failures (so where uniform sampling already fails often, the search does
        not fall behind it)."""
        (te, he), (tm, hm) = stats["explore"], stats["mutate"]
        if te + tm < 10:
            return EXPLOIT
        re_, rm = (he + 1) / (te + 2), (hm + 1) / (tm + 2)
        return min(0.85, max(0.15, rm / (re_ + rm)))

    def draw_candidate(data) -> tuple[tuple[float, ...], str]:
        # Every example draws the same choices whatever the archive holds (Hypothesis checks
        # that generation does not depend on external state); the archive only decides how
        # the drawn values are used. Uniform exploration and Gaussian steps come from a
        # Hypothesis-drawn Random (Hypothesis's own floats favour bounds and round values).
        pick = data.draw(st.integers(0, ARCHIVE_SIZE - 1), label="elite")   # shrinks toward the best
        k = data.draw(st.integers(0, 3), label="k")
        # One drawn integer seeds a Random, mixed with the example counter: Hypothesis often
        # repeats a draw (simplest values, mutations), and a repeated seed would repeat the
        # candidate and waste a simulation.
        drawn = data.draw(st.integers(0, 2**64 - 1), label="rng")
        counter[0] += 1
        rnd = random.Random(f"{seed_value}:{counter[0]}:{drawn}")
        used = sim.report.sims_used
        if used == 0:
            return space.zero(), "seed"
        warmup = used <= max(2, min(10, budget // 10))
        if warmup or not archive.members or rnd.random() >= exploit_share():
            return tuple(rnd.uniform(p.lo, p.hi) for p in space.params), "explore"
        failures = [f.found for f in sim.report.failures]
        if failures and rnd.random() < 0.5:
            parent = rnd.choice(failures)      # around a known failure: look for its neighbours
        else:
            parent = archive.members[pick % len(archive.members)]
        offsets = list(parent.offsets)
        # k = 0: every parameter moves; 1: one obstacle's (or pose's); 2-3: that many parameters
        if k == 0:
            idx = list(range(n))
        elif k == 1:
            idx = rnd.choice(groups)
        else:
            idx = sorted({rnd.randrange(n) for _ in range(k)})
        scale = rnd.choice(MUTATION_SCALES[1:] if parent.failed else MUTATION_SCALES)
        for i in idx:
            offsets[i] += rnd.gauss(0.0, 1.0) * scale * space.params[i].width
        if parent.failed:  # a failure's child must be a new failure, not the same one again
            i = rnd.choice(idx)
            jump = rnd.uniform(DISTINCT_DISTANCE, 3 * DISTINCT_DISTANCE) * space.params[i].width
            offsets[i] = parent.offsets[i] + (jump if rnd.random() < 0.5 else -jump)
        return space.clip(offsets), "mutate"

    def body(data):
        offsets, origin = draw_candidate(data)   # draw first: a stop must not change what is drawn
        sim.check_stop()
        if sim.report.sims_used >= budget:
            raise _Stop()
        scenario = space.apply(offsets)
        reason = invalid_reason(scenario)
        if reason is not None:
            key = reason.split(":")[0]
            sim.report.discarded[key] = sim.report.discarded.get(key, 0) + 1
            invalid_run[0] += 1
            if invalid_run[0] > MAX_INVALID_FACTOR * max(budget, 1):
                sim.report.stop_reason = (f"gave up after {invalid_run[0]} invalid candidates in a row: "
                                          "the search bounds are too wide for this seed, or every nearby layout fails already")
                raise _Stop()
            reject()
        key = tuple(round(v, 6) for v in offsets)
        if key in simulated or (origin == "mutate" and is_near_failure(space, offsets, sim.report.failures)):
            sim.report.skipped += 1   # would most likely repeat a known failure: not worth a simulation
            invalid_run[0] += 1
            reject()
        invalid_run[0] = 0
        simulated.add(key)
        cand = sim.simulate(offsets, scenario, "search", origin)
        archive.add(cand)
        before = len(sim.report.failures)
        on_result(cand)
        if origin in stats:
            stats[origin][0] += 1
            stats[origin][1] += len(sim.report.failures) - before
        clearance = cand.clearance if math.isfinite(cand.clearance) else 10.0
        target(-clearance + (10.0 if cand.failed else 0.0), label="fitness")

    # One Hypothesis run normally spends the whole budget (each simulated candidate is one
    # valid example, rejected ones are free); if Hypothesis stops early, run again with a
    # derived seed for the remainder.
    for round_no in range(8):
        remaining = budget - sim.report.sims_used
        if remaining <= 0:
            break
        prop = settings(max_examples=remaining, database=None, deadline=None,
                        phases=[Phase.generate, Phase.target], suppress_health_check=list(HealthCheck),
                        verbosity=Verbosity.quiet, derandomize=False, report_multiple_bugs=False,
                        print_blob=False)(hseed(seed_value + 7919 * round_no)(given(st.data())(body)))
        try:
            prop()
        except _Stop:
            pass
        if sim.report.stop_reason or sim.report.interrupted or sim.report.sims_used == budget - remaining:
            break


def _random(space: SearchSpace, sim: _Simulator, budget: int, seed_value: int, on_result) -> None:
    rng = random.Random(seed_value)
    invalid_run = 0
    while sim.report.sims_used < budget:
        sim.check_stop()
        offsets = tuple(rng.uniform(p.lo, p.hi) for p in space.params)
        scenario = space.apply(offsets)
        reason = invalid_reason(scenario)
        if reason is not None:
            key = reason.split(":")[0]
            sim.report.discarded[key] = sim.report.discarded.get(key, 0) + 1
            invalid_run += 1
            if invalid_run > MAX_INVALID_FACTOR * budget:
                sim.report.stop_reason = (f"gave up after {invalid_run} invalid candidates in a row: "
                                          "the search bounds are too wide for this seed")
                return
            continue
        invalid_run = 0
        on_result(sim.simulate(offsets, scenario, "search", "random"))


# -- shrinking --------------------------------------------------------------------------------
def shrink_failure(space: SearchSpace, sim: _Simulator, found: Candidate, cap: int) -> Failure:
    """Reduce ``found`` toward the seed with at most ``cap`` simulations (Hypothesis's shrinker
    on the offset vector, started from this failure): the result fails with the same outcome."""
    from hypothesis import Phase, Verbosity, find, settings
    from hypothesis.database import InMemoryExampleDatabase, choices_to_bytes
    from hypothesis.errors import NoSuchExample

    failure = Failure(found=found, shrunk=found)
    if cap <= 0 or not any(found.offsets):
        return failure
    best = [found]
    used = [0]
    db = InMemoryExampleDatabase()
    key = b"navsearch-shrink"
    db.save(key + b".secondary", choices_to_bytes(found.offsets))

    def still_fails(offsets) -> bool:
        offsets = tuple(offsets)
        if offsets == tuple(found.offsets) and used[0] > 0:
            return True
        sim.check_stop()
        if used[0] >= cap:
            failure.note = f"shrink cap of {cap} simulations reached"
            raise _Stop()
        scenario = space.apply(offsets)
        if invalid_reason(scenario) is not None:
            return False
        used[0] += 1
        cand = sim.simulate(offsets, scenario, "shrink", "shrink")
        ok = cand.outcome == found.outcome
        if ok and _simpler(offsets, best[0].offsets):
            best[0] = cand
        return ok

    try:
        find(offsets_strategy(space), still_fails, database_key=key,
             settings=settings(database=db, phases=[Phase.reuse, Phase.shrink], verbosity=Verbosity.quiet,
                               deadline=None, max_examples=max(cap, 1)))
    except _Stop:
        pass
    except NoSuchExample:
        failure.note = "did not reproduce when re-simulated: kept as found"
    failure.shrunk = best[0]
    failure.shrink_sims = used[0]
    return failure


def _simpler(a: Sequence[float], b: Sequence[float]) -> bool:
    """Fewer non-zero offsets, then smaller total |offset|: closer to the seed."""
    ka = (sum(1 for v in a if v), sum(abs(v) for v in a))
    kb = (sum(1 for v in b if v), sum(abs(v) for v in b))
    return ka < kb


# -- entry point -------------------------------------------------------------------------------
def run_search(seed: Scenario, subject_factory: Callable[[], Any], *, budget: int, seed_value: int = 0,
               strategy: str = "evolve", shrink_budget: int = DEFAULT_SHRINK_BUDGET,
               progress: Callable[[SearchReport], None] | None = None,
               stop: Callable[[], bool] | None = None, space: SearchSpace | None = None,
               subject: str = "", episode_seed: int | None = None) -> SearchReport:
    """Search for failures of ``subject_factory()`` planners around ``seed``.

    Exactly ``budget`` simulations of valid candidates (fewer only if interrupted or if the
    bounds leave almost no valid candidate, said in ``stop_reason``), then each distinct
    failure is shrunk with at most ``shrink_budget`` more simulations. ``progress(report)`` is
    called after each simulation; ``stop()`` returning True ends the search early (as does
    Ctrl-C): the report then keeps every failure found so far, unshrunk, with ``interrupted``.
    Deterministic given ``seed_value`` (and a deterministic subject).
    """
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown search strategy {strategy!r}; use one of {', '.join(STRATEGIES)}")
    if budget <= 0:
        raise ValueError(f"budget must be a positive number of simulations, got {budget}")
    space = space if space is not None else SearchSpace(seed)
    if not space.params:
        raise ValueError(f"the search space of seed {seed.name!r} is empty (every part frozen or bounds "
                         f"[0, 0]); widen its search: bounds")
    reason = invalid_reason(seed)
    if reason is not None:
        from ..core.errors import ScenarioError
        raise ScenarioError(f"the seed itself is not a valid scenario ({reason}): fix the seed first",
                            path=seed.source or seed.name)
    report = SearchReport(seed_name=seed.name, seed_source=seed.source, subject=subject or "?",
                          subject_version=None, strategy=strategy, seed_value=seed_value, budget=budget,
                          shrink_budget=shrink_budget, params=[p.name for p in space.params], episode_seed=episode_seed)
    sim = _Simulator(space, subject_factory, report, progress, stop, episode_seed)
    kept: list[Candidate] = []

    def on_result(cand: Candidate) -> None:
        if cand.failed and not is_duplicate(space, cand, kept):
            kept.append(cand)
            report.failures.append(Failure(found=cand, shrunk=cand))
        if progress is not None:
            progress(report)

    t0 = time.perf_counter()
    try:
        (_evolve if strategy == "evolve" else _random)(space, sim, budget, seed_value, on_result)
        for i, f in enumerate(report.failures):
            sim.check_stop()
            report.failures[i] = shrink_failure(space, sim, f.found, shrink_budget)
            if progress is not None:
                progress(report)
    except _Stop:
        pass  # stop() said so: check_stop marked the report interrupted
    except KeyboardInterrupt:
        report.interrupted = True
        report.stop_reason = "interrupted (Ctrl-C)"
    if report.interrupted:
        for f in report.failures:
            if f.shrink_sims == 0 and not f.note and any(f.found.offsets):
                f.note = "not shrunk: the search was interrupted"
    report.wall_time = time.perf_counter() - t0
    return report
