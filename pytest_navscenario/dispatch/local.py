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
import threading
import time
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any, Sequence

from ..core.interrupts import unmasked
from .jobs import EpisodeError, EpisodeJob, Pending, run_job, worker_name
from ..verdict.result import EpisodeResult

# Imported once by the forkserver, so that every worker starts with the simulation loaded.
PRELOAD = ["pytest_navscenario.harness.runner", "pytest_navscenario.sim.episode",
           "pytest_navscenario.verdict.metrics", "pytest_navscenario.verdict.oracle",
           "pytest_navscenario.verdict.feasibility",
           "pytest_navscenario.subjects.planners.dwa"]
MAX_ATTEMPTS = 3           # a job whose worker died this many times is reported as an error
STOP_GRACE = 2.0           # s the workers have to stop their planners' processes when the pool closes


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
    attempts: int = 0          # times the worker running this job died of it
    death: str = ""            # how it died the last time: "exit code 3", "killed by SIGKILL"


def _dead_workers(pool: ProcessPoolExecutor | None) -> dict[int, str]:
    """pid -> how it ended, of the workers of a broken pool that ended on their own (not by the
    SIGTERM with which the pool stops the others once one has died)."""
    if pool is None or not getattr(pool, "_broken", False):
        return {}
    procs = dict(getattr(pool, "_processes", None) or {})
    manager = getattr(pool, "_executor_manager_thread", None)
    if manager is not None:      # it stops and reaps the other workers (~0.1 s): then every code is
        manager.join(timeout=10)  # known, and only it reads them (two readers could garble one)
    dead = {}
    for pid, proc in procs.items():
        code = proc.exitcode
        if code is None or code == -signal.SIGTERM:
            continue
        dead[pid] = (f"killed by {signal.Signals(-code).name}" if code < 0 and -code in signal.valid_signals()
                     else f"exit code {code}")
    return dead


_STARTED: Any = None   # worker side: the pipe end on which a worker says which job it started


def _worker_init(started: Any, alive: Any = None) -> None:
    """In each worker: leave Ctrl-C to the parent (it cancels the batch and stops the pool),
    note started jobs, stop what the planners started (exec: programs, processes an in-process
    planner left) whenever the worker ends: at exit, on SIGTERM (a broken pool stops the others
    so), and when the parent is gone (``_exit_with_parent``)."""
    global _STARTED
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _stop_on_sigterm)
    _STARTED = started
    from multiprocessing.util import Finalize

    Finalize(None, _stop_planner_processes, exitpriority=10)
    if alive is not None:
        threading.Thread(target=_exit_with_parent, args=(alive,), name="navscenario-parent-watch",
                         daemon=True).start()


_STOPPING = threading.RLock()   # re-entered by the SIGTERM handler in the thread holding it


def _stop_planner_processes() -> None:
    """Worker side: end the exec: planner programs (their process groups) and the processes
    in-process planners left running (core/processes.py). Several ends may come at once (the
    worker's exit and its parent-watch thread): the first does the work, the others wait for it,
    so that none exits the process while the first is still ending a group."""
    from ..core.processes import end_left_behind
    from ..subjects.external import _shutdown_all
    with _STOPPING:
        try:
            _shutdown_all()
        finally:
            end_left_behind(grace=0.5)


def _stop_on_sigterm(signum: int, frame: Any) -> None:
    """Worker side: stop the planners' processes, then die of the SIGTERM as before (its exit
    code -15 tells the parent this worker was stopped, not killed by its episode)."""
    try:
        _stop_planner_processes()
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)


def _exit_with_parent(alive: Any) -> None:
    """Worker side: wait for the end of file on ``alive``, a pipe whose only writing end the
    parent holds, then stop this worker's planners' processes and exit. The end of file comes
    when the parent closes the pool or dies, even by SIGKILL: a pool's worker otherwise waits for
    its next job forever (it holds its job queue's writing end itself), and with it the
    forkserver and the resource tracker (they exit when the last process holding their pipes does)."""
    try:
        alive.recv()
    except (EOFError, OSError):
        pass
    try:
        _stop_planner_processes()
    finally:
        os._exit(0)


def _pool_run(key: int, job: Any) -> Any:
    _STARTED.send((key, os.getpid()))   # a few bytes: one atomic pipe write, whichever worker writes
    return run_job(job)


