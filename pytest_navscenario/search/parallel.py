"""A search's generations evaluated on an executor (``dispatch/``: local worker processes or Ray).

``executor_evaluator(executor)`` is an evaluator for ``run_search(..., evaluator=...)``: each
generation the strategy proposes becomes one ``CandidateJob`` per candidate, all submitted the
moment the generation is proposed (the search loop proposes the next generation before it reads
the results of this one, engine._search_loop), and the candidates come back in proposal order.
Each distinct failure becomes one ``ShrinkJob`` the moment it is found, so its shrinking runs
beside the rest of the search instead of after it. A candidate is a pure function of the
evaluation context and its offsets (``evaluation.evaluate_candidate``), a shrink a pure function of
the failure and its cap, and the strategy sees results at the same point as in a serial run, so
the search takes the same path, finds the same failures and writes the same files as a serial
run with the same search seed; only the measured wall times differ, as they do between two
serial runs.
"""
from __future__ import annotations

import dataclasses
import uuid
from dataclasses import dataclass
from typing import Any, Iterator, Sequence

from ..core.interrupts import deferred
from .evaluation import EvalContext, Simulator, evaluate_candidate, evaluate_candidates, unpack
from .evaluators import Evaluator
from .report import Candidate, Failure, SearchReport
from .shrinker import shrink_failure, shrink_order, shrink_status
from .holding import Estimate

_CONTEXTS: dict[str, EvalContext] = {}   # worker side: the first copy of each context received
_MAX_CONTEXTS = 4


@dataclass(frozen=True)
class CandidateJob:
    """One candidate to simulate in a worker (a dispatch job: ``run`` there, ``restore`` here)."""
    ctx: EvalContext
    offsets: tuple[float, ...]
    origin: str
    token: str          # names ``ctx``: a worker reuses its first copy, so per-space caches survive
    noise_run: int = 0  # 0: the search's own run; k: the k-th confirmation run (holding.py)

    def run(self) -> Candidate:
        cand = evaluate_candidate(_context(self.token, self.ctx), self.offsets, self.origin, self.noise_run)
        cand.scenario = None    # rebuilt from the offsets here: no need to send it back
        return cand

    def restore(self, cand: Candidate) -> Candidate:
        cand.scenario = self.ctx.space.apply(self.offsets)
        return cand


def _context(token: str, ctx: EvalContext) -> EvalContext:
    """Worker side: the first copy of ``ctx`` this worker received (its caches survive)."""
    cached = _CONTEXTS.get(token)
    if cached is None:
        if len(_CONTEXTS) >= _MAX_CONTEXTS:
            _CONTEXTS.clear()
        cached = _CONTEXTS[token] = ctx
    return cached


@dataclass(frozen=True)
class CandidateBatchJob:
    """Several candidates simulated together in a worker (``evaluation.evaluate_candidates``: in
    lockstep when the subject answers the batch protocol): one worker's share of a generation."""
    ctx: EvalContext
    proposals: tuple[tuple[tuple[float, ...], str, int], ...]   # (offsets, origin, noise run)
    token: str

    def run(self) -> list[Candidate]:
        cands = evaluate_candidates(_context(self.token, self.ctx), self.proposals)
        for cand in cands:
            cand.scenario = None
        return cands

    def restore(self, cands: list[Candidate]) -> list[Candidate]:
        for cand, (offsets, *_) in zip(cands, self.proposals):
            cand.scenario = self.ctx.space.apply(offsets)
        return cands


@dataclass(frozen=True)
class ShrinkJob:
    """Shrink one failure in a worker, as a serial run would (``shrinker.shrink_failure`` with its
    own simulations, one after the other); the failures of a search shrink side by side."""
    ctx: EvalContext
    found: Candidate
    cap: int
    token: str
    known: tuple[Candidate, ...] = ()   # simulations a shorter shrink of this failure already ran
    estimate: Estimate | None = None    # the found layout's (holding.py)

    def run(self) -> tuple[int, str, int, list[Candidate], Estimate]:
        """(index of the shrunk candidate among the shrink candidates, -1: as found; note;
        simulations used; the shrink candidates in the order they ran, scenarios stripped; the
        estimate of the shrunk layout)."""
        ctx = _context(self.token, self.ctx)
        scratch = SearchReport(seed_name="", seed_source=None, subject="", subject_version=None,
                               strategy="", seed_value=0, budget=0, shrink_budget=self.cap, params=[])
        sim = _Replay(ctx, scratch, self.known) if self.known else Simulator(ctx, scratch, None)
        failure = shrink_failure(ctx.space, sim, self.found, self.cap, self.estimate)
        cands = scratch.candidates
        index = next((i for i, c in enumerate(cands) if c is failure.shrunk), -1)
        for cand in cands:
            cand.metrics["subject"], cand.metrics["subject_version"] = scratch.subject, scratch.subject_version
            cand.scenario = None
        return index, failure.note, failure.shrink_sims, cands, failure.estimate

    def restore(self, outcome: tuple) -> tuple:
        for cand in outcome[3]:
            cand.scenario = self.ctx.space.apply(cand.offsets)
        return outcome


