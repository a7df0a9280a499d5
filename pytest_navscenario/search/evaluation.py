"""Evaluating candidates: one simulation is a pure function of the candidate, and a ``Simulator``
numbers and records what an evaluator returns.

``evaluate_candidate(ctx, offsets, origin, run)`` builds the layout, runs its episode and reads it
(fitness.py) in any process; ``iter_candidates`` does a generation, in lockstep batches when the
subject can (harness/batch.py). ``Simulator`` is what the engine, the shrinker and the evaluators
of parallel.py and batched.py share: it numbers each candidate in its phase, adds it to the report,
tells the recorder and checks for a stop request (``Stop``). What else an evaluator may do is in
evaluators.py.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator, Sequence

from ..core.interrupts import deferred
from ..core.rates import Sprt
from ..core.seeds import repeat_seed
from ..scenario.model import Scenario
from .report import Candidate, Failure, Recorder, SearchReport
from .space import SearchSpace

DEFAULT_STUCK_AFTER = 15.0  # s without new ground covered: the episode ends as a stuck timeout (the
                            # longest stall a robot recovered from over the shipped seeds and the
                            # example suites x 3 planners: 14.5 s; benchmarks/check_stuck.py)


class Stop(BaseException):
    """Raised inside a Hypothesis run to end it at once (BaseException: Hypothesis does not
    treat it as a test failure, so nothing is replayed or shrunk)."""


@dataclass(frozen=True)
class EvalContext:
    """What evaluating a candidate needs besides its offsets (picklable for worker processes);
    ``hold`` the confirmation test (holding.py; None: one run decides) and its threshold."""
    space: SearchSpace
    subject_factory: Any
    episode_seed: int | None = None
    stuck_after: float | None = DEFAULT_STUCK_AFTER
    hold: Sprt | None = None
    hold_threshold: float = 0.0
    batch: int = 1        # candidates simulated together (harness/batch.py) by evaluate_candidates
    engine: str = "cpu"   # the batch engine that steps them (sim/batching/batch.py: "cpu" or "warp")

    def run_seed(self, run: int) -> int | None:
        """The base seed of noise run ``run`` (0: the search's own, the run's --nav-seed)."""
        return repeat_seed(self.episode_seed or 0, run) if run else self.episode_seed


_ROUTES: dict[int, Any] = {}


def _route(space: SearchSpace) -> Any:
    from .fitness import Route
    key = id(space)
    if key not in _ROUTES:
        _ROUTES.clear()
        _ROUTES[key] = (space, Route(space.seed))
    return _ROUTES[key][1]


Proposal = tuple  # (offsets, origin) from a strategy, or (offsets, origin, run) with a noise run


def unpack(proposal: Proposal) -> tuple[tuple[float, ...], str, int]:
    """(offsets, origin, run) of a proposal (run 0, the search's own noise, when it names none)."""
    offsets, origin, *run = proposal
    return tuple(offsets), origin, (run[0] if run else 0)


def evaluate_candidate(ctx: EvalContext, offsets: Sequence[float], origin: str, run: int = 0) -> Candidate:
    """Simulate one candidate under noise run ``run``; never raises for a harness failure
    (recorded as harness-error)."""
    from ..harness.runner import run_scenario

    scenario = ctx.space.apply(offsets)
    t0 = time.perf_counter()
    try:
        res = run_scenario(scenario, ctx.subject_factory(), seed=ctx.run_seed(run), stuck_after=ctx.stuck_after)
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # the harness itself failed: record, never raise inside the loop
        res = exc
    return _candidate(ctx, offsets, origin, scenario, res, t0, run)


def evaluate_candidates(ctx: EvalContext, proposals: Sequence[Proposal],
                        batching: Any = None) -> list[Candidate]:
    """``evaluate_candidate`` for each proposal, in order, the episodes run ``ctx.batch`` at a time
    in lockstep when the subject answers the batch protocol (harness/batch.py): the same
    candidates, bit for bit, wall times aside. ``batching`` (a harness.batch.Batching) counts how."""
    return list(iter_candidates(ctx, proposals, batching))


def iter_candidates(ctx: EvalContext, proposals: Sequence[Proposal],
                    batching: Any = None) -> Iterator[Candidate]:
    """``evaluate_candidates``'s candidates, each as soon as its episode is known (harness/batch.
    iter_batch: alone, one by one; in a batch, when the batch ends)."""
    from ..harness.batch import iter_batch

    proposals = [unpack(p) for p in proposals]
    scenarios = [ctx.space.apply(offsets) for offsets, _, _ in proposals]
    t0 = time.perf_counter()
    results = iter_batch(scenarios, ctx.subject_factory, seeds=[ctx.run_seed(run) for _, _, run in proposals],
                         stuck_after=ctx.stuck_after, batch=ctx.batch, call_factory=True, batching=batching,
                         engine=ctx.engine)
    for (offsets, origin, run), sc in zip(proposals, scenarios):
        try:
            res = next(results)
        except KeyboardInterrupt:
            raise
        except Exception as exc:   # the harness itself failed: every candidate left records it
            results = iter([exc] * len(scenarios))
            res = exc
        yield _candidate(ctx, offsets, origin, sc, res, t0, run)
        t0 = time.perf_counter()


def _candidate(ctx: EvalContext, offsets: Sequence[float], origin: str, scenario: Scenario, res: Any,
               t0: float, run: int = 0) -> Candidate:
    """The Candidate of an episode's result under noise run ``run`` (or of the exception the
    harness raised for it)."""
    from ..scenario.model import content_hash
    from .fitness import read_episode

    if not isinstance(res, Exception):
        try:
            reading, culprit = read_episode(res, _route(ctx.space))
        except KeyboardInterrupt:
            raise
        except Exception as exc:
            res = exc
    if isinstance(res, Exception):   # the harness itself failed: record, never raise inside the loop
        return Candidate(0, "", origin, tuple(offsets), "harness-error", math.nan, "",
                         f"{type(res).__name__}: {res}", {}, content_hash(scenario),
                         time.perf_counter() - t0, scenario, signature=("harness-error", "", 0, 0), run=run)
    cand = Candidate(0, "", origin, tuple(offsets), res.outcome.value, float(res.metrics.min_clearance),
                     culprit, res.message, res.metrics.as_dict(), content_hash(scenario),
                     time.perf_counter() - t0, scenario, reading.robustness, reading.signature,
                     reading.progress, reading.path, reading.closest, run)
    cand.metrics["subject"], cand.metrics["subject_version"] = res.subject, res.subject_version
    return cand


def serial_evaluator(ctx: EvalContext, proposals: Sequence[Proposal]) -> Iterator[Candidate]:
    """The default evaluator: one candidate after the other, in proposal order (with ``ctx.batch``
    > 1, the generation in one batch)."""
    if ctx.batch > 1:
        yield from iter_candidates(ctx, proposals)
        return
    for proposal in proposals:
        yield evaluate_candidate(ctx, *proposal)


Evaluator = Callable[[EvalContext, Sequence[Proposal]], Iterable[Candidate]]   # evaluators.Evaluator's call


class Simulator:
    """Numbers and records the candidates an evaluator returns; checks for a stop request; tells
    the recorder (if any) each shrink-phase candidate and each change of a failure."""

    def __init__(self, ctx: EvalContext, report: SearchReport, stop, evaluator: Evaluator | None = None,
                 recorder: Recorder | None = None):
        self.ctx, self.report, self.stop = ctx, report, stop
        self.evaluator = evaluator or serial_evaluator
        self.recorder = recorder
        self.counts = {"search": 0, "shrink": 0}

    def start(self, proposals: Sequence[Proposal], phase: str,
              then: Callable[[Candidate], None] | None = None) -> Iterator[Candidate]:
        """Hand ``proposals`` to the evaluator now (one on worker processes starts them at once);
        the iterator records and yields each candidate in proposal order as it is consumed.
        Recording a candidate and ``then(candidate)`` (the search's bookkeeping, which logs it)
        are one step an interrupt waits for: a candidate counted is a candidate logged."""
        results = iter(self.evaluator(self.ctx, list(proposals)))
        return self._recorded(results, phase, then)

    def _recorded(self, results: Iterator[Candidate], phase: str,
                  then: Callable[[Candidate], None] | None) -> Iterator[Candidate]:
        for cand in results:   # waiting for the next one may be interrupted; what follows may not
            with deferred():
                self.record(cand, phase)
                if then is not None:
                    then(cand)
            yield cand

    def run(self, proposals: Sequence[Proposal], phase: str) -> Iterator[Candidate]:
        """Evaluate ``proposals`` and yield each recorded candidate in proposal order."""
        yield from self.start(proposals, phase)

    def record(self, cand: Candidate, phase: str) -> Candidate:
        """Number ``cand`` in its phase and add it to the report (a shrink candidate is logged at
        once; a caller recording several holds interrupts around them: ``deferred``)."""
        self.counts[phase] += 1
        cand.sim, cand.phase = self.counts[phase], phase
        subject = cand.metrics.pop("subject", None)
        version = cand.metrics.pop("subject_version", None)
        if self.report.subject in ("", "?") and subject:
            self.report.subject = subject
        if self.report.subject_version is None and version:
            self.report.subject_version = version
        self.report.candidates.append(cand)
        if phase == "search":
            self.report.sims_used += 1
            self.report.confirm_sims += cand.run > 0
            if cand.failed and not self.report.first_failure:
                self.report.first_failure = cand.sim
        else:
            self.report.shrink_sims += 1
            self.tell_recorder("simulated", cand)   # search-phase ones: once their failure is known
        return cand

    def set_failure(self, index: int, failure: Failure) -> None:
        """Replace failure ``index`` (shrunk, or kept as found) and tell the recorder."""
        self.report.failures[index] = failure
        self.tell_recorder("failure", failure)

    def tell_recorder(self, event: str, *args: Any) -> None:
        """``recorder.<event>(report, *args)``, whole: an interrupt waits until it has written."""
        if self.recorder is not None:
            with deferred():
                getattr(self.recorder, event)(self.report, *args)

    def simulate(self, offsets: Sequence[float], phase: str, origin: str, run: int = 0) -> Candidate:
        return next(iter(self.run([(tuple(offsets), origin, run)], phase)))

    def check_stop(self) -> None:
        if self.stop is not None and self.stop():
            self.report.interrupted = True
            self.report.stop_reason = self.report.stop_reason or "stopped by request"
            raise Stop()
