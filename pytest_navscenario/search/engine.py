"""Failure search around a seed scenario: an ask/tell loop, shrinking, the report.

``run_search(seed, subject_factory, budget=..., seed_value=...)`` simulates exactly ``budget``
valid candidates (invalid ones -- obstacles on the start/goal footprint, no path at all --
are discarded before simulation and counted separately), keeps the *distinct* failures and
shrinks them toward the seed within a shrink budget of their own: a share of the search's
budget (default 25 %), handed out before any shrinking starts, most important failures first
(``shrink_plan``), so each failure's shrinking is an independent job with a fixed cap.

The loop is ask/tell: a strategy (strategies.py) proposes a generation of candidates, they are
evaluated -- by ``evaluate_candidate``, a pure function of the candidate, in any order, in any
number of chunks or processes -- and the results are told back in proposal order. A
generation's size and the strategy's ``lag`` (how many generations later it learns a
generation's results; 1: generation g+2 is drawn knowing generations up to g) belong to the
strategy, never to the evaluator, so the same search seed gives the same candidates, failures
and frozen files however many are evaluated at once. The lag keeps work in flight: while the
strategy draws the next generation and while the slowest episode of one generation ends, worker
processes already evaluate the next one.

Distinct failures: two failures are the same when they have the same cause signature
(fitness.py: outcome, culprit, where the culprit lies along the route, how far the robot got),
which is also how the frozen files are told apart.
"""
from __future__ import annotations

import contextlib
import dataclasses
import math
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Iterator, Protocol, Sequence

from ..core.interrupts import deferred, first_signal
from ..core.rates import Sprt
from ..core.seeds import repeat_seed
from ..scenario.model import Scenario
from .holding import Estimate, decide
from .space import FLAG_ON, SearchSpace, invalid_reason, offsets_strategy

STRATEGIES = ("evolve", "random", "hillclimb")
DISTINCT_DISTANCE = 0.1    # kept for is_near_failure (fraction of each parameter's range)
DEFAULT_SHRINK_BUDGET = "25%"   # of the search budget, for the whole shrink phase
MIN_SHRINK_SIMS = 10       # a failure given a share of the shrink budget gets at least this many
SEVERITY = ("collision", "fall", "subject-error", "safety-stop", "timeout")   # shrunk first .. last
DEFAULT_STUCK_AFTER = 15.0  # s without new ground covered: the episode ends as a stuck timeout (the
                            # longest stall a robot recovered from over the shipped seeds and the
                            # example suites x 3 planners: 14.5 s; benchmarks/check_stuck.py)
MAX_INVALID_FACTOR = 50    # give up after budget * this many discarded candidates in a row


class _Stop(BaseException):
    """Raised inside a Hypothesis run to end it at once (BaseException: Hypothesis does not
    treat it as a test failure, so nothing is replayed or shrunk)."""


@dataclass
class Candidate:
    """One simulated candidate."""
    sim: int                      # 1-based simulation number within its phase
    phase: str                    # "search" or "shrink"
    origin: str                   # seed / explore / mutate / place / insert / random / climb / shrink
    offsets: tuple[float, ...]
    outcome: str                  # Outcome value, or "harness-error" if the simulation itself failed
    clearance: float              # metrics.min_clearance (nan on harness error)
    culprit: str                  # obstacle hit / stopped for / nearest
    message: str
    metrics: dict[str, Any]
    scenario_hash: str
    wall_time: float
    scenario: Scenario | None = field(default=None, repr=False, compare=False)
    robustness: float = math.inf  # fitness.py: < 0 failed, small = near a failure
    signature: tuple = ()         # fitness.py: the cause signature
    progress: float = 0.0         # 0..1 along the seed's route where the episode ended
    path: tuple = field(default=(), repr=False)      # robot centre samples (x, y)
    closest: tuple = field(default=(), repr=False)   # (t, x, y) of the closest approach
    run: int = 0                  # noise run: 0 the search's own, k >= 1 the k-th confirmation run

    @property
    def failed(self) -> bool:
        return self.outcome not in ("success", "harness-error")

    @property
    def fitness(self) -> tuple[int, float]:
        """Smaller is better: failures first, then lower robustness (closer to failing)."""
        r = self.robustness if math.isfinite(self.robustness) else math.inf
        return (0 if self.failed else 1, r)

    def to_dict(self, space: SearchSpace) -> dict[str, Any]:
        return {"sim": self.sim, "phase": self.phase, "origin": self.origin,
                "params": space.as_mapping(self.offsets), "outcome": self.outcome,
                "clearance": _finite(self.clearance), "culprit": self.culprit,
                "message": self.message, "metrics": {k: _finite(v) for k, v in self.metrics.items()},
                "scenario_hash": self.scenario_hash, "wall_time": round(self.wall_time, 6),
                "robustness": _finite(round(self.robustness, 6)), "signature": list(self.signature),
                "run": self.run}


