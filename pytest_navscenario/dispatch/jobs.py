"""What crosses to a worker and back: a job out (an ``EpisodeJob``, or any picklable object with
``run()`` and ``restore(outcome)``, such as the search's candidate jobs), a compact result (or the
job's exception) back, and ``Pending``, the handle every executor returns per job.

Compact: the worker drops the scenario from the result (the caller already holds it and puts it
back) and, unless asked for, the trajectory (the bulk: ~60-400 KiB per episode, against ~2 KiB
for outcome, metrics and events). Numpy arrays pickle exactly, so a result that crossed is equal,
bit for bit, to one computed in place.
"""
from __future__ import annotations

import os
import pickle
import socket
import traceback
from dataclasses import dataclass
from typing import Any, Callable

from ..core.errors import NavScenarioError
from ..scenario.model import Scenario
from ..verdict.result import EpisodeResult

KEEP_CHOICES = ("all", "failed", "none")


@dataclass(frozen=True)
class EpisodeJob:
    """One episode to run: ``run_scenario(scenario, subject, seed=seed, tick_limit=tick_limit)``.

    ``subject``: a spec string (``dwa``, ``pkg.mod:Attr``, ``exec:PROGRAM ARGS``) or a picklable
    planner factory. ``keep_trajectory``: which results bring their trajectory back ("all",
    "failed": outcome not success, "none"). ``cwd``: the folder an ``exec:`` program is resolved
    and started in (a Ray worker's own working folder is not the user's)."""
    scenario: Scenario
    subject: Any = None
    seed: int | None = None
    tick_limit: float | None = None
    keep_trajectory: str = "all"
    cwd: str | None = None
    reset_timeout: float | None = None    # s an exec: planner may take to answer reset (None: its default)
    check_feasible: bool = False          # first verdict.feasibility: an impassable scenario is not run

    def __post_init__(self) -> None:
        if self.keep_trajectory not in KEEP_CHOICES:
            raise ValueError(f"keep_trajectory must be one of {KEEP_CHOICES}, got {self.keep_trajectory!r}")

    def run(self) -> EpisodeResult | Impassable:
        """Worker side: the episode, compacted for the way back; with ``check_feasible``, an
        ``Impassable`` instead for a scenario no planner can pass (nothing simulated)."""
        from ..harness.runner import add_check_time, check_feasibility, run_scenario

        checked = 0.0
        if self.check_feasible:
            found, checked = check_feasibility(self.scenario)
            if found is not None:
                return Impassable(str(found), found.field)
        result = run_scenario(self.scenario, _subject_for(self), seed=self.seed, tick_limit=self.tick_limit,
                              reset_timeout=self.reset_timeout)
        return compact(add_check_time(result, checked), self.keep_trajectory)

    def restore(self, result: EpisodeResult | Impassable) -> EpisodeResult | Impassable:
        """Caller side: put the scenario back."""
        if isinstance(result, Impassable):
            return result
        result.scenario = self.scenario
        return result


@dataclass(frozen=True)
class Impassable:
    """What a job with ``check_feasible`` returns for a scenario no planner can pass (or that
    passes without one, or simulates the impossible): ``verdict.feasibility.infeasible``'s words and
    the field to fix (None when no one field is to blame)."""
    reason: str
    field: str | None = None


@dataclass
class EpisodeError:
    """An exception an episode raised in a worker: re-raised, as itself, by ``Pending.result``."""
    type_name: str
    message: str
    remote_traceback: str
    where: str
    pickled: bytes | None      # the exception itself when it survives pickling unchanged

    @classmethod
    def capture(cls, exc: BaseException, text: str | None = None) -> "EpisodeError":
        """The EpisodeError of ``exc``; ``text``: its traceback (default: the one being handled)."""
        pickled: bytes | None
        try:
            pickled = pickle.dumps(exc)
            back = pickle.loads(pickled)
            if type(back) is not type(exc) or str(back) != str(exc):
                pickled = None
        except Exception:
            pickled = None
        if text is None:
            text = traceback.format_exc()
        return cls(type(exc).__name__, str(exc), text, worker_name(), pickled)

    def exception(self) -> BaseException:
        exc: BaseException
        if self.pickled is not None:
            exc = pickle.loads(self.pickled)
        else:
            exc = RemoteEpisodeError(f"{self.type_name}: {self.message}")
        if hasattr(exc, "add_note"):
            exc.add_note(f"(raised in the episode worker {self.where}; its traceback:\n"
                         f"{self.remote_traceback.rstrip()})")
        return exc