class _StartLog:
    """Which job each worker process started last (pid -> key), from the workers' pipe.

    A thread of this process reads the pipe as the messages come, so it never fills: unread, it
    held ~4000 messages, after which every worker blocked on its next one and the pool hung (a
    suite or a search of more than a few thousand episodes on -n 2). When a worker dies, the job it
    started last (unless that one finished) is the one that killed it."""

    def __init__(self, reader: Any):
        self._reader = reader
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self.last: dict[int, int] = {}          # pid -> key of the job it started last
        self._thread = threading.Thread(target=self._read, name="navscenario-pool-starts", daemon=True)
        self._thread.start()

    def _read(self) -> None:
        while not self._stop.is_set():
            try:
                if self._reader.poll(0.1):
                    with self._lock:
                        self._take()
            except (EOFError, OSError):
                return

    def _take(self) -> None:
        while self._reader.poll(0):
            key, pid = self._reader.recv()
            self.last[pid] = key

    def close(self) -> dict[int, int]:
        """Stop reading, take what is left in the pipe, and return pid -> last started key."""
        self._stop.set()
        self._thread.join(timeout=5)
        with self._lock:
            try:
                self._take()
            except (EOFError, OSError):
                pass
            self._reader.close()
        return self.last


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
        self._starts: _StartLog | None = None   # which job each worker started last
        self._alive: Any = None                 # writing end of the workers' "parent alive" pipe
        self._generation = 0
        self._keys = itertools.count()
        self._open: dict[int, _Slot] = {}      # submitted, result not yet taken
        self.deaths: list[str] = []            # each pool that broke: which worker died, what ran again

    def _ensure_pool(self) -> ProcessPoolExecutor:
        if self._pool is None:
            ctx = multiprocessing.get_context(self.start_method)
            if self.start_method == "forkserver":
                ctx.set_forkserver_preload(PRELOAD)
            # a plain pipe, not a SimpleQueue: its semaphore upsets the resource tracker at exit
            reader, writer = ctx.Pipe(duplex=False)
            self._starts = _StartLog(reader)
            alive, self._alive = ctx.Pipe(duplex=False)   # only this process holds the writing end
            self._pool = ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=_worker_init,
                                             initargs=(writer, alive))
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
        """Each job on the pool. A pool broken since the last look (a worker died between two
        batches: a search submits its next generation before it waits) is replaced first, its
        unfinished jobs run again (``_recover``), instead of refusing every later job."""
        if self._pool is not None and getattr(self._pool, "_broken", False):
            self._recover()
        pool = self._ensure_pool()
        pendings = []
        for job in jobs:
            key = next(self._keys)
            try:
                future = pool.submit(_pool_run, key, job)
            except BrokenProcessPool:     # it broke while this batch was being submitted
                self._recover()
                pool = self._ensure_pool()
                future = pool.submit(_pool_run, key, job)
            slot = _Slot(key, job, future, self._generation)
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
                                        f"{slot.attempts} times (last: {slot.death}; the planner ended "
                                        f"its process or crashed the interpreter, or the process was "
                                        f"killed or ran out of memory); it was not run again",
                                        "", worker_name(), None)
                continue
            except RuntimeError as exc:      # after BrokenProcessPool, a RuntimeError too
                if unmasked(exc) is not exc:    # the user's interrupt, surfaced as a lock error
                    raise unmasked(exc) from None
                raise
            self._open.pop(slot.key, None)
            return outcome

    def _cancel(self, slot: _Slot) -> None:
        """Drop ``slot``: a job not started never runs, a running one finishes unread."""
        slot.future.cancel()
        self._open.pop(slot.key, None)

    def _recover(self) -> None:
        """The pool broke (a worker died): run every unfinished job again on a new pool. Only the
        job whose episode killed its worker (the one that worker started last) counts an attempt;
        the jobs the pool stopped with it are innocent and run again as if nothing had happened. If
        no worker can be singled out (each ended by SIGTERM, as the pool ends the others), every
        job that had started counts one."""
        old, self._pool = self._pool, None
        starts, self._starts = self._starts, None
        dead = _dead_workers(old)
        last = starts.close() if starts is not None else {}
        if old is not None:
            old.shutdown(wait=False, cancel_futures=True)
        self._let_workers_go()
        culprits = {last[pid]: why for pid, why in dead.items() if pid in last}
        started = set(last.values())
        pool = self._ensure_pool()
        again = 0
        for slot in self._open.values():
            done_ok = slot.future.done() and not slot.future.cancelled() and slot.future.exception() is None
            if done_ok:
                continue
            if slot.key in culprits or (not culprits and slot.key in started):
                # a batch job is not run again whole (dispatch/batches.py): its episodes go alone
                slot.attempts += MAX_ATTEMPTS if getattr(slot.job, "alone_after_death", False) else 1
                slot.death = culprits.get(slot.key, "ended by a signal")
            if slot.attempts < MAX_ATTEMPTS:   # else its broken future stays: _wait reports it
                slot.future = pool.submit(_pool_run, slot.key, slot.job)
                slot.generation = self._generation
                again += 1
        who = "; ".join(f"worker pid {pid} {why}" for pid, why in sorted(dead.items())) or "a worker process died"
        self.deaths.append(f"{who}: the pool was replaced and {again} unfinished job(s) were run again")

    def _let_workers_go(self) -> None:
        """Close this process's end of the "parent alive" pipe: every worker still running exits."""
        alive, self._alive = self._alive, None
        if alive is not None:
            alive.close()

    def close(self, cancel: bool = False) -> None:
        """Stop the workers; with ``cancel`` (Ctrl-C, an error) at once, dropping unfinished jobs."""
        pool, self._pool = self._pool, None
        starts, self._starts = self._starts, None
        self._open.clear()
        try:
            if pool is None:
                return
            if not cancel:
                pool.shutdown(wait=True)
                self._let_workers_go()
                return
            procs = list((getattr(pool, "_processes", None) or {}).values())   # gone after shutdown
            pool.shutdown(wait=False, cancel_futures=True)
            self._let_workers_go()    # each worker stops its exec: planners and leftovers, and exits
            deadline = time.monotonic() + STOP_GRACE
            for proc in procs:
                proc.join(timeout=max(0.0, deadline - time.monotonic()))
            for proc in procs:        # one stuck in C code that ignores its parent-watch thread
                if proc.exitcode is None:
                    try:
                        proc.kill()
                    except Exception:
                        pass
            for proc in procs:
                proc.join(timeout=5)
        finally:
            if starts is not None:     # after the workers: none is left to write to its pipe
                starts.close()


def make_local_executor(workers: int | None) -> SerialExecutor | ProcessExecutor:
    """Serial for ``workers`` of None or 1 (no process start-up to pay), else a pool."""
    if workers is None or workers == 1:
        return SerialExecutor()
    return ProcessExecutor(workers)
