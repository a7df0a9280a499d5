"""A search's simulations in batches, in this process: the evaluator ``run_search`` uses when the
subject answers the batch protocol (harness/batch.py, sim/batching/batch.py).

Generations: ``batch_evaluator`` queues each generation the search proposes and runs everything
queued as one batch when the first of its results is asked for. The search proposes the next
generation before it reads this one's results (engine._search_loop, the strategy's lag), so a batch
holds the generations in flight (two of 8 candidates today), up to the batch size.

Shrinking: each failure is shrunk by its own thread running ``shrinker.shrink_failure`` exactly as a
serial run does, except that its simulations are handed to a coordinator, which runs every
thread's next simulation as one batch. Only one thread runs at a time (a thread runs until it asks
for a simulation or finishes, then hands over), so Hypothesis's shrinker never runs in two threads
at once, and each failure's shrink asks the same questions in the same order as a serial run. The
shrink simulations are recorded failure by failure, in the serial run's order (as the
worker-process evaluator of parallel.py does). The search takes the same path, finds and shrinks
the same failures and writes the same files as a serial run; only wall times differ.
"""
from __future__ import annotations

import threading
from typing import Any, Iterator, Sequence

from ..core.interrupts import deferred
from .evaluation import EvalContext, Proposal, Simulator, Stop, evaluate_candidates, iter_candidates, unpack
from .evaluators import Evaluator
from .report import Candidate, Failure, SearchReport
from .shrinker import shrink_all, shrink_failure, shrink_order, shrink_status

Proposals = Sequence[Proposal]   # (offsets, origin[, noise run]): confirmation runs batch like the rest


class _Queued:
    def __init__(self, ctx: EvalContext, proposals: Proposals):
        self.ctx, self.proposals = ctx, list(proposals)
        self.results: list[Candidate] = []
        self.source: _Source | None = None     # set when the batch holding it starts


class _Source:
    """The candidates of the generations simulated together, handed to each as they come."""

    def __init__(self, candidates: Iterator[Candidate], jobs: list[_Queued]):
        self.candidates, self.jobs = candidates, jobs

    def pull(self) -> bool:
        """The next candidate into its generation's results; False when there is none."""
        for job in self.jobs:
            if len(job.results) < len(job.proposals):
                job.results.append(next(self.candidates))
                return True
        return False


class batch_evaluator(Evaluator):   # noqa: N801  (used like a function: evaluator=batch_evaluator())
    """An evaluator that simulates the generations in flight together and shrinks the failures
    side by side, in batches of ``ctx.batch`` (see the module docstring)."""

    def __init__(self) -> None:
        from ..harness.batch import Batching

        self._queue: list[_Queued] = []
        self.batching = Batching()     # how the simulations ran (the summary line)

    def __call__(self, ctx: EvalContext, proposals: Proposals) -> Iterator[Candidate]:
        job = _Queued(ctx, proposals)
        self._queue.append(job)
        return self._results(job)

    def _results(self, job: _Queued) -> Iterator[Candidate]:
        if job.source is None:
            self._start(job)
        k = 0
        while k < len(job.proposals):
            while len(job.results) <= k:
                job.source.pull()
            yield job.results[k]
            k += 1

    def _start(self, first: _Queued) -> None:
        """Start simulating the queued generations, from ``first`` on, up to the batch size (at
        least ``first`` whole), together; each gets its candidates as they come."""
        size = max(1, first.ctx.batch)
        take, n = [], 0
        for job in self._queue:
            if job.source is not None or job.ctx is not first.ctx:
                continue
            if take and n + len(job.proposals) > size:
                break
            take.append(job)
            n += len(job.proposals)
        source = _Source(iter_candidates(first.ctx, [p for job in take for p in job.proposals], self.batching), take)
        for job in take:
            job.source = source
        self._queue = [job for job in self._queue if job.source is None]

    def discard(self) -> None:
        """The search ended early: forget the generations not simulated."""
        self._queue = []

    def shrink_failures(self, sim: Simulator, caps: Sequence[int], progress: Any) -> None:
        """Shrink every failure with a cap (shrinker.shrink_plan) side by side, their simulations in
        batches; record them failure by failure in shrinker.shrink_order."""
        report = sim.report
        order = [i for i in shrink_order(report.failures) if caps[i] > 0]
        if not order:
            return
        if sim.ctx.batch <= 1 or (self.batching.alone and not self.batching.batched):
            shrink_all(sim.ctx.space, sim, caps, progress)   # nothing to batch: the serial shrink
            return
        rounds = _Rounds(sim.ctx, sim.check_stop, self.batching)
        shrinks = [_Shrink(rounds, k, sim.ctx, report.failures[i].found, caps[i], report.failures[i].estimate)
                   for k, i in enumerate(order)]
        rounds.run(shrinks)
        for i, shrink in zip(order, shrinks):
            sim.check_stop()
            found = report.failures[i].found
            failure, scratch = shrink.failure, shrink.scratch
            with deferred():   # its simulations logged and the shrunk failure written: one step
                for cand in scratch.candidates:
                    cand.metrics["subject"], cand.metrics["subject_version"] = scratch.subject, scratch.subject_version
                    sim.record(cand, "shrink")
                sim.set_failure(i, Failure(found=found, shrunk=failure.shrunk, shrink_sims=failure.shrink_sims,
                                           note=failure.note, status=shrink_status(failure.note),
                                           estimate=failure.estimate))
            if progress is not None:
                progress(report)


