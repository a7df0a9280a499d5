"""Failure search around a seed scenario: the ask/tell loop and ``run_search``.

``run_search(seed, subject_factory, budget=..., seed_value=...)`` (or ``run_search(seed,
subject_factory, config=SearchConfig(...))``) simulates exactly ``budget`` valid candidates
(invalid ones -- obstacles on the start/goal footprint, no path at all -- are discarded before
simulation and counted separately), keeps the *distinct* failures and shrinks them toward the seed
within a shrink budget of their own (shrinker.py: a share of the search's budget, default 25 %,
handed out before any shrinking starts, most important failures first, so each failure's
shrinking is an independent job with a fixed cap).

The loop is ask/tell: a strategy (strategies/, protocol.Strategy) proposes a generation of
candidates, they are evaluated -- by ``evaluation.evaluate_candidate``, a pure function of the
candidate, in any order, in any number of chunks or processes -- and the results are told back in
proposal order. A generation's size and the strategy's ``lag`` (how many generations later it
learns a generation's results; 1: generation g+2 is drawn knowing generations up to g) belong to
the strategy, never to the evaluator, so the same search seed gives the same candidates, failures
and frozen files however many are evaluated at once. The lag keeps work in flight: while the
strategy draws the next generation and while the slowest episode of one generation ends, worker
processes already evaluate the next one. A failure counts once confirmation runs decide it holds
(confirming.py, holding.py).

Distinct failures: two failures are the same when they have the same cause signature
(fitness.py: outcome, culprit, where the culprit lies along the route, how far the robot got),
which is also how the frozen files are told apart.

Split as Hypothesis splits its engine: the report types (report.py), evaluation and the
``Simulator`` (evaluation.py), confirmation (confirming.py) and shrinking (shrinker.py) are their
own modules; the names they define are re-exported here for older imports.
"""
from __future__ import annotations

import dataclasses
import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Sequence

from ..core.interrupts import deferred, first_signal
from ..scenario.model import Scenario
from . import strategies as _strategies
from .confirming import Confirming
from .evaluation import (DEFAULT_STUCK_AFTER, EvalContext, Proposal, Simulator, Stop, evaluate_candidate,
                         evaluate_candidates, iter_candidates, serial_evaluator, unpack)
from .evaluators import Evaluator, as_evaluator
from .report import Candidate, Failure, Recorder, SearchReport
from .shrinker import (DEFAULT_SHRINK_BUDGET, MIN_SHRINK_SIMS, SEVERITY, ShrinkBudget, _note_unshrunk,
                       shrink_all, shrink_failure, shrink_order, shrink_plan, shrink_status)
from .space import SearchSpace, invalid_reason

STRATEGIES = _strategies.names()   # the registry's names (strategies/__init__.py), the default first
DISTINCT_DISTANCE = 0.1    # kept for is_near_failure (fraction of each parameter's range)
MAX_INVALID_FACTOR = 50    # give up after budget * this many discarded candidates in a row

__all__ = ["run_search", "SearchConfig", "STRATEGIES", "Candidate", "Failure", "SearchReport", "Recorder",
           "EvalContext", "Evaluator", "Proposal", "Simulator", "evaluate_candidate", "evaluate_candidates",
           "iter_candidates", "serial_evaluator", "unpack", "ShrinkBudget", "shrink_all", "shrink_failure",
           "shrink_order", "shrink_plan", "shrink_status", "is_duplicate", "is_near_failure",
           "DEFAULT_SHRINK_BUDGET", "DEFAULT_STUCK_AFTER", "MIN_SHRINK_SIMS", "SEVERITY"]


def is_duplicate(space: SearchSpace, cand: Candidate, kept: Sequence[Candidate]) -> bool:
    """Same cause signature as a kept failure (fitness.py): the same way of failing (public API;
    run_search itself keeps a set of the signatures seen)."""
    return any(k.signature == cand.signature for k in kept)


def is_near_failure(space: SearchSpace, offsets: Sequence[float], failures: Sequence[Failure]) -> bool:
    """Within DISTINCT_DISTANCE of a failure's offsets on every parameter (kept for the public
    API; the search itself no longer calls it: distinct failures are told apart by signature)."""
    return any(space.normalised_distance(f.found.offsets, offsets) < DISTINCT_DISTANCE for f in failures)


