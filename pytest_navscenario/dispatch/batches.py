"""Episode jobs sent to a worker in batches: one ``BatchJob`` runs several ``EpisodeJob`` of one
subject together (harness/batch.run_batch: in lockstep, one planner call a tick, when the subject
answers the batch protocol), and every job still gets its own ``Pending`` with its own result, the
one it gets alone.

``submit_batched(executor, jobs, size)`` groups consecutive jobs that share their subject and
limits into batch jobs of up to ``size`` (an ``exec:`` subject is never batched: its planner is a
process of its own). If the worker running a batch job dies (a planner that crashes the
interpreter), the batch is not run again whole: its episodes are submitted again one job each, so
only the episode that kills its worker fails (``WorkerDied``), as without batches.
"""
from __future__ import annotations

import threading
import traceback
from dataclasses import dataclass
from typing import Any, Sequence

from .jobs import EpisodeError, EpisodeJob, Impassable, Pending, _subject_for, compact


EXEC_ALONE = "an exec: subject is a process of its own"
LOST = ("WorkerDied", "RayTaskLost")   # a batch job that lost its worker: its episodes run again alone
WORKER_DIED = "their batch's worker process died, so they ran again one by one"   # the summary's reason


def _key(job: EpisodeJob) -> tuple | None:
    """What the jobs of one batch share, or None for a job that runs alone."""
    if not isinstance(job, EpisodeJob) or not isinstance(job.subject, str) or job.subject.strip().startswith("exec:"):
        return None
    return (job.subject, job.tick_limit, job.reset_timeout, job.cwd, job.keep_trajectory, job.check_feasible)


def _error(exc: BaseException) -> EpisodeError:
    """The EpisodeError of an exception run_batch returned for one episode (not raised)."""
    return EpisodeError.capture(exc, "".join(traceback.format_exception(type(exc), exc, exc.__traceback__)))


@dataclass(frozen=True)
class BatchJob:
    """EpisodeJobs of one subject run as batches of up to ``size`` in one worker. ``run`` returns
    (one outcome per job: a compacted EpisodeResult, an Impassable or an EpisodeError; the
    counts of harness.batch.Batching)."""
    jobs: tuple[EpisodeJob, ...]
    size: int
    alone_after_death: bool = True      # dispatch/local.py: a worker death splits it, no retry
    engine: str = "cpu"                 # the batch engine (sim/batching/batch.py: "cpu" or "warp")

    def run(self) -> tuple[list[Any], dict[str, Any]]:
        from ..harness.batch import Batching, run_batch
        from ..harness.runner import add_check_time, check_feasibility

        first = self.jobs[0]
        outcomes: list[Any] = [None] * len(self.jobs)
        checked = [0.0] * len(self.jobs)
        todo = []
        for k, job in enumerate(self.jobs):
            if job.check_feasible:
                try:
                    found, checked[k] = check_feasibility(job.scenario)
                except Exception as exc:
                    outcomes[k] = _error(exc)
                    continue
                if found is not None:
                    outcomes[k] = Impassable(str(found), found.field)
                    continue
            todo.append(k)
        batching = Batching()
        results = run_batch([self.jobs[k].scenario for k in todo], _subject_for(first),
                            seeds=[self.jobs[k].seed for k in todo], tick_limit=first.tick_limit,
                            reset_timeout=first.reset_timeout, batch=self.size, batching=batching,
                            engine=self.engine)
        for k, res in zip(todo, results):
            if isinstance(res, BaseException):
                outcomes[k] = _error(res)
            else:
                outcomes[k] = compact(add_check_time(res, checked[k]), self.jobs[k].keep_trajectory)
        return outcomes, {"batched": batching.batched, "batches": batching.batches, "alone": batching.alone,
                          "why_alone": dict(batching.why_alone)}

    def restore(self, outcome: Any) -> Any:
        return outcome


class _Shared:
    """The one pending batch job behind several per-job Pendings."""

    def __init__(self, executor: Any, jobs: list[EpisodeJob], pending: Any, batching: Any):
        self.executor, self.jobs, self.pending, self.batching = executor, jobs, pending, batching
        self.lock = threading.Lock()
        self.outcomes: list[Any] | None = None
        self.alone: list[Any] | None = None      # per-job Pendings after a worker death
        self.open = set(range(len(jobs)))        # parts neither taken nor cancelled

    def outcome(self, k: int) -> Any:
        with self.lock:
            if self.outcomes is None and self.alone is None:
                got = self.pending.outcome()
                if isinstance(got, EpisodeError):
                    if got.type_name in LOST:
                        # the batch took its worker with it: each episode again, alone
                        self.alone = self.executor.submit(self.jobs)
                        if self.batching is not None:
                            self.batching.note_alone(WORKER_DIED, len(self.jobs))
                    else:
                        self.outcomes = [got] * len(self.jobs)
                else:
                    self.outcomes, counts = got
                    if self.batching is not None:
                        self.batching.batched += counts["batched"]
                        self.batching.batches += counts["batches"]
                        for why, n in counts["why_alone"].items():
                            self.batching.note_alone(why, n)
            self.open.discard(k)
        if self.alone is not None:
            return self.alone[k].outcome()
        return self.outcomes[k]

    def cancel(self, k: int) -> None:
        with self.lock:
            self.open.discard(k)
            if self.open or self.outcomes is not None:
                return
            if self.alone is not None:
                for p in self.alone:
                    p.cancel()
            else:
                self.pending.cancel()


def submit_batched(executor: Any, jobs: Sequence[Any], size: int, batching: Any = None,
                   engine: str = "cpu") -> list[Pending]:
    """``executor.submit(jobs)``, with consecutive jobs of one subject and the same limits sent as
    batch jobs of up to ``size`` episodes (see the module docstring); one Pending per job, in
    order. ``batching`` (a harness.batch.Batching) counts how the batch jobs ran, as their results
    are taken."""
    if size <= 1:
        return executor.submit(jobs)
    out: list[Pending | None] = [None] * len(jobs)
    chunks: list[list[int]] = []
    last = None
    for i, job in enumerate(jobs):
        key = _key(job)
        if key is None or key != last or len(chunks[-1]) >= size:
            chunks.append([i])
        else:
            chunks[-1].append(i)
        last = key
    submitted = [jobs[c[0]] if len(c) == 1 else BatchJob(tuple(jobs[i] for i in c), size, engine=engine)
                 for c in chunks]
    for c, p in zip(chunks, executor.submit(submitted)):
        if len(c) == 1:
            out[c[0]] = p
            if batching is not None:
                key = _key(jobs[c[0]])
                batching.note_alone(EXEC_ALONE if key is None else "nothing to batch it with")
            continue
        shared = _Shared(executor, [jobs[i] for i in c], p, batching)
        for k, i in enumerate(c):
            out[i] = Pending(jobs[i], lambda shared=shared, k=k: shared.outcome(k),
                             lambda shared=shared, k=k: shared.cancel(k))
    return out     # type: ignore[return-value]

