"""Telling a user's Ctrl-C (or SIGTERM) from a planner that raises KeyboardInterrupt or SystemExit.

A planner's own ``sys.exit()`` or ``raise KeyboardInterrupt`` must end only its episode (a subject
error), while a real Ctrl-C must stop the run, although both arrive as the same exception inside
the planner's code. ``install()`` replaces Python's default SIGINT handler and the default SIGTERM
action with handlers that raise ``UserInterrupt`` (a KeyboardInterrupt, so every caller handles it
as before); ``from_the_user(exc)`` then tells the two apart. Without the handlers (a library user's
script) every KeyboardInterrupt counts as the user's: it stops the run, as it always did.
"""
from __future__ import annotations

import signal
import threading
from typing import Any, Callable


class UserInterrupt(KeyboardInterrupt):
    """A Ctrl-C (SIGINT) or SIGTERM received while the handlers of ``install()`` were active."""


class PlannerExit(Exception):
    """The planner's own code raised SystemExit, KeyboardInterrupt or GeneratorExit: an ordinary
    subject error of its episode (the original exception is the ``__cause__``)."""

    def __init__(self, original: BaseException):
        what = f"{type(original).__name__}: {original}" if str(original) else type(original).__name__
        super().__init__(f"the planner's own code raised {what} (a planner ends its episode, "
                         f"not the test run)")
        self.original = original


def _on_sigint(signum: int, frame: Any) -> None:
    raise UserInterrupt("interrupted by Ctrl-C (SIGINT)")


def _on_sigterm(signum: int, frame: Any) -> None:
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # a second SIGTERM kills at once
    raise UserInterrupt("interrupted by SIGTERM")


def install(sigterm: bool = True) -> Callable[[], None] | None:
    """Mark real interrupts (main thread only; a handler someone else installed is left alone).
    SIGTERM then ends the run like Ctrl-C. Returns the function that restores the old handlers."""
    if threading.current_thread() is not threading.main_thread():
        return None
    undo = []
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _on_sigint)
        undo.append((signal.SIGINT, signal.default_int_handler))
    if sigterm and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _on_sigterm)
        undo.append((signal.SIGTERM, signal.SIG_DFL))

    def restore() -> None:
        for signum, handler in undo:
            if signal.getsignal(signum) in (_on_sigint, _on_sigterm):
                signal.signal(signum, handler)
    return restore


_WORKER = False   # set in a process that only runs episodes for another one (a Ray worker)


def running_for_another_process() -> None:
    """Mark this process as a worker whose Ctrl-C belongs to the process that submitted the
    episodes (Ray workers: Ray turns a task's KeyboardInterrupt into a cancelled task). There a
    KeyboardInterrupt inside the planner is the planner's own, as in a serial run."""
    global _WORKER
    _WORKER = True


def from_the_user(exc: BaseException) -> bool:
    """True if ``exc`` must stop the run: a marked interrupt, or any KeyboardInterrupt while
    interrupts are not marked (then a real Ctrl-C cannot be told apart). A process that ignores
    SIGINT (a local worker: its parent handles Ctrl-C) never gets a Ctrl-C as an exception, so
    there a KeyboardInterrupt is the planner's own."""
    if isinstance(exc, UserInterrupt):
        return True
    if _WORKER:
        return False
    handler = signal.getsignal(signal.SIGINT)
    return isinstance(exc, KeyboardInterrupt) and handler is not _on_sigint and handler is not signal.SIG_IGN