@dataclass
class Failure:
    """A distinct failure: as found, and after shrinking toward the seed.

    ``status`` says how far the search got with it (and is written in its frozen file's
    provenance): "found" (failed once: not yet confirmed nor shrunk; the search was still running,
    or was cut short, before it was done with it), "confirmed" (it holds under the scenario's
    randomness, holding.py; not yet shrunk), "shrunk" (final: shrunk toward the seed, still
    holding), "unshrunk" (final: kept as found, ``note`` says why); or, not frozen, "rejected" (it
    does not hold: a knife-edge) and "unconfirmed" (the budget ran out before the test decided).
    ``estimate`` is what the confirmation runs of its current layout (``shrunk``) showed."""
    found: Candidate
    shrunk: Candidate
    shrink_sims: int = 0
    note: str = ""                # e.g. "shrink cap reached", "did not reproduce"
    status: str = "found"
    estimate: Estimate = field(default_factory=lambda: Estimate(decision="off", threshold=0.0))

    @property
    def key(self) -> int:
        """Names the failure for the whole search: the simulation that found it."""
        return self.found.sim


@dataclass
class SearchReport:
    seed_name: str
    seed_source: str | None
    subject: str
    subject_version: str | None
    strategy: str
    seed_value: int
    budget: int
    shrink_budget: "int | str"    # as given: "25%" (share of the budget) or N (per failure, the old form)
    params: list[str]
    sims_used: int = 0
    shrink_sims: int = 0
    shrink_total: int = 0         # simulations the shrink phase was allowed (shrink_plan's total)
    discarded: dict[str, int] = field(default_factory=dict)   # reason -> count
    # (simulations recorded by then, reason) of each discarded candidate: when the search spent
    # its draws on invalid layouts (the search report's chart)
    discard_log: list[tuple[int, str]] = field(default_factory=list)
    skipped: int = 0              # repeats of a simulated candidate, redrawn without simulating
    candidates: list[Candidate] = field(default_factory=list)  # search + shrink sims, in order
    failures: list[Failure] = field(default_factory=list)     # distinct failures that hold, in order confirmed
    hold: float = 0.0             # the failure probability a failure must show to count (0: one run counts)
    randomness: tuple[str, ...] = ()   # what varies between runs of the seed (scenario.model.randomness)
    confirm_sims: int = 0         # of sims_used: confirmation runs (holding.py)
    rejected: list[Failure] = field(default_factory=list)     # failed once, did not hold (knife-edges)
    unconfirmed: list[Failure] = field(default_factory=list)  # the test undecided when the search ended
    under_test: int = 0           # failures being confirmed now (the live progress line)
    interrupted: bool = False
    stop_reason: str = ""
    wall_time: float = 0.0
    episode_seed: int | None = None   # the run's base seed (--nav-seed) every episode used
    first_failure: int = 0            # simulation number of the first failing candidate (0: none)
    batching: str = ""                # how the simulations ran in batches (search/batched.py), or ""

    @property
    def discarded_total(self) -> int:
        return sum(self.discarded.values())

    def _scan(self) -> tuple:
        """(best, lowest clearance, lowest robustness) of the search phase, updated with the
        candidates added since the last call: the live progress line asks after every simulation,
        and a rescan would make a search quadratic in its budget."""
        cache = self.__dict__.get("_bests")
        if cache is None or cache[0] > len(self.candidates):
            cache = (0, None, math.nan, math.nan)
        n, best, clear, rob = cache
        for c in self.candidates[n:]:
            if c.phase != "search":
                continue
            if best is None or c.fitness < best.fitness:
                best = c
            if math.isfinite(c.clearance) and not c.clearance >= clear:
                clear = c.clearance
            if math.isfinite(c.robustness) and not c.robustness >= rob:
                rob = c.robustness
        self.__dict__["_bests"] = (len(self.candidates), best, clear, rob)
        return best, clear, rob

    @property
    def best(self) -> Candidate | None:
        return self._scan()[0]

    @property
    def best_clearance(self) -> float:
        return self._scan()[1]

    @property
    def best_robustness(self) -> float:
        return self._scan()[2]

    def failures_by_outcome(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for f in self.failures:
            out[f.found.outcome] = out.get(f.found.outcome, 0) + 1
        return out


def _finite(v: Any) -> Any:
    return None if isinstance(v, float) and not math.isfinite(v) else v


# -- one simulation: a pure function of the candidate (any process may run it) -----------------
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


Evaluator = Callable[[EvalContext, Sequence[Proposal]], Iterable[Candidate]]


class Recorder(Protocol):
    """What ``run_search(..., recorder=...)`` tells while the search runs, so that what it found is
    on disk at every moment (search/freeze.py: ``SearchRecorder``). Each call is made whole: a
    Ctrl-C waits until it returns. The order: ``start``; per simulated candidate, first
    ``failure`` if it is a new failure (status "found"), then ``simulated``; ``failure`` again
    whenever a failure changes (Failure.status: confirmed, rejected, shrunk, ...); ``finish`` last,
    also when the search was cut short."""

    def start(self, report: SearchReport) -> None: ...
    def simulated(self, report: SearchReport, cand: Candidate) -> None: ...
    def failure(self, report: SearchReport, failure: Failure) -> None: ...
    def finish(self, report: SearchReport) -> None: ...


class _Simulator:
    """Numbers and records the candidates an evaluator returns; checks for a stop request; tells
    the recorder (if any) each shrink-phase candidate and each change of a failure."""

    def __init__(self, ctx: EvalContext, report: SearchReport, stop, evaluator: Evaluator | None = None,
                 recorder: "Recorder | None" = None):
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
            raise _Stop()


def is_duplicate(space: SearchSpace, cand: Candidate, kept: Sequence[Candidate]) -> bool:
    """Same cause signature as a kept failure (fitness.py): the same way of failing (public API;
    run_search itself keeps a set of the signatures seen)."""
    return any(k.signature == cand.signature for k in kept)


def is_near_failure(space: SearchSpace, offsets: Sequence[float], failures: Sequence[Failure]) -> bool:
    """Within DISTINCT_DISTANCE of a failure's offsets on every parameter (kept for the public
    API; the search itself no longer calls it: distinct failures are told apart by signature)."""
    return any(space.normalised_distance(f.found.offsets, offsets) < DISTINCT_DISTANCE for f in failures)


# -- the ask/tell loop ----------------------------------------------------------------------------
def _search_loop(strategy: Any, sim: _Simulator, budget: int, on_result: Callable[[Candidate], None],
                 confirming: "_Confirming | None" = None) -> None:
    """Ask generations, evaluate them, tell the results back in order, until the budget is spent.

    With the strategy's ``lag`` L (read before each ask: it may change), up to L + 1 generations
    are in flight: the next one is asked for (and handed to the evaluator) before the results of
    the last L are told. Serial or on workers, the strategy sees the same results at the same
    point, so the search is the same. Each generation begins with the confirmation runs the
    failures under test need next (``_Confirming``: they come out of the budget, before new
    candidates); the strategy is asked for the rest, less what the failures under test may still
    need, and told only its own candidates' results."""
    from .strategies import GaveUp

    report = sim.report
    in_flight: deque[tuple[Iterator[Candidate], bool]] = deque()   # (results, the strategy's generation?)
    planned, asking = report.sims_used, True
    new_in_flight = 0   # the strategy's candidates handed over, results not yet read
    while True:
        while len(in_flight) <= max(0, int(getattr(strategy, "lag", 0))) and planned < budget:
            sim.check_stop()
            confirm = confirming.requests(budget - planned) if confirming is not None else []
            room = budget - planned - len(confirm) - (confirming.reserve(new_in_flight) if confirming is not None else 0)
            proposals: list = []
            if asking and room > 0:
                try:
                    with deferred():
                        proposals = [(tuple(o), origin, 0) for o, origin in strategy.ask(room)[:room]]
                except GaveUp:   # the strategy set stop_reason; what is in flight still counts
                    proposals = []
                if not proposals:
                    report.stop_reason = report.stop_reason or "the strategy had no new candidate to propose"
                    asking = False
            if not confirm and not proposals:
                break   # nothing to run now: wait for what is in flight (or end)
            planned += len(confirm) + len(proposals)
            new_in_flight += len(proposals)
            in_flight.append((sim.start(confirm + proposals, "search", then=on_result), bool(proposals)))
        if not in_flight:
            break
        results = []
        batch, asked = in_flight.popleft()
        for cand in batch:   # each recorded and told to on_result (logged) as one step
            if cand.run == 0:
                results.append(cand)
                new_in_flight -= 1
            if report.sims_used < budget:
                sim.check_stop()
        if asked:
            strategy.tell(results)


class _Confirming:
    """The failures of the search phase under confirmation (holding.py), oldest first: which
    confirmation runs to ask for next, and what their results decide.

    A candidate that fails in a way no failure holds yet becomes a failure "found"; with a test
    (the seed has randomness and the threshold is not 0) it waits for its confirmation runs, else
    it holds at once. While one failure of a way of failing is under test, the first other
    candidate failing that way is kept aside and tried next if the first is rejected; a way of
    failing rejected MAX_REJECTIONS times is not tried again. ``on_decided(failure)`` is called
    when a failure holds or is rejected."""

    def __init__(self, ctx: EvalContext, report: SearchReport, exact: str, on_decided: Callable[[Failure], None]):
        from .holding import MAX_REJECTIONS

        self.test, self.exact, self.report = ctx.hold, exact, report
        self.threshold = ctx.hold_threshold
        self.on_decided = on_decided
        self.pending: list[Failure] = []
        self.flight: dict[int, int] = {}            # failure key -> runs asked for, results not yet in
        self.by_offsets: dict[tuple, Failure] = {}  # the layout under test -> its failure
        self.aside: dict[tuple, Candidate] = {}     # signature -> a later candidate failing that way
        self.held: set[tuple] = set()
        self.rejections: dict[tuple, int] = {}
        self.max_rejections = MAX_REJECTIONS
        self.seen = self.begun = 0    # the strategy's candidates read, failures begun (reserve's rate)

    def counted(self, cand: Candidate) -> None:
        """A strategy's candidate came back (the rate of new failures, for ``reserve``)."""
        self.seen += 1

    def failed(self, cand: Candidate) -> Failure | None:
        """A search candidate failed: the new failure it starts (None: a way of failing known)."""
        sig = cand.signature
        if sig in self.held or self.rejections.get(sig, 0) >= self.max_rejections:
            return None
        if any(f.found.signature == sig for f in self.pending):
            self.aside.setdefault(sig, cand)
            return None
        return self._begin(cand)

    def _begin(self, cand: Candidate) -> Failure:
        self.begun += 1
        failure = Failure(found=cand, shrunk=cand, estimate=Estimate(threshold=self.threshold))
        if self.test is None:
            failure.estimate.decision = self.exact
            failure.status = "confirmed"
            self.held.add(cand.signature)
        else:
            self.pending.append(failure)
            self.by_offsets[tuple(cand.offsets)] = failure
        return failure

    def requests(self, room: int) -> list[Proposal]:
        """The confirmation runs to start now, oldest failure first: for each failure with no run
        in flight, the fewest runs that could decide its test (Sprt.runs_to_decide)."""
        out: list[Proposal] = []
        for failure in self.pending:
            if self.flight.get(failure.key) or len(out) >= room:
                continue
            est = failure.estimate
            n = min(self.test.runs_to_decide(est.outcomes), room - len(out))
            out += [(tuple(failure.found.offsets), "confirm", est.runs + 1 + k) for k in range(n)]
            self.flight[failure.key] = n
        return out

    def reserve(self, new_in_flight: int = 0) -> int:
        """Runs kept out of the strategy's room so that the failures found can be decided before
        the budget ends: what the failures under test still need beyond the runs in flight if
        each keeps failing (the runs a failure that holds takes), and what the new failures
        expected among the ``new_in_flight`` candidates not yet read would need (at the rate new
        failures have come so far)."""
        need = 0
        for failure in self.pending:
            est = failure.estimate
            need += max(self._to_accept(est.outcomes) - self.flight.get(failure.key, 0), 0)
        if self.seen and new_in_flight:
            need += math.ceil(new_in_flight * self.begun / self.seen * self._to_accept([]) - 1e-9)
        return need

    def _to_accept(self, outcomes: list[bool]) -> int:
        """Runs to accept after ``outcomes`` if every one fails (at most the test's last run)."""
        runs = math.ceil((self.test.accept_at - self.test.llr(outcomes)) / self.test.up - 1e-9)
        return max(0, min(runs, self.test.max_runs - len(outcomes)))

    def result(self, cand: Candidate) -> None:
        """A confirmation run came back: note it; decide when the runs asked for are all in."""
        failure = self.by_offsets[tuple(cand.offsets)]
        failure.estimate.outcomes.append(cand.failed)
        self.flight[failure.key] -= 1
        if self.flight[failure.key]:
            return
        del self.flight[failure.key]
        decide(self.test, failure.estimate)
        if failure.estimate.decision == "pending":
            return
        self.pending.remove(failure)
        del self.by_offsets[tuple(failure.found.offsets)]
        sig = failure.found.signature
        if failure.estimate.decision == "held":
            failure.status = "confirmed"
            self.held.add(sig)
            self.aside.pop(sig, None)
        else:
            failure.status = "rejected"
            self.rejections[sig] = self.rejections.get(sig, 0) + 1
        self.on_decided(failure)

    def next_aside(self, failure: Failure) -> Failure | None:
        """After ``failure`` was rejected: the candidate kept aside for its way of failing, begun."""
        sig = failure.found.signature
        cand = self.aside.pop(sig, None)
        if cand is None or self.rejections.get(sig, 0) >= self.max_rejections:
            return None
        return self._begin(cand)

    def close(self, interrupted: bool) -> list[Failure]:
        """The search phase is over: the failures still under test (marked unconfirmed unless the
        search was cut short, when they stay as found)."""
        left, self.pending = self.pending, []
        for failure in left:
            failure.estimate.decision = "pending" if interrupted else "unconfirmed"
            failure.status = "found" if interrupted else "unconfirmed"
        return left


# -- shrinking --------------------------------------------------------------------------------
@dataclass(frozen=True)
class ShrinkBudget:
    """How many simulations the shrink phase may use: ``share`` of the search's budget for all
    failures together (``"25%"``), or, the old form, ``per_failure`` simulations for each (``40``)."""
    share: float | None = None
    per_failure: int | None = None

    @classmethod
    def parse(cls, value: "ShrinkBudget | int | str") -> "ShrinkBudget":
        """``"25%"``, ``"0"``/``0`` (no shrinking) or a whole number N (per failure, the old form);
        ValueError saying what is accepted otherwise."""
        if isinstance(value, ShrinkBudget):
            return value
        text = str(value).strip()
        try:
            if text.endswith("%"):
                share = float(text[:-1])
                if not math.isfinite(share) or not 0 <= share <= 1000:
                    raise ValueError
                return cls(share=share / 100.0)
            n = int(text)
            if n < 0:
                raise ValueError
            return cls(share=0.0) if n == 0 else cls(per_failure=n)
        except ValueError:
            raise ValueError(f"shrink budget {value!r}: give a share of the search budget such as 25% "
                             f"(0% to 1000%), or 0 to keep failures as found, or a whole number N for at "
                             f"most N simulations per failure (the old form)") from None

    def total(self, budget: int, failures: int) -> int:
        """Simulations the whole shrink phase may use for ``failures`` failures."""
        if self.per_failure is not None:
            return self.per_failure * failures
        return int(round((self.share or 0.0) * budget))

    def describe(self, budget: int) -> str:
        if self.per_failure is not None:
            return f"{self.per_failure} simulations per failure"
        return f"{self.share:.0%} of the budget of {budget}"


def shrink_order(failures: Sequence[Failure]) -> list[int]:
    """Indexes of ``failures``, the one that matters most first: the most severe outcome
    (SEVERITY), then the one that failed earliest along the route (lowest robustness), then the
    one found first."""
    def key(i: int) -> tuple:
        c = failures[i].found
        sev = SEVERITY.index(c.outcome) if c.outcome in SEVERITY else len(SEVERITY)
        rob = c.robustness if math.isfinite(c.robustness) else math.inf
        return (sev, rob, c.sim, i)
    return sorted(range(len(failures)), key=key)


def shrink_plan(failures: Sequence[Failure], total: int, budget: ShrinkBudget | None = None) -> list[int]:
    """Each failure's cap (aligned with ``failures``), fixed before any shrinking starts so that
    the failures can shrink as independent jobs, in any order or process, with the same result.

    ``total`` is shared out in ``shrink_order``: as many failures as can get MIN_SHRINK_SIMS each
    get an equal part (the first ones one more while the remainder lasts); the rest get 0 and are
    kept as found. A failure with nothing to shrink (the seed itself) gets 0. The old
    per-failure form gives each failure its fixed cap."""
    caps = [0] * len(failures)
    todo = [i for i in shrink_order(failures) if any(failures[i].found.offsets)]
    if budget is not None and budget.per_failure is not None:
        for i in todo:
            caps[i] = budget.per_failure
        return caps
    if total <= 0 or not todo:
        return caps
    k = min(len(todo), max(1, total // MIN_SHRINK_SIMS))
    each, extra = divmod(total, k)
    for rank, i in enumerate(todo[:k]):
        caps[i] = each + (1 if rank < extra else 0)
    return caps


def shrink_all(space: SearchSpace, sim: "_Simulator", caps: Sequence[int], progress=None) -> None:
    """Shrink each failure of ``sim.report`` with its cap (``shrink_plan``), in ``shrink_order``,
    serially; the result is the same as shrinking them side by side (parallel.py)."""
    report = sim.report
    for i in shrink_order(report.failures):
        if caps[i] <= 0:
            continue
        sim.check_stop()
        sim.set_failure(i, shrink_failure(space, sim, report.failures[i].found, caps[i], report.failures[i].estimate))
        if progress is not None:
            progress(report)


def _note_unshrunk(report: "SearchReport", caps: Sequence[int], budget: ShrinkBudget) -> None:
    """Say why a failure was kept as found when the shrink budget did not reach it."""
    for f, cap in zip(report.failures, caps):
        if cap == 0 and any(f.found.offsets) and not f.note and report.shrink_total > 0:
            f.note = (f"not shrunk: the shrink budget ({report.shrink_total} simulations, "
                      f"{budget.describe(report.budget)}) went to failures that matter more")


def shrink_failure(space: SearchSpace, sim: _Simulator, found: Candidate, cap: int,
                   estimate: Estimate | None = None) -> Failure:
    """Reduce ``found`` toward the seed with at most ``cap`` simulations: first drop inserted
    obstacles and restore removed ones, one at a time, then Hypothesis's shrinker on the offset
    vector. The result fails with the same cause signature as ``found``, and holds as ``found``
    did: with a confirmation test (``sim.ctx.hold``), a simpler layout that fails that way counts
    only once its own confirmation runs (simulations of the cap) decide that it holds.
    ``estimate`` is ``found``'s (kept when nothing simpler holds; None: left to the caller)."""
    failure = Failure(found=found, shrunk=found, status="unshrunk", estimate=estimate or Estimate())
    if cap <= 0 or not any(found.offsets):
        return failure
    test, threshold = sim.ctx.hold, sim.ctx.hold_threshold
    best, best_estimate, used = [found], [failure.estimate], [0]
    answers: dict[tuple, bool] = {}   # Hypothesis may ask about one layout twice (clipped values)

    def still_fails(offsets) -> bool:
        offsets = tuple(offsets)
        if offsets == tuple(found.offsets) and used[0] > 0:
            return True
        if offsets in answers:   # (only with a test: without one, a repeat costs one run, as it always did)
            return answers[offsets]
        sim.check_stop()
        if used[0] >= cap:
            failure.note = f"shrink cap of {cap} simulations reached"
            raise _Stop()
        if invalid_reason(space.apply(offsets)) is not None:
            return False
        used[0] += 1
        cand = sim.simulate(offsets, "shrink", "shrink")
        ok = cand.signature == found.signature
        est = None
        if ok and test is not None and offsets != tuple(found.offsets):   # it must hold, not fail once
            est = Estimate(threshold=threshold)
            while est.decision == "pending":
                n = min(test.runs_to_decide(est.outcomes), cap - used[0])
                if n <= 0:
                    failure.note = f"shrink cap of {cap} simulations reached"
                    raise _Stop()
                runs = list(sim.run([(offsets, "confirm", est.runs + 1 + k) for k in range(n)], "shrink"))
                used[0] += n
                est.outcomes += [c.failed for c in runs]
                decide(test, est)
            ok = est.decision == "held"
            answers[offsets] = ok
        if ok and _simpler(offsets, best[0].offsets):
            best[0], best_estimate[0] = cand, est or best_estimate[0]
        return ok

    try:
        _drop_structure(space, still_fails, best)
        _hypothesis_shrink(space, still_fails, best[0].offsets)
    except _Stop:
        pass
    except _NoExample:
        failure.note = "did not reproduce when re-simulated: kept as found"
    failure.shrunk, failure.estimate = best[0], best_estimate[0]
    failure.status = shrink_status(failure.note)
    failure.shrink_sims = used[0]
    return failure


def shrink_status(note: str) -> str:
    """A shrunk failure's status from its shrink's note: kept as found if it did not reproduce."""
    return "unshrunk" if note.startswith("did not reproduce") else "shrunk"


class _NoExample(Exception):
    pass


def _drop_structure(space: SearchSpace, still_fails, best: list) -> None:
    """Turn off each inserted obstacle and restore each removed one, keeping what still fails."""
    for i in space.inserted_slots() + space.removal_flags():
        current = list(best[0].offsets)
        if current[i] >= FLAG_ON:
            current[i] = 0.0
            still_fails(tuple(current))


def _hypothesis_shrink(space: SearchSpace, still_fails, start: Sequence[float]) -> None:
    from hypothesis import Phase, Verbosity, find, settings
    from hypothesis.database import InMemoryExampleDatabase, choices_to_bytes
    from hypothesis.errors import NoSuchExample

    db = InMemoryExampleDatabase()
    key = b"navsearch-shrink"
    db.save(key + b".secondary", choices_to_bytes(tuple(start)))
    try:
        with _fixed_hypothesis_random(repr(tuple(start))):
            find(offsets_strategy(space), still_fails, database_key=key,
                 settings=settings(database=db, phases=[Phase.reuse, Phase.shrink], verbosity=Verbosity.quiet,
                                   deadline=None, max_examples=1000))
    except NoSuchExample:
        raise _NoExample() from None


@contextlib.contextmanager
def _fixed_hypothesis_random(key: str) -> Iterator[None]:
    """Some of Hypothesis's shrink passes are randomised, from a stream it seeds afresh in every
    process, so two runs with the same search seed could shrink a failure differently (seen at
    budget 200: the logs parted in the shrink phase). find() has no public way to fix that stream
    and keep the database we start from (seed= and derandomize=True both switch it off), so the
    stream Hypothesis draws test seeds from is set here, from ``key``, for the one find() call.
    Private to Hypothesis: if it moves, shrinking still works, only without that guarantee."""
    import random

    import hypothesis.core as hcore

    local = getattr(hcore, "threadlocal", None)
    if local is None or not hasattr(local, "_hypothesis_global_random"):
        yield
        return
    saved = local._hypothesis_global_random
    local._hypothesis_global_random = random.Random(key)
    try:
        yield
    finally:
        local._hypothesis_global_random = saved


def _simpler(a: Sequence[float], b: Sequence[float]) -> bool:
    """Fewer non-zero offsets, then smaller total |offset|: closer to the seed."""
    ka = (sum(1 for v in a if v), sum(abs(v) for v in a))
    kb = (sum(1 for v in b if v), sum(abs(v) for v in b))
    return ka < kb


# -- entry point -------------------------------------------------------------------------------
def _check_inputs(seed: Scenario, strategy: str, budget: int, space: SearchSpace) -> None:
    if strategy not in STRATEGIES:
        raise ValueError(f"unknown search strategy {strategy!r}; use one of {', '.join(STRATEGIES)}")
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


def run_search(seed: Scenario, subject_factory: Callable[[], Any], *, budget: int, seed_value: int = 0,
               strategy: str = "evolve", shrink_budget: ShrinkBudget | int | str = DEFAULT_SHRINK_BUDGET,
               progress: Callable[[SearchReport], None] | None = None,
               stop: Callable[[], bool] | None = None, space: SearchSpace | None = None,
               subject: str = "", episode_seed: int | None = None,
               stuck_after: float | None = DEFAULT_STUCK_AFTER, evaluator: Evaluator | None = None,
               recorder: Recorder | None = None, hold: float | None = None, batch: int = 1,
               engine: str = "cpu") -> SearchReport:
    """Search for failures of ``subject_factory()`` planners around ``seed``.

    Exactly ``budget`` simulations of valid candidates (fewer only if interrupted or if the
    bounds leave almost no valid candidate, said in ``stop_reason``), then the distinct failures
    are shrunk within ``shrink_budget`` more simulations: a share of the budget (``"25%"``, the
    default; ``0``: no shrinking) shared out most important failure first (``shrink_plan``), or
    the old form, a whole number N of simulations per failure. ``progress(report)`` is
    called after each simulation; ``stop()`` returning True ends the search early (as does
    Ctrl-C): the report then keeps every failure found so far, unshrunk, with ``interrupted``.
    ``stuck_after`` (s, None = off) ends an episode early as a timeout when the robot covers no
    new ground. ``evaluator(ctx, proposals)`` evaluates a generation (default: serially). An
    evaluator may also have ``shrink_failures(sim, caps, progress)`` (shrink the failures, each
    with its cap, e.g. all at once on worker processes, and record the results in a serial run's
    order), ``start_shrink(ctx, found, cap)`` (begin shrinking a failure the moment it is found,
    while the search goes on, with a cap no larger than the plan's, ``_early_shrink``) and
    ``discard()`` (give up what is still in flight when the search ends early), as the
    worker-process one in search/parallel.py does; the result does not depend on the evaluator.
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
    from .holding import DEFAULT_HOLD, hold_test
    from .strategies import GaveUp, make_strategy
    from ..scenario.model import randomness

    space = space if space is not None else SearchSpace(seed)
    _check_inputs(seed, strategy, budget, space)
    shrink = ShrinkBudget.parse(shrink_budget)
    hold = DEFAULT_HOLD if hold is None else float(hold)
    test = hold_test(hold)   # ValueError for a threshold outside [0, 1)
    noisy = randomness(space.seed)
    report = SearchReport(seed_name=seed.name, seed_source=seed.source, subject=subject or "?",
                          subject_version=None, strategy=strategy, seed_value=seed_value, budget=budget,
                          shrink_budget=str(shrink_budget), params=[p.name for p in space.params],
                          episode_seed=episode_seed, hold=hold, randomness=noisy)
    ctx = EvalContext(space, subject_factory, episode_seed, stuck_after, test if noisy else None, hold,
                      batch=batch, engine=engine)
    sim = _Simulator(ctx, report, stop, evaluator, recorder)
    searcher = make_strategy(strategy, space, report, budget, seed_value)
    told = getattr(searcher, "confirmed", None)   # strategies.py: prefer failures that hold

    start_shrink = getattr(evaluator, "start_shrink", None)   # parallel.py: shrink while searching
    early_cap, early_count = _early_shrink(shrink, budget)

    def holds(failure: Failure) -> None:
        report.failures.append(failure)
        if start_shrink is not None and early_cap > 0 and any(failure.found.offsets) \
                and len(report.failures) <= early_count:
            start_shrink(sim.ctx, failure.found, early_cap, estimate=failure.estimate)

    def decided(failure: Failure) -> None:
        sim.tell_recorder("failure", failure)
        if told is not None:
            told(failure.found, failure.estimate)
        if failure.status == "confirmed":
            holds(failure)
            return
        report.rejected.append(failure)
        nxt = confirming.next_aside(failure)   # the next candidate that failed this way, if any
        if nxt is not None:
            sim.tell_recorder("failure", nxt)

    confirming = _Confirming(ctx, report, "exact" if test is not None else "off", decided)

    def on_result(cand: Candidate) -> None:
        if cand.run:
            confirming.result(cand)
        else:
            confirming.counted(cand)
        if not cand.run and cand.failed:
            failure = confirming.failed(cand)
            if failure is not None:
                sim.tell_recorder("failure", failure)   # on disk before it is logged
                if failure.status == "confirmed":       # no test to pass: it holds at once
                    if told is not None:
                        told(failure.found, failure.estimate)
                    holds(failure)
        sim.tell_recorder("simulated", cand)
        report.under_test = len(confirming.pending)
        if progress is not None:
            progress(report)

    def close_confirming() -> None:
        for failure in confirming.close(report.interrupted):
            report.unconfirmed.append(failure)
            sim.tell_recorder("failure", failure)
        report.under_test = 0

    t0 = time.perf_counter()
    try:
        sim.tell_recorder("start")
        _search_loop(searcher, sim, budget, on_result, confirming if ctx.hold is not None else None)
        close_confirming()
        report.shrink_total = shrink.total(budget, len(report.failures))
        caps = shrink_plan(report.failures, report.shrink_total, shrink)
        _note_unshrunk(report, caps, shrink)
        for i, cap in enumerate(caps):   # kept as found: final now
            if cap <= 0:
                sim.set_failure(i, dataclasses.replace(report.failures[i], status="unshrunk"))
        shrink_failures = getattr(evaluator, "shrink_failures", None)   # parallel.py: all at once
        if shrink_failures is not None:
            shrink_failures(sim, caps, progress)
        else:
            shrink_all(space, sim, caps, progress)
    except (_Stop, GaveUp):
        pass  # stop() said so, or the strategy gave up (stop_reason says why)
    except KeyboardInterrupt:
        report.interrupted = True
        report.stop_reason = f"interrupted ({first_signal() or 'Ctrl-C'})"
    finally:
        discard = getattr(evaluator, "discard", None)   # jobs still in flight if it ended early
        if discard is not None:
            discard()
        if confirming.pending:   # cut short during the search phase
            report.interrupted = True
            close_confirming()
        batching = getattr(evaluator, "batching", None)
        if batching is not None and batching.batched:
            report.batching = batching.describe()
        if report.interrupted:
            for f in report.failures:
                if f.shrink_sims == 0 and not f.note and any(f.found.offsets):
                    f.note = "not shrunk: the search was interrupted"
        report.wall_time = time.perf_counter() - t0
        sim.tell_recorder("finish")   # also when something failed: what was found stays on disk
    return report