class _ThreadSimulator(Simulator):
    """A shrink thread's simulator: each simulation (a layout, or its confirmation runs under
    fresh noise seeds, holding.py) is asked of the coordinator and waited for."""

    def __init__(self, shrink: "_Shrink", ctx: EvalContext, report: SearchReport):
        super().__init__(ctx, report, None)
        self.shrink = shrink

    def run(self, proposals: Sequence[Proposal], phase: str) -> Iterator[Candidate]:
        cands = self.shrink.ask([unpack(p) for p in proposals])
        return iter([self.record(cand, phase) for cand in cands])

    def simulate(self, offsets: Sequence[float], phase: str, origin: str, run: int = 0) -> Candidate:
        return next(self.run([(tuple(offsets), origin, run)], phase))

    def check_stop(self) -> None:
        if self.shrink.rounds.stopping:
            raise Stop()


class _Shrink:
    """One failure's shrink, run by its own thread."""

    def __init__(self, rounds: "_Rounds", key: int, ctx: EvalContext, found: Candidate, cap: int,
                 estimate: Any = None):
        self.rounds, self.key, self.ctx, self.found, self.cap = rounds, key, ctx, found, cap
        self.estimate = estimate                          # the found layout's (holding.py)
        self.scratch = SearchReport(seed_name="", seed_source=None, subject="", subject_version=None,
                                    strategy="", seed_value=0, budget=0, shrink_budget=cap, params=[])
        self.failure: Failure | None = None
        self.error: BaseException | None = None
        self.asked: list[tuple] | None = None            # the simulations it waits for (proposals)
        self.answer: list[Candidate] | None = None
        self.done = False
        self.turn = threading.Event()                     # set: this thread may run

    def ask(self, proposals: list[tuple]) -> list[Candidate]:
        """Hand the turn back with simulations to run; wait for their candidates."""
        self.asked = proposals
        self.turn.clear()
        self.rounds.handed_back.set()
        self.turn.wait()
        if self.rounds.stopping:
            raise Stop()
        answer, self.answer = self.answer, None
        return answer

    def main(self) -> None:
        self.turn.wait()
        try:
            if not self.rounds.stopping:
                sim = _ThreadSimulator(self, self.ctx, self.scratch)
                self.failure = shrink_failure(self.ctx.space, sim, self.found, self.cap, self.estimate)
        except BaseException as exc:   # handed to the coordinator, raised there
            self.error = exc
        finally:
            self.done = True
            self.rounds.handed_back.set()


class _Rounds:
    """The coordinator: lets each shrink thread run in turn until it asks for a simulation (or
    finishes), then simulates every question of the round as one batch, and again."""

    def __init__(self, ctx: EvalContext, check_stop: Any, batching: Any):
        self.ctx, self.check_stop, self.batching = ctx, check_stop, batching
        self.stopping = False
        self.handed_back = threading.Event()

    def _give_turn(self, shrink: _Shrink) -> None:
        self.handed_back.clear()
        shrink.turn.set()
        self.handed_back.wait()

    def run(self, shrinks: list[_Shrink]) -> None:
        threads = [threading.Thread(target=s.main, name=f"navsearch-shrink-{s.key}", daemon=True) for s in shrinks]
        for t in threads:
            t.start()
        try:
            for s in shrinks:                 # each runs to its first question, one at a time
                self._give_turn(s)
            while True:
                waiting = [s for s in shrinks if not s.done]
                if not waiting:
                    break
                self.check_stop()
                cands = iter(evaluate_candidates(self.ctx, [p for s in waiting for p in s.asked], self.batching))
                for s in waiting:
                    s.answer = [next(cands) for _ in s.asked]
                    s.asked = None
                    self._give_turn(s)
        except BaseException:
            self.stopping = True              # every thread ends at its next question (or now)
            for s in shrinks:
                s.turn.set()
            for t in threads:
                t.join()
            raise
        for t in threads:
            t.join()
        for s in shrinks:
            if s.error is not None:
                raise s.error