class _Replay(Simulator):
    """Answers a shrink's simulations from those a shorter shrink of the same failure ran (with
    the same answers the shrinker asks the same questions in the same order, so a longer shrink
    begins with exactly those) and simulates the rest: a cap raised after the search costs only
    the simulations beyond the first cap."""

    def __init__(self, ctx: EvalContext, report: SearchReport, known: Sequence[Candidate]):
        super().__init__(ctx, report, None)
        self.known: dict[tuple, Candidate] = {}
        for cand in known:
            self.known.setdefault((tuple(cand.offsets), cand.run), cand)

    def run(self, proposals: Sequence[tuple], phase: str) -> Iterator[Candidate]:
        for offsets, origin, *run in proposals:
            yield self.simulate(offsets, phase, origin, *run)

    def simulate(self, offsets: Sequence[float], phase: str, origin: str, run: int = 0) -> Candidate:
        cand = self.known.pop((tuple(offsets), run), None)
        if cand is None:
            return next(iter(super().run([(tuple(offsets), origin, run)], phase)))
        return self.record(dataclasses.replace(cand, metrics=dict(cand.metrics)), phase)


class executor_evaluator(Evaluator):   # noqa: N801  (used like a function: evaluator=executor_evaluator(ex))
    """An evaluator that runs each generation on ``executor`` (see the module docstring)."""

    shrinks_early = True

    def __init__(self, executor: Any):
        from ..harness.batch import Batching

        self.executor = executor
        self.batching = Batching()     # the candidates sent to the workers as batches (the summary line)
        self._ctx: EvalContext | None = None
        self._token = ""
        self._open: dict[int, Any] = {}              # id -> Pending: submitted, result not yet taken
        self._shrinks: list[tuple[Candidate, int, Any]] = []   # (failure as found, cap, its pending shrink)

    def _token_for(self, ctx: EvalContext) -> str:
        if ctx is not self._ctx:
            self._ctx, self._token, self._shrinks = ctx, uuid.uuid4().hex, []
            self._deaths_from = len(getattr(self.executor, "deaths", ()))
        return self._token

    def worker_deaths(self) -> list[str]:
        """The worker processes that died during this search (the pool replaced, what they had
        not finished run again: dispatch/local.py), for the search log's end record."""
        return list(getattr(self.executor, "deaths", ())[getattr(self, "_deaths_from", 0):])

    def _submit(self, jobs: list[Any]) -> list[Any]:
        pending = self.executor.submit(jobs)
        self._open.update((id(p), p) for p in pending)
        return pending

    def _take(self, pending: Any) -> Any:
        self._open.pop(id(pending), None)
        return pending.result()

    def __call__(self, ctx: EvalContext, proposals: Sequence[tuple]) -> Iterator[Candidate]:
        """Submit the generation now; the iterator waits for each candidate in proposal order."""
        token = self._token_for(ctx)
        proposals = [unpack(p) for p in proposals]
        if ctx.batch > 1 and len(proposals) > 1 and _answers_batches(ctx):   # each worker's share as a batch
            workers = max(1, int(getattr(self.executor, "workers", 1)))
            size = min(ctx.batch, -(-len(proposals) // workers))
            chunks = [tuple(proposals[i:i + size]) for i in range(0, len(proposals), size)]
            pending = self._submit([CandidateBatchJob(ctx, chunk, token) for chunk in chunks])
            self.batching.batched += len(proposals)
            self.batching.batches += len(chunks)
            return (cand for p in pending for cand in self._take(p))
        pending = self._submit([CandidateJob(ctx, offsets, origin, token, run) for offsets, origin, run in proposals])
        return (self._take(p) for p in pending)

    def start_shrink(self, ctx: EvalContext, found: Candidate, cap: int, known: Sequence[Candidate] = (),
                     estimate: Estimate | None = None) -> None:
        """Submit the shrinking of a failure (during the search: just confirmed; its simulations
        are recorded later, by ``shrink_failures``, after the search's own, as in a serial run)."""
        token = self._token_for(ctx)
        job = ShrinkJob(ctx, _stripped(found), cap, token, tuple(_stripped(c) for c in known), estimate)
        self._shrinks.append((found, cap, self._submit([job])[0]))

    def shrink_failures(self, sim: Simulator, caps: Sequence[int], progress: Any) -> None:
        """Shrink every failure with a cap (shrinker.shrink_plan), one job each; a job begun during
        the search with a smaller cap is continued (its simulations replayed, not run again) and
        one whose failure gets no cap is given up. Record the shrink simulations failure by
        failure, in the order a serial run records them (shrinker.shrink_order). Ctrl-C keeps the
        failures not yet shrunk as found (run_search notes them)."""
        report = sim.report
        order = [i for i in shrink_order(report.failures) if caps[i] > 0]
        started = {id(f): (c, p) for f, c, p in self._shrinks} if sim.ctx is self._ctx else {}
        self._shrinks = []
        outcome: dict[int, Any] = {}
        for i in order:   # jobs with the planned cap, and fresh ones, first
            found, estimate = report.failures[i].found, report.failures[i].estimate
            cap, p = started.get(id(found), (0, None))
            if p is not None and cap == caps[i]:
                outcome[i] = started.pop(id(found))[1]
            elif p is None or cap > caps[i]:
                self.start_shrink(sim.ctx, found, caps[i], estimate=estimate)
                outcome[i] = self._shrinks[-1][2]
        for i in order:   # begun with a smaller cap: continue where it stopped, unless it had finished
            if i not in outcome:
                cap, p = started.pop(id(report.failures[i].found))
                early = self._take(p)
                if early[2] < cap:   # the shrinker finished below its cap: a larger one changes nothing
                    outcome[i] = early
                else:
                    self.start_shrink(sim.ctx, report.failures[i].found, caps[i], early[3],
                                      report.failures[i].estimate)
                    outcome[i] = self._shrinks[-1][2]
        for _, p in started.values():   # failures the plan gives no simulation
            self._open.pop(id(p), None)
            p.cancel()
        for i in order:
            sim.check_stop()
            found = report.failures[i].found
            index, note, used, cands, estimate = (outcome[i] if isinstance(outcome[i], tuple)
                                                  else self._take(outcome[i]))
            with deferred():   # its simulations logged and the shrunk failure written: one step
                for cand in cands:
                    sim.record(cand, "shrink")
                sim.set_failure(i, Failure(found=found, shrunk=cands[index] if index >= 0 else found,
                                           shrink_sims=used, note=note, status=shrink_status(note),
                                           estimate=estimate if index >= 0 else report.failures[i].estimate))
            if progress is not None:
                progress(report)
        self._shrinks = []

    def discard(self) -> None:
        """Give up every job whose result was not taken (the search ended early)."""
        for p in self._open.values():
            p.cancel()
        self._open.clear()
        self._shrinks = []


_BATCHES: dict[int, bool] = {}


def _answers_batches(ctx: EvalContext) -> bool:
    """True if the context's subject makes planners that answer the batch protocol, as far as this
    process can tell without making one (a class, or a spec naming one); False otherwise, and for an
    exec: program or a subject this process cannot load (then each candidate is its own job)."""
    factory = ctx.subject_factory
    key = id(factory)
    if key not in _BATCHES:
        from ..subjects.protocol import is_batch_planner
        spec = getattr(factory, "spec", None)
        try:
            if isinstance(spec, str):
                from ..subjects.loading import load_subject
                factory = None if spec.strip().startswith("exec:") else load_subject(spec, cwd=getattr(factory, "cwd", None))
            answer = isinstance(factory, type) and is_batch_planner(factory)
        except Exception:
            answer = False
        _BATCHES.clear()
        _BATCHES[key] = answer
    return _BATCHES[key]


def _stripped(cand: Candidate) -> Candidate:
    """A copy of ``cand`` without its scenario (the worker rebuilds it from the offsets)."""
    import dataclasses
    return dataclasses.replace(cand, scenario=None)
