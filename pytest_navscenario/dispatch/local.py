"""Executors on this machine: in this process (``SerialExecutor``) or on worker processes
(``ProcessExecutor``, every core by default).

Why ``concurrent.futures.ProcessPoolExecutor`` with the ``forkserver`` start method:
- a pool of long-lived workers: the subject is loaded once per worker (an ``exec:`` program is
  started once per worker and reused, as under xdist), and each job is one small message;
- futures: results come back in job order whatever order the episodes finish in, and a worker
  that dies is reported (``BrokenProcessPool``) instead of hanging, which ``multiprocessing.Pool``
  does; its unfinished jobs are then run again on a new pool, so nothing is lost;
- ``forkserver``: each worker forks from a clean server process that has imported the simulation
  once (numpy, MuJoCo; ~0.4 s paid once, not per worker), not from pytest's process, whose
  threads and open ``exec:`` planner pipes a plain ``fork`` would copy (unsafe, and the default
  from Python 3.14 on); ``spawn`` where there is no forkserver (macOS, Windows). Workers get the
  parent's ``sys.path`` and working folder, so a subject importable here is importable there;
  a planner factory from a conftest hook must be picklable (a module-level class or function).
An xdist-style worker (a whole pytest per worker, execnet) would repeat the collection and the
subject check in every worker for no gain: a job needs only the scenario and the subject spec.
"""
from __future__ import annotations

import itertools
import multiprocessing
import os
import pickle
import signal
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any, Sequence

from .jobs import EpisodeError, EpisodeJob, Pending, run_job, worker_name
from ..verdict.result import EpisodeResult

# Imported once by the forkserver, so that every worker starts with the simulation loaded.
PRELOAD = ["pytest_navscenario.harness.runner", "pytest_navscenario.sim.episode",
           "pytest_navscenario.verdict.metrics", "pytest_navscenario.verdict.oracle",
           "pytest_navscenario.verdict.feasibility",
           "pytest_navscenario.subjects.planners.dwa"]
MAX_ATTEMPTS = 3           # a job whose worker died this many times is reported as an error


def available_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def default_start_method() -> str:
    return "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"


class SerialExecutor:
    """Runs each job in this process when its result is asked for (the reference: every other
    executor must give the same bits)."""

    workers = 1
    description = "this process"

    def submit(self, jobs: Sequence[Any]) -> list[Pending]:
        return [Pending(job, lambda job=job: run_job(job)) for job in jobs]

    def map(self, jobs: Sequence[Any]) -> list[Any]:
        return [p.result() for p in self.submit(jobs)]

    def close(self, cancel: bool = False) -> None:
        pass


@dataclass(eq=False)
class _Slot:
    key: int
    job: EpisodeJob
    future: Future
    generation: int
    attempts: int = 0


_STARTED: Any = None   # worker side: the pipe end on which a worker says which job it started


def _worker_init(started: Any) -> None:
    """In each worker: leave Ctrl-C to the parent (it cancels the batch and stops the pool),
    note started jobs, and stop exec: planner programs when the worker exits."""
    global _STARTED
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _STARTED = started
    from multiprocessing.util import Finalize

    from ..subjects.external import _shutdown_all
    Finalize(None, _shutdown_all, exitpriority=10)


def _pool_run(key: int, job: Any) -> Any:
    _STARTED.send(key)   # a few bytes: one atomic pipe write, whichever worker writes at once
    return run_job(job)


class _Warm:
    """A job that does nothing: submitted to start the workers ahead of the first real batch."""

    def run(self) -> None:
        return None

    def restore(self, outcome: None) -> None:
        return None