# -- the ask/tell loop ----------------------------------------------------------------------------
def _search_loop(strategy: _strategies.Strategy, sim: Simulator, budget: int,
                 on_result: Callable[[Candidate], None], confirming: Confirming | None = None) -> None:
    """Ask generations, evaluate them, tell the results back in order, until the budget is spent.

    With the strategy's ``lag`` L (read before each ask: it may change), up to L + 1 generations
    are in flight: the next one is asked for (and handed to the evaluator) before the results of
    the last L are told. Serial or on workers, the strategy sees the same results at the same
    point, so the search is the same. Each generation begins with the confirmation runs the
    failures under test need next (``Confirming``: they come out of the budget, before new
    candidates); the strategy is asked for the rest, less what the failures under test may still
    need, and told only its own candidates' results."""
    report = sim.report
    in_flight: deque[tuple[Iterator[Candidate], bool]] = deque()   # (results, the strategy's generation?)
    planned, asking = report.sims_used, True
    new_in_flight = [0]   # the strategy's candidates handed over, results not yet read
    while True:
        while len(in_flight) <= max(0, int(strategy.lag)) and planned < budget:
            sim.check_stop()
            confirm = confirming.requests(budget - planned) if confirming is not None else []
            room = budget - planned - len(confirm) - (confirming.reserve(new_in_flight[0]) if confirming is not None else 0)
            proposals: list = []
            if asking and room > 0:
                proposals = _ask(strategy, room)
                if not proposals:
                    report.stop_reason = report.stop_reason or "the strategy had no new candidate to propose"
                    asking = False
            if not confirm and not proposals:
                break   # nothing to run now: wait for what is in flight (or end)
            planned += len(confirm) + len(proposals)
            new_in_flight[0] += len(proposals)
            in_flight.append((sim.start(confirm + proposals, "search", then=on_result), bool(proposals)))
        if not in_flight:
            break
        _tell_oldest(strategy, sim, budget, in_flight.popleft(), new_in_flight)


def _ask(strategy: _strategies.Strategy, room: int) -> list[Proposal]:
    """The strategy's next generation as proposals of run 0 ([] when it has none or gave up: it
    set stop_reason; what is in flight still counts)."""
    try:
        with deferred():
            return [(tuple(o), origin, 0) for o, origin in strategy.ask(room)[:room]]
    except _strategies.GaveUp:
        return []


def _tell_oldest(strategy: _strategies.Strategy, sim: Simulator, budget: int,
                 flight: tuple[Iterator[Candidate], bool], new_in_flight: list[int]) -> None:
    """Read the oldest generation in flight (each candidate recorded and logged as one step) and
    tell the strategy its own candidates' results."""
    batch, asked = flight
    results = []
    for cand in batch:
        if cand.run == 0:
            results.append(cand)
            new_in_flight[0] -= 1
        if sim.report.sims_used < budget:
            sim.check_stop()
    if asked:
        strategy.tell(results)


# -- entry point -------------------------------------------------------------------------------
@dataclass
class SearchConfig:
    """Everything ``run_search`` takes besides the seed and the subject (see run_search)."""
    budget: int
    seed_value: int = 0
    strategy: str = "evolve"
    shrink_budget: "ShrinkBudget | int | str" = DEFAULT_SHRINK_BUDGET
    progress: Callable[[SearchReport], None] | None = None
    stop: Callable[[], bool] | None = None
    space: SearchSpace | None = None
    subject: str = ""
    episode_seed: int | None = None
    stuck_after: float | None = DEFAULT_STUCK_AFTER
    evaluator: "Evaluator | Callable | None" = None
    recorder: Recorder | None = None
    hold: float | None = None
    batch: int = 1
    engine: str = "cpu"


def _check_inputs(seed: Scenario, strategy: str, budget: int, space: SearchSpace) -> None:
    if strategy not in _strategies.STRATEGIES:
        raise ValueError(f"unknown search strategy {strategy!r}; use one of {', '.join(_strategies.names())}")
    if budget <= 0:
        raise ValueError(f"budget must be a positive number of simulations, got {budget}")
    if not space.params:
        raise ValueError(f"the search space of seed {seed.name!r} is empty (every part frozen or bounds "
                         f"[0, 0]); widen its search: bounds")
    reason = invalid_reason(seed)
    if reason is not None:
        from ..core.errors import ScenarioError
        raise ScenarioError(f"the seed itself is not a valid scenario ({reason}): fix the seed first",
                            path=seed.source or seed.name)


