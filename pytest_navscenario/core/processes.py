"""Processes a planner leaves behind: ending an ``exec:`` planner's whole process group, and
finding (then ending) the children an in-process planner started and did not end.

An in-process planner runs inside this process, so whatever it starts with ``fork`` or ``Popen``
is a child of ours. The harness takes the list of our children before an episode and again after
it (``children``); the new ones still running are the planner's (``note_left_behind``), reported
with the episode and ended when the run ends (``end_left_behind``), not at once: a planner may
keep a helper process on purpose for its next episodes. Children are read from
``/proc/<pid>/task/<tid>/children`` (Linux; elsewhere nothing is found, and nothing is ended); a
process is named by its pid and start time, so a pid the system reused is never signalled.
A grandchild whose parent exited was adopted by another process and is out of reach here.
"""
from __future__ import annotations

import os
import signal
import time
from dataclasses import dataclass


class LeftRunningWarning(UserWarning):
    """A planner started processes that were still running after its episode."""


@dataclass(frozen=True)
class Leftover:
    pid: int
    started: int          # start time in clock ticks since boot (/proc/<pid>/stat): tells a reused pid
    command: str
    episode: str          # the episode after which it was found


_LEFT: dict[int, Leftover] = {}


def children(pid: int | None = None) -> set[int]:
    """The running children of ``pid`` (this process by default); empty where /proc is missing."""
    pid = os.getpid() if pid is None else pid
    found: set[int] = set()
    try:
        tasks = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return found
    for tid in tasks:
        try:
            with open(f"/proc/{pid}/task/{tid}/children", "rb") as fh:
                found.update(int(p) for p in fh.read().split())
        except (OSError, ValueError):
            continue
    return found


def _stat(pid: int) -> tuple[str, int] | None:
    """(state letter, start time) of ``pid``, or None if it is gone."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            text = fh.read().decode("ascii", "replace")
    except OSError:
        return None
    fields = text[text.rfind(")") + 2:].split()    # after "pid (comm) "; comm may hold spaces
    try:
        return fields[0], int(fields[19])
    except (IndexError, ValueError):
        return None


def command_of(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as fh:
            words = [w.decode("utf-8", "replace") for w in fh.read().split(b"\0") if w]
    except OSError:
        return "?"
    text = " ".join(words) or "?"
    return text if len(text) <= 100 else text[:97] + "..."


def note_left_behind(before: set[int], episode: str, ours: set[int] = frozenset()) -> list[Leftover]:
    """Our children now running that were not running in ``before`` (nor in ``ours``, processes
    the harness itself started): remembered to be ended with the run, and returned."""
    found = []
    for pid in sorted(children() - before - set(ours)):
        stat = _stat(pid)
        if stat is None or stat[0] == "Z" or pid in _LEFT:
            continue
        left = Leftover(pid, stat[1], command_of(pid), episode)
        _LEFT[pid] = left
        found.append(left)
    return found


def end_left_behind(grace: float = 1.0) -> list[Leftover]:
    """End every process ``note_left_behind`` found that still runs (SIGTERM, after ``grace``
    seconds SIGKILL) and reap those that are our children. Returns the ones it signalled."""
    alive = [left for left in _LEFT.values() if _same(left)]
    _LEFT.clear()
    for left in alive:
        _signal(left, signal.SIGTERM)
    deadline = time.monotonic() + grace
    waiting = list(alive)
    while waiting and time.monotonic() < deadline:
        waiting = [left for left in waiting if not _reap(left)]
        if waiting:
            time.sleep(0.02)
    for left in waiting:
        _signal(left, signal.SIGKILL)
        _reap(left, block=True)
    return alive


def _same(left: Leftover) -> bool:
    stat = _stat(left.pid)
    return stat is not None and stat[1] == left.started and stat[0] != "Z"


def _signal(left: Leftover, signum: int) -> None:
    if _same(left):
        try:
            os.kill(left.pid, signum)
        except OSError:
            pass


def _reap(left: Leftover, block: bool = False) -> bool:
    """True once ``left`` has ended (reaped if it was our child)."""
    try:
        pid, _ = os.waitpid(left.pid, 0 if block else os.WNOHANG)
        if pid == left.pid:
            return True
    except ChildProcessError:       # not our child (any more): gone once its stat is
        pass
    except OSError:
        return True
    return not _same(left)


def end_group(pgid: int, grace: float = 1.0) -> None:
    """End every process of the process group ``pgid`` (an ``exec:`` planner's session: the
    program and whatever it started, as a launch file starts nodes): SIGTERM, then after
    ``grace`` seconds SIGKILL. Nothing happens where process groups do not exist (Windows)."""
    killpg = getattr(os, "killpg", None)
    if killpg is None:
        return
    try:
        killpg(pgid, signal.SIGTERM)
    except OSError:                 # no process left in the group
        return
    deadline = time.monotonic() + grace
    while time.monotonic() < deadline:
        if not _group_running(pgid):
            return
        time.sleep(0.02)
    try:
        killpg(pgid, signal.SIGKILL)
    except OSError:
        pass


def _group_running(pgid: int) -> bool:
    """True while a live (not zombie) process is in group ``pgid``. Adopted members are reaped
    by their new parent; a zombie left for a moment does not count."""
    try:
        os.killpg(pgid, 0)
    except OSError:
        return False
    try:
        pids = [int(p) for p in os.listdir("/proc") if p.isdigit()]
    except OSError:
        return True                 # no /proc: the signal reached someone
    for pid in pids:
        try:
            with open(f"/proc/{pid}/stat", "rb") as fh:
                text = fh.read().decode("ascii", "replace")
        except OSError:
            continue
        fields = text[text.rfind(")") + 2:].split()
        if len(fields) > 2 and fields[2] == str(pgid) and fields[0] != "Z":
            return True
    return False