class ProcessExecutor:
    """Jobs on ``workers`` local worker processes (created on the first submit, reused)."""

    def __init__(self, workers: int | None = None, *, start_method: str | None = None):
        workers = available_cores() if workers is None else int(workers)
        if workers < 1:
            raise ValueError(f"a process pool needs at least one worker, got {workers}")
        self.workers = workers
        self.start_method = start_method or default_start_method()
        self.description = f"{workers} local worker process(es) ({self.start_method})"
        self._pool: ProcessPoolExecutor | None = None
        self._started: Any = None               # reading end of the workers' "started" pipe
        self._generation = 0
        self._keys = itertools.count()
        self._open: dict[int, _Slot] = {}      # submitted, result not yet taken

    def _ensure_pool(self) -> ProcessPoolExecutor:
        if self._pool is None:
            ctx = multiprocessing.get_context(self.start_method)
            if self.start_method == "forkserver":
                ctx.set_forkserver_preload(PRELOAD)
            # a plain pipe, not a SimpleQueue: its semaphore upsets the resource tracker at exit
            self._started, writer = ctx.Pipe(duplex=False)
            self._pool = ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=_worker_init,
                                             initargs=(writer,))
            self._generation += 1
        return self._pool

    def warm(self) -> None:
        """Start the workers now, in the background (the forkserver imports the simulation once,
        ~0.5-1.5 s), so that they are ready when the first batch comes."""
        self.submit([_Warm() for _ in range(self.workers)])

    def check_picklable(self, subject: Any) -> None:
        """ValueError if ``subject`` cannot be sent to a worker (e.g. a lambda from a hook)."""
        if isinstance(subject, str) or subject is None:
            return
        try:
            pickle.dumps(subject)
        except Exception as exc:
            raise ValueError(
                f"the subject {subject!r} cannot be sent to worker processes ({type(exc).__name__}: "
                f"{exc}); make the pytest_navscenario_make_subject hook return a module-level class "
                f"or function, or a 'package.module:Attribute' string") from None

    def submit(self, jobs: Sequence[Any]) -> list[Pending]:
        pool = self._ensure_pool()
        pendings = []
        for job in jobs:
            key = next(self._keys)
            slot = _Slot(key, job, pool.submit(_pool_run, key, job), self._generation)
            self._open[key] = slot
            pendings.append(Pending(job, lambda slot=slot: self._wait(slot), lambda slot=slot: self._cancel(slot)))
        return pendings

    def map(self, jobs: Sequence[Any]) -> list[Any]:
        return [p.result() for p in self.submit(jobs)]

    def _wait(self, slot: _Slot) -> Any:
        while True:
            try:
                outcome = slot.future.result()
            except BrokenProcessPool:
                if slot.generation == self._generation:
                    self._recover()
                if slot.attempts >= MAX_ATTEMPTS:
                    self._open.pop(slot.key, None)
                    return EpisodeError("WorkerDied", f"the worker process running this episode died "
                                        f"{slot.attempts} times (killed, out of memory, or the planner "
                                        f"crashed the interpreter); it was not run again",
                                        "", worker_name(), None)
                continue
            self._open.pop(slot.key, None)
            return outcome

    def _cancel(self, slot: _Slot) -> None:
        """Drop ``slot``: a job not started never runs, a running one finishes unread."""
        slot.future.cancel()
        self._open.pop(slot.key, None)

    def _recover(self) -> None:
        """The pool broke (a worker died): run every unfinished job again on a new pool; the jobs
        that had started count an attempt (the one that killed its worker is among them)."""
        started = set()
        while self._started is not None and self._started.poll():
            started.add(self._started.recv())
        old, self._pool = self._pool, None
        if old is not None:
            old.shutdown(wait=False, cancel_futures=True)
        pool = self._ensure_pool()
        for slot in self._open.values():
            done_ok = slot.future.done() and not slot.future.cancelled() and slot.future.exception() is None
            if done_ok:
                continue
            if slot.key in started:   # a batch job is not run again whole (dispatch/batches.py)
                slot.attempts += MAX_ATTEMPTS if getattr(slot.job, "alone_after_death", False) else 1
            if slot.attempts < MAX_ATTEMPTS:
                slot.future = pool.submit(_pool_run, slot.key, slot.job)
            slot.generation = self._generation

    def close(self, cancel: bool = False) -> None:
        """Stop the workers; with ``cancel`` (Ctrl-C, an error) at once, dropping unfinished jobs."""
        pool, self._pool = self._pool, None
        self._open.clear()
        if pool is None:
            return
        if not cancel:
            pool.shutdown(wait=True)
            return
        procs = list((getattr(pool, "_processes", None) or {}).values())   # gone after shutdown
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in procs:
            try:
                proc.kill()
            except Exception:
                pass
        for proc in procs:
            proc.join(timeout=5)


def make_local_executor(workers: int | None) -> SerialExecutor | ProcessExecutor:
    """Serial for ``workers`` of None or 1 (no process start-up to pay), else a pool."""
    if workers is None or workers == 1:
        return SerialExecutor()
    return ProcessExecutor(workers)