def _early_shrink(shrink: ShrinkBudget, budget: int) -> tuple[int, int]:
    """(cap, how many failures) an evaluator may start shrinking while the search goes on: every
    cap shrink_plan gives is at least this one (per failure: exactly it), and at most this many
    failures get one, so work begun early is rarely thrown away (a failure the plan gives no cap)."""
    if shrink.per_failure is not None:
        return shrink.per_failure, budget
    total = shrink.total(budget, 0)
    return min(MIN_SHRINK_SIMS, total), max(1, total // MIN_SHRINK_SIMS)


def run_search(seed: Scenario, subject_factory: Callable[[], Any], config: SearchConfig | None = None,
               **options: Any) -> SearchReport:
    """Search for failures of ``subject_factory()`` planners around ``seed``; ``config`` a
    ``SearchConfig``, or its fields given as keywords (``budget=100, seed_value=0, ...``).

    Exactly ``budget`` simulations of valid candidates (fewer only if interrupted or if the
    bounds leave almost no valid candidate, said in ``stop_reason``), then the distinct failures
    are shrunk within ``shrink_budget`` more simulations: a share of the budget (``"25%"``, the
    default; ``0``: no shrinking) shared out most important failure first (``shrink_plan``), or
    the old form, a whole number N of simulations per failure. ``progress(report)`` is
    called after each simulation; ``stop()`` returning True ends the search early (as does
    Ctrl-C): the report then keeps every failure found so far, unshrunk, with ``interrupted``.
    ``stuck_after`` (s, None = off) ends an episode early as a timeout when the robot covers no
    new ground. ``evaluator(ctx, proposals)`` evaluates a generation (default: serially); an
    ``evaluation.Evaluator`` may also shrink the failures itself, begin shrinking early and
    discard what is in flight, as the worker-process one in search/parallel.py does; the result
    does not depend on the evaluator.
    ``batch`` > 1 simulates each generation's candidates together, in lockstep, when the subject
    answers the batch protocol (harness/batch.py): the same search, faster; search/batched.py's
    ``batch_evaluator`` also batches the generations in flight together and the failures' shrinks.
    ``engine`` names the batch engine ("cpu"; "warp": MuJoCo Warp, sim/batching/warp_engine.py, whose
    trajectories agree with the CPU's within a tolerance, not bit for bit).
    ``recorder`` (``Recorder``) is told every candidate and failure as the search goes, so that a
    search killed at any moment has written what it found (search/freeze.py: ``SearchRecorder``).
    ``hold`` (default holding.DEFAULT_HOLD, 0.9): a failure counts (is distinct, shrunk, frozen) only
    when a sequential test over confirmation runs under fresh noise seeds decides that it fails
    with at least this probability (holding.py); the confirmation runs are simulations of the
    budget, and a shrink step must hold too (its runs come out of the shrink budget). A seed
    without randomness needs none (one run decides), nor does ``hold=0`` (every failure counts).
    Deterministic given ``seed_value`` (and a deterministic subject).
    """
    if config is None:
        config = SearchConfig(**options)
    elif options:
        config = dataclasses.replace(config, **options)
    search = _Search(seed, subject_factory, config)
    search.run()
    return search.report


class _Search:
    """One run of ``run_search``: the report, the strategy, the confirmation state and the hooks
    that tie them together (what a candidate's result sets off)."""

    def __init__(self, seed: Scenario, subject_factory: Callable[[], Any], config: SearchConfig):
        from ..scenario.model import randomness
        from .holding import DEFAULT_HOLD, hold_test

        c = self.config = config
        space = self.space = c.space if c.space is not None else SearchSpace(seed)
        _check_inputs(seed, c.strategy, c.budget, space)
        self.shrink = ShrinkBudget.parse(c.shrink_budget)
        hold = DEFAULT_HOLD if c.hold is None else float(c.hold)
        test = hold_test(hold)   # ValueError for a threshold outside [0, 1)
        noisy = randomness(space.seed)
        self.report = SearchReport(seed_name=seed.name, seed_source=seed.source, subject=c.subject or "?",
                                   subject_version=None, strategy=c.strategy, seed_value=c.seed_value,
                                   budget=c.budget, shrink_budget=str(c.shrink_budget),
                                   params=[p.name for p in space.params], episode_seed=c.episode_seed,
                                   hold=hold, randomness=noisy)
        self.ctx = EvalContext(space, subject_factory, c.episode_seed, c.stuck_after, test if noisy else None, hold,
                               batch=c.batch, engine=c.engine)
        self.evaluator = as_evaluator(c.evaluator)
        self.sim = Simulator(self.ctx, self.report, c.stop, self.evaluator, c.recorder)
        self.strategy = _strategies.make_strategy(c.strategy, space, self.report, c.budget, c.seed_value)
        self.early_cap, self.early_count = _early_shrink(self.shrink, c.budget)
        self.confirming = Confirming(self.ctx, self.report, "exact" if test is not None else "off", self.decided)

    # -- what a result sets off
    def holds(self, failure: Failure) -> None:
        """``failure`` holds: it counts (and may begin shrinking now, on an evaluator that can)."""
        self.report.failures.append(failure)
        if self.evaluator.shrinks_early and self.early_cap > 0 and any(failure.found.offsets) \
                and len(self.report.failures) <= self.early_count:
            self.evaluator.start_shrink(self.sim.ctx, failure.found, self.early_cap, estimate=failure.estimate)

    def decided(self, failure: Failure) -> None:
        """A failure's confirmation test decided: it holds, or the next candidate failing its way is tried."""
        self.sim.tell_recorder("failure", failure)
        self.strategy.confirmed(failure.found, failure.estimate)
        if failure.status == "confirmed":
            self.holds(failure)
            return
        self.report.rejected.append(failure)
        nxt = self.confirming.next_aside(failure)   # the next candidate that failed this way, if any
        if nxt is not None:
            self.sim.tell_recorder("failure", nxt)

    def on_result(self, cand: Candidate) -> None:
        """Book a search-phase candidate: confirmation, a new failure, the recorder, progress."""
        if cand.run:
            self.confirming.result(cand)
        else:
            self.confirming.counted(cand)
        if not cand.run and cand.failed:
            failure = self.confirming.failed(cand)
            if failure is not None:
                self.sim.tell_recorder("failure", failure)   # on disk before it is logged
                if failure.status == "confirmed":            # no test to pass: it holds at once
                    self.strategy.confirmed(failure.found, failure.estimate)
                    self.holds(failure)
        self.sim.tell_recorder("simulated", cand)
        self.report.under_test = len(self.confirming.pending)
        if self.config.progress is not None:
            self.config.progress(self.report)

    def close_confirming(self) -> None:
        for failure in self.confirming.close(self.report.interrupted):
            self.report.unconfirmed.append(failure)
            self.sim.tell_recorder("failure", failure)
        self.report.under_test = 0

    # -- the phases
    def run(self) -> None:
        report, t0 = self.report, time.perf_counter()
        try:
            self.sim.tell_recorder("start")
            _search_loop(self.strategy, self.sim, self.config.budget, self.on_result,
                         self.confirming if self.ctx.hold is not None else None)
            self.close_confirming()
            self.shrink_phase()
        except (Stop, _strategies.GaveUp):
            pass  # stop() said so, or the strategy gave up (stop_reason says why)
        except KeyboardInterrupt:
            report.interrupted = True
            report.stop_reason = f"interrupted ({first_signal() or 'Ctrl-C'})"
        finally:
            self.finish(t0)

    def shrink_phase(self) -> None:
        """Share the shrink budget out (shrink_plan) and shrink the failures it reaches."""
        report = self.report
        report.shrink_total = self.shrink.total(self.config.budget, len(report.failures))
        caps = shrink_plan(report.failures, report.shrink_total, self.shrink)
        _note_unshrunk(report, caps, self.shrink)
        for i, cap in enumerate(caps):   # kept as found: final now
            if cap <= 0:
                self.sim.set_failure(i, dataclasses.replace(report.failures[i], status="unshrunk"))
        self.evaluator.shrink_failures(self.sim, caps, self.config.progress)

    def finish(self, t0: float) -> None:
        """Whatever ended the search: drop work in flight, close confirmation, say why a failure was
        not shrunk, and tell the recorder (what was found stays on disk)."""
        report = self.report
        self.evaluator.discard()   # jobs still in flight if it ended early
        if self.confirming.pending:   # cut short during the search phase
            report.interrupted = True
            self.close_confirming()
        batching = self.evaluator.batching
        if batching is not None and batching.batched:
            report.batching = batching.describe()
        if report.interrupted:
            for f in report.failures:
                if f.shrink_sims == 0 and not f.note and any(f.found.offsets):
                    f.note = "not shrunk: the search was interrupted"
        report.wall_time = time.perf_counter() - t0
        self.sim.tell_recorder("finish")