class RemoteEpisodeError(NavScenarioError):
    """An episode raised an exception in a worker that cannot be rebuilt here (its type and
    message are kept)."""


def worker_name() -> str:
    return f"pid {os.getpid()} on {socket.gethostname()}"


# -- worker side ----------------------------------------------------------------------------------
_FACTORIES: dict[tuple[str, str | None], Callable[[], Any]] = {}


def _factory(spec: str, cwd: str | None) -> Callable[[], Any]:
    """The planner factory of a spec, loaded once per process; an ``exec:`` program is resolved
    in and started in ``cwd`` (so it is started once per process and reused)."""
    key = (spec.strip(), cwd)
    factory = _FACTORIES.get(key)
    if factory is None:
        from ..subjects.loading import load_subject
        factory = _FACTORIES[key] = load_subject(key[0], cwd=cwd)
    return factory


@dataclass(frozen=True)
class SubjectFactory:
    """A picklable planner factory for a subject spec: whichever process calls it loads the spec
    (once) and makes a fresh planner. What a worker gets instead of a loaded class or closure."""
    spec: str
    cwd: str | None = None

    def __call__(self) -> Any:
        return _factory(self.spec, self.cwd)()


def _subject_for(job: EpisodeJob) -> Any:
    """What run_scenario gets: the spec itself (so results name it as written), except
    ``exec:`` with a ``cwd``, which becomes a factory bound to that folder."""
    spec = job.subject
    if isinstance(spec, str) and spec.strip().startswith("exec:") and job.cwd:
        return _factory(spec, job.cwd)
    return spec


def compact(result: EpisodeResult, keep: str) -> EpisodeResult:
    """Strip what need not travel: the scenario always, the trajectory unless ``keep`` wants it."""
    result.scenario = None  # type: ignore[assignment]
    if keep == "none" or keep == "failed" and result.passed:
        from ..sim.trajectory import Trajectory
        result.trajectory = Trajectory.empty()
    return result


def run_job(job: Any) -> Any:
    """Run one job here (``job.run()``) and return its result, or its exception as an
    EpisodeError (never raises, so a pool or Ray never mistakes an episode's error for a lost
    worker)."""
    try:
        return job.run()
    except Exception as exc:
        return EpisodeError.capture(exc)


def run_job_on_worker(job: Any) -> Any:
    """``run_job`` in a worker process of Ray's: the planner's own KeyboardInterrupt or
    SystemExit is its episode's subject error there too (core/interrupts.py)."""
    from ..core.interrupts import running_for_another_process
    running_for_another_process()
    return run_job(job)


def restore(job: Any, outcome: Any) -> Any:
    """Caller side: raise the job's exception, or let the job complete its result."""
    if isinstance(outcome, EpisodeError):
        raise outcome.exception()
    return job.restore(outcome)


class Pending:
    """The handle of one submitted job. ``result()`` waits for it and returns the result (an
    EpisodeResult for an EpisodeJob) or raises the exception the job raised; ``cancel()`` gives
    it up (not started: it never runs; running: its result is dropped)."""

    def __init__(self, job: Any, wait: Callable[[], Any], cancel: Callable[[], None] | None = None):
        self.job = job
        self._wait = wait
        self._cancel = cancel
        self._outcome: Any = None

    def outcome(self) -> Any:
        """Wait for the job and return what came back as it is (an EpisodeError is not raised)."""
        if self._outcome is None:
            self._outcome = self._wait()
            self._wait = self._cancel = None  # type: ignore[assignment]  # drop the future / object ref
        return self._outcome

    def result(self) -> Any:
        return restore(self.job, self.outcome())

    def cancel(self) -> None:
        """Give the job up, unless its result was already taken (then nothing happens)."""
        if self._outcome is None and self._cancel is not None:
            self._cancel()
        self._wait = self._cancel = None  # type: ignore[assignment]
