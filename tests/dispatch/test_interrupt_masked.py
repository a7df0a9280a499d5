"""A Ctrl-C or SIGTERM that arrives while ``threading.Condition.wait`` has let go of its lock (the
plugin waiting on an episode's Future) comes out of the ``with`` block as ``RuntimeError: cannot
release un-acquired lock`` with the user's interrupt as its context. Seen once in five CI runs of
tests/plugin/test_results_file_safety.py (the item failed instead of the run stopping): the executor
raises the interrupt it hides. The race itself cannot be timed from a test; the exception's shape is
made here with a real lock."""
from __future__ import annotations

import threading

import pytest

from pytest_navscenario.core.interrupts import UserInterrupt, unmasked


def _lock_error_hiding(exc: BaseException) -> RuntimeError:
    lock = threading.Lock()
    try:
        try:
            raise exc
        finally:
            lock.release()          # not held: what Condition.__exit__ does after the race
    except RuntimeError as err:
        return err
    raise AssertionError("no RuntimeError")


def test_the_users_interrupt_behind_a_lock_error_is_what_stops_the_run():
    err = _lock_error_hiding(UserInterrupt("interrupted by SIGTERM"))
    assert isinstance(unmasked(err), UserInterrupt)
    assert str(unmasked(err)) == "interrupted by SIGTERM"


@pytest.mark.parametrize("hidden", [ValueError("the planner's"), KeyboardInterrupt("the planner's own")])
def test_other_errors_stay_what_they_are(hidden):
    err = _lock_error_hiding(hidden)
    assert unmasked(err) is err
    plain = RuntimeError("a planner's own RuntimeError")
    assert unmasked(plain) is plain
