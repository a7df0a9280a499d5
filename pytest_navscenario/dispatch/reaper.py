"""Stop what a run started on this machine when the run ends without stopping it.

A local Ray instance (``--nav-ray=auto``) is a tree of processes under the run's process: the
raylet, the GCS server, the dashboard, their agents, the workers. ``ray.shutdown()`` stops them;
a run that cannot call it (killed with SIGKILL, out of memory) leaves them to notice on their own:
the raylet does at once, but its dashboard and runtime-env agents were measured to linger for
1.5-2 minutes (Ray 2.60), holding memory and ports.

``start_reaper()`` starts a small watcher process: it notes the run's descendants every second
while the run lives (those started after the watcher: a planner program the run started before
is not its to end), and when the run closes the pipe it was given (the run stops it, or the run
dies, which closes it too) it ends every noted process still running (SIGTERM, then SIGKILL
after ``GRACE`` s). It ignores Ctrl-C (a Ctrl-C reaches the whole process group, and the run
itself decides what a Ctrl-C stops). Linux reads the process table from /proc, elsewhere from
``ps``.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from typing import Any

POLL = 1.0        # s between two looks at the run's descendants
GRACE = 3.0       # s between SIGTERM and SIGKILL


def _table() -> dict[int, tuple[int, str]]:
    """pid -> (parent pid, start time: a token that tells a reused pid apart)."""
    out: dict[int, tuple[int, str]] = {}
    if os.path.isdir("/proc/self"):
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                try:
                    with open(f"/proc/{entry}/stat", "rb") as fh:
                        fields = fh.read().rsplit(b")", 1)[1].split()
                    out[int(entry)] = (int(fields[1]), fields[19].decode())
                except (OSError, IndexError, ValueError):
                    continue
        return out
    try:
        text = subprocess.run(["ps", "-axo", "pid=,ppid="], capture_output=True, text=True, timeout=10).stdout
    except (OSError, subprocess.SubprocessError):
        return out
    for line in text.splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[0].isdigit() and parts[1].isdigit():
            out[int(parts[0])] = (int(parts[1]), "")
    return out


def descendants(root: int, table: dict[int, tuple[int, str]]) -> dict[int, str]:
    """Every descendant of ``root`` in ``table``: pid -> its start time."""
    children: dict[int, list[int]] = {}
    for pid, (ppid, _) in table.items():
        children.setdefault(ppid, []).append(pid)
    out, todo = {}, list(children.get(root, ()))
    while todo:
        pid = todo.pop()
        if pid not in out:
            out[pid] = table[pid][1]
            todo.extend(children.get(pid, ()))
    return out


def _end(noted: dict[int, str]) -> None:
    """SIGTERM to every noted process still running (the same start time), SIGKILL after GRACE."""
    def alive() -> list[int]:
        table = _table()
        return [pid for pid, start in noted.items() if pid in table and table[pid][1] == start]

    for sig, wait in ((signal.SIGTERM, GRACE), (signal.SIGKILL, 0.0)):
        for pid in alive():
            try:
                os.kill(pid, sig)
            except OSError:
                pass
        deadline = time.monotonic() + wait
        while wait and alive() and time.monotonic() < deadline:
            time.sleep(0.1)


def main(parent: int) -> None:
    """Watch ``parent`` until stdin reaches its end, then end its noted descendants."""
    import select

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    me = os.getpid()
    before = descendants(parent, _table())   # started before the watcher (an exec: planner): not its to end
    noted: dict[int, str] = {}
    while True:
        ready, _, _ = select.select([sys.stdin], [], [], POLL)
        if ready and not os.read(sys.stdin.fileno(), 4096):
            break
        table = _table()
        if parent not in table:   # gone, though a child it forked may hold the pipe open
            break
        for pid, start in descendants(parent, table).items():
            if pid != me and before.get(pid) != start:
                noted[pid] = start
    _end(noted)


class Reaper:
    """The run's side of a watcher process (``start_reaper``); ``stop()`` lets it end what it noted."""

    def __init__(self, proc: subprocess.Popen, writer: int):
        self.proc, self._writer = proc, writer

    def stop(self, wait: float = GRACE + 2.0) -> None:
        """Close the pipe (the watcher ends what is left of the run's descendants) and wait for it."""
        if self._writer >= 0:
            os.close(self._writer)
            self._writer = -1
        try:
            self.proc.wait(timeout=wait)
        except subprocess.TimeoutExpired:
            pass


def start_reaper() -> Any:
    """Start a watcher of this process's descendants (see the module docstring); None if it
    cannot be started (then nothing changes but the clean-up after a killed run)."""
    reader, writer = os.pipe()
    try:
        proc = subprocess.Popen([sys.executable, "-m", "pytest_navscenario.dispatch.reaper", str(os.getpid())],
                                stdin=reader, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                close_fds=True)
    except OSError:
        os.close(writer)
        return None
    finally:
        os.close(reader)
    os.set_inheritable(writer, False)
    return Reaper(proc, writer)


if __name__ == "__main__":
    main(int(sys.argv[1]))
