"""Telling a user's Ctrl-C (or SIGTERM) from a planner that raises KeyboardInterrupt or SystemExit.

A planner's own ``sys.exit()`` or ``raise KeyboardInterrupt`` must end only its episode (a subject
error), while a real Ctrl-C must stop the run, although both arrive as the same exception inside
the planner's code. ``install()`` replaces Python's default SIGINT handler and the default SIGTERM
action with handlers that raise ``UserInterrupt`` (a KeyboardInterrupt, so every caller handles it
as before); ``from_the_user(exc)`` then tells the two apart. Without the handlers (a library user's
script) every KeyboardInterrupt counts as the user's: it stops the run, as it always did.

Once the first interrupt has been raised the run is stopping and saving what it found (frozen
failures, the search log, the results and JUnit files): a second Ctrl-C or SIGTERM is held (noted,
not raised), so that it cannot abort the saving half way; a third one acts at once (Ctrl-C raises,
SIGTERM ends the process), for a run whose saving hangs. ``deferred()`` holds interrupts for the
length of a block that must not be cut in two (a file write, a Hypothesis draw) and delivers the
first one after it.
"""
from __future__ import annotations

import contextlib
import signal
import threading
import types
from typing import Any, Callable, Iterator


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


_RECEIVED: list[int] = []   # the interrupts received while the handlers of install() were active


def _on_sigint(signum: int, frame: Any) -> None:
    _received(signum, "interrupted by Ctrl-C (SIGINT)")


def _on_sigterm(signum: int, frame: Any) -> None:
    _received(signum, "interrupted by SIGTERM")


def _received(signum: int, message: str) -> None:
    """The first interrupt raises; the second is held (the run is stopping and saving what it
    found); from the third on, the default action: Ctrl-C raises, SIGTERM ends the process."""
    _RECEIVED.append(signum)
    if len(_RECEIVED) == 2:
        return
    if len(_RECEIVED) > 2 and signum == signal.SIGTERM:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.raise_signal(signal.SIGTERM)
    raise UserInterrupt(message)


def stopping() -> bool:
    """True once a user's Ctrl-C or SIGTERM has been raised in this process (the run is ending)."""
    return bool(_RECEIVED)


def held() -> int:
    """How many interrupts were held (received after the first, while the run was saving)."""
    return max(0, min(len(_RECEIVED), 2) - 1)


def first_signal() -> str:
    """The name of the interrupt that stopped the run ("Ctrl-C" or "SIGTERM"); "" if none did."""
    if not _RECEIVED:
        return ""
    return "SIGTERM" if _RECEIVED[0] == signal.SIGTERM else "Ctrl-C"


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """Hold Ctrl-C and SIGTERM until the block ends, then deliver the first one received to the
    handler that was in place (a block cut in two by an interrupt would leave a half-done state:
    a Hypothesis engine not yet set up, a file not yet renamed into place). Main thread only (where
    Python runs signal handlers); elsewhere a no-op."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got: list[int] = []
    saved = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            saved[sig] = signal.signal(sig, lambda s, _frame: got.append(s))
        except (ValueError, OSError):
            pass
    try:
        yield
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, handler)
        if got:   # deliver the first one now, to the handler that was in place
            handler = saved.get(got[0])
            try:
                if callable(handler):
                    handler(got[0], None)
                elif handler == signal.SIG_DFL:
                    signal.raise_signal(got[0])
            finally:   # more than one: the run is stopping, the others count as held
                if handler in (_on_sigint, _on_sigterm):
                    _RECEIVED.extend(got[1:2])


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

    if undo:
        _RECEIVED.clear()

    def restore() -> None:
        _RECEIVED.clear()
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


def unmasked(exc: BaseException) -> BaseException:
    """The user's interrupt that ``exc`` hides, else ``exc``. A signal whose handler raises
    ``UserInterrupt`` while ``threading.Condition.wait`` has let go of its lock (waiting on a
    ``Future``) leaves the ``with`` block releasing a lock it does not hold: the interrupt comes out
    as ``RuntimeError('cannot release un-acquired lock')`` with the interrupt as its context, and an
    item failed with that error instead of the run stopping (seen once in five CI runs)."""
    if isinstance(exc, RuntimeError) and isinstance(exc.__context__, UserInterrupt):
        return exc.__context__
    return exc


def with_line_numbers(exc: BaseException) -> bool:
    """Give every frame of ``exc``'s traceback, and of the exceptions chained to it, a line number:
    CPython 3.11 reports ``tb_lineno`` None for a frame interrupted on an instruction that has none
    (a signal's handler raised there), on which pytest's report of the interruption fails ("unsupported
    operand type(s) for -: 'NoneType' and 'int"), ending the run with status 1 and no summary. Such a
    frame gets its function's first line. True when one had none."""
    seen: set[int] = set()
    renumbered = False
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        entries, tb = [], exc.__traceback__
        while tb is not None:
            entries.append(tb)
            tb = tb.tb_next
        if any(t.tb_lineno is None for t in entries):
            numbered = None
            for t in reversed(entries):
                if t.tb_lineno is None:        # its instruction unknown too (-1: no column to show)
                    numbered = types.TracebackType(numbered, t.tb_frame, -1, t.tb_frame.f_code.co_firstlineno)
                else:
                    numbered = types.TracebackType(numbered, t.tb_frame, t.tb_lasti, t.tb_lineno)
            exc.__traceback__ = numbered
            renumbered = True
        exc = exc.__cause__ or exc.__context__
    return renumbered
