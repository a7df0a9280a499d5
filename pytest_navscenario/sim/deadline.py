"""Per-tick time limit for in-process planners.

A planner that takes longer than the limit is a subject error; one that hangs forever must not
hang the test run. In the main thread on POSIX an interval timer (SIGALRM) interrupts a planner
stuck in Python code; elsewhere (threads, Windows) the limit is checked after ``act`` returns.
A planner blocked inside C code that never returns cannot be interrupted in-process: run such
planners as external programs (``exec:``), which are killed and restarted.

The handler is installed once per episode and the timer armed per tick (two cheap syscalls), and any
timer set before (e.g. pytest-timeout's signal method) is restored afterwards with its remaining time.
"""
from __future__ import annotations

import signal
import threading
import time


# s: what one planner tick may take in a pytest item (--nav-tick-limit) and in `navscenario run`
# (the same, so that `run` gives the item's outcome): ten control periods at 10 Hz, so a slow
# planner is reported as a subject-error and one that hangs cannot stall a suite. The other
# defaults, and why: `navscenario check-planner` 10 s (harness.conformance.HUNG_TICK: it measures
# and reports slow ticks, so it lets them finish, and warns when a tick is over this limit);
# `run_scenario` in Python none (a library call runs the planner as any function call; nav_run
# passes --nav-tick-limit).
DEFAULT_TICK_LIMIT = 1.0


class PlannerTimeout(BaseException):
    """Raised inside a planner that overran its tick limit. A BaseException so that a planner's
    own ``except Exception:`` cannot swallow it."""


def _can_use_alarm() -> bool:
    return hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()


class TickDeadline:
    """Context manager for one episode: ``arm()`` before each ``act``, ``disarm()`` after."""

    def __init__(self, limit: float | None):
        self.limit = limit if limit and limit > 0 else None
        self._use_alarm = self.limit is not None and _can_use_alarm()
        self._old_handler = None
        self._old_timer = (0.0, 0.0)
        self._entered_at = 0.0
        self._armed_at = 0.0
        self.scale = 1          # a batch call of k episodes may take k times the limit (sim/batching/batch.py)

    def __enter__(self) -> "TickDeadline":
        if self._use_alarm:
            self._entered_at = time.monotonic()
            self._old_timer = signal.getitimer(signal.ITIMER_REAL)
            self._old_handler = signal.signal(signal.SIGALRM, self._on_alarm)
        return self

    def __exit__(self, *exc) -> None:
        if self._use_alarm:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, self._old_handler)
            remaining, interval = self._old_timer
            if remaining > 0:  # give the outer timer back what it had left (at least 1 ms)
                left = max(0.001, remaining - (time.monotonic() - self._entered_at))
                signal.setitimer(signal.ITIMER_REAL, left, interval)

    def _on_alarm(self, signum, frame) -> None:
        raise PlannerTimeout(f"planner did not answer within the per-tick limit of {self._limit_text()}")

    def _limit_text(self) -> str:
        if self.scale == 1:
            return f"{self.limit:g} s"
        return f"{self.limit * self.scale:g} s ({self.limit:g} s for each of the call's {self.scale} episodes)"

    def arm(self) -> None:
        if self.limit is None:
            return
        self._armed_at = time.perf_counter()
        if self._use_alarm:
            signal.setitimer(signal.ITIMER_REAL, self.limit * self.scale)

    def disarm(self) -> float:
        """Stop the timer; return the seconds since arm(). Raises PlannerTimeout if over the limit."""
        if self.limit is None:
            return 0.0
        if self._use_alarm:
            signal.setitimer(signal.ITIMER_REAL, 0)
        elapsed = time.perf_counter() - self._armed_at
        if elapsed > self.limit * self.scale:
            raise PlannerTimeout(
                f"planner took {elapsed:.3f} s for one tick, over the per-tick limit of {self._limit_text()}")
        return elapsed
