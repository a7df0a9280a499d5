"""Black-box planners in any language: a subprocess spoken to in JSON Lines over stdin/stdout.

Subject spec: ``exec:COMMAND [ARGS...]`` (shell-like quoting), e.g. ``exec:./my_planner --fast``.
The program is started once per process (per xdist worker) and reused across episodes; it is
restarted after it crashed, exited, hung or broke the protocol.

Protocol ``navscenario-exec`` version 1 -- one JSON object per line, UTF-8:

harness -> planner
  {"type": "reset", "protocol": "navscenario-exec", "version": 1,
   "scenario": {...the scenario as in YAML (scenario_to_dict): metres, seconds, degrees...}}
  {"type": "observation", "tick": 0, "time": 0.0, "pose": [x, y, yaw_rad],
   "velocity": [vx, vy, wz], "ranges": [...], "angles": [beam angles, rad, robot frame],
   "goal": [x, y, yaw_rad], "waypoints": [[x, y], ...], "attitude": [roll_rad, pitch_rad],
   "points": [[x, y, z], ...]}     (points: 3D lidar returns, sensor frame, mm precision; only
                                    with robot.lidar3d)
  {"type": "shutdown"}
planner -> harness
  {"type": "ready", "name": "optional", "version": "optional"}   (answer to reset)
  {"type": "command", "vx": 0.5, "vy": 0.0, "wz": 0.1}          (answer to each observation)
  {"type": "error", "message": "..."}                            (gives up: the episode is a subject error)

Logs must go to stderr (its last lines are quoted in error messages); anything on stdout that is not
one JSON object per line is a protocol error.
"""
from __future__ import annotations

import atexit
import collections
import json
import os
import selectors
import shlex
import shutil
import subprocess
import threading
import time
from typing import Any

from ..core.errors import PlannerProtocolError, SubjectLoadError
from ..core.processes import end_group
from .protocol import Command, Observation
from ..scenario.model import Scenario

PROTOCOL = "navscenario-exec"
PROTOCOL_VERSION = 1
DEFAULT_TICK_TIMEOUT = 1.0      # s, per observation, unless the run sets its own (--nav-tick-limit)
RESET_TIMEOUT = 10.0            # s, for the first answer (program start-up included)
STDERR_LINES = 20               # kept for error messages
MAX_LINE = 1 << 20              # a reply longer than 1 MiB is garbage


class ExternalProcess:
    """One running planner program with line-based, deadline-bounded request/response."""

    def __init__(self, argv: list[str], cwd: str | None = None):
        self.argv = argv
        self.cwd = cwd
        self.proc: subprocess.Popen[bytes] | None = None
        self._stderr: collections.deque[str] = collections.deque(maxlen=STDERR_LINES)
        self._buffer = b""
        self.identity: dict[str, Any] = {}
        self.timed_out = False                  # the last exchange ended by its deadline
        self.reset_timeout_message: str | None = None   # set once a reset timed out: fail fast after

    # -- life cycle -------------------------------------------------------------------------
    def start(self) -> None:
        if _CLOSING[0]:
            raise PlannerProtocolError("external planner not started again: this process is ending")
        try:
            self.proc = subprocess.Popen(
                self.argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                cwd=self.cwd, bufsize=0, start_new_session=True)
        except OSError as exc:
            raise SubjectLoadError(
                f"cannot start external planner {shlex.join(self.argv)!r}: {exc.strerror or exc} "
                f"(is the path right and the file executable?)") from None
        self._buffer = b""
        self._stderr.clear()
        threading.Thread(target=self._drain_stderr, args=(self.proc,), daemon=True).start()

    def _drain_stderr(self, proc: subprocess.Popen[bytes]) -> None:
        assert proc.stderr is not None
        for raw in iter(proc.stderr.readline, b""):
            self._stderr.append(raw.decode("utf-8", "replace").rstrip())

    @property
    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def stop(self, grace: float = 1.0) -> None:
        """Ask politely (shutdown message, close stdin), then end its whole process group: the
        program was started in a session of its own, so whatever it started (as a launch file
        starts nodes) is in that group too; SIGTERM, then SIGKILL (core/processes.end_group)."""
        proc, self.proc = self.proc, None
        if proc is None:
            return
        try:
            if proc.poll() is None and proc.stdin:
                proc.stdin.write(b'{"type": "shutdown"}\n')
                proc.stdin.close()
        except OSError:
            pass
        try:
            proc.wait(timeout=grace)
        except subprocess.TimeoutExpired:
            pass
        end_group(proc.pid, grace)
        try:
            proc.wait(timeout=grace)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        for stream in (proc.stdout, proc.stderr, proc.stdin):
            try:
                if stream:
                    stream.close()
            except OSError:
                pass

    def stderr_tail(self) -> str:
        lines = list(self._stderr)
        return ("; its stderr ended with: " + " | ".join(lines[-5:])) if lines else ""

    # -- messaging --------------------------------------------------------------------------
    def request(self, message: dict[str, Any], timeout: float, what: str) -> dict[str, Any]:
        """Send one message, wait up to ``timeout`` s for one JSON line back.

        Anything that interrupts the exchange (a protocol error, the harness's own tick alarm,
        Ctrl-C) stops the process, so a late answer can never be read as the next tick's."""
        if not self.alive:
            self.start()
        self.timed_out = False
        try:
            return self._exchange(message, timeout, what)
        except BaseException:
            self.stop(grace=0.2)
            raise

    def _exchange(self, message: dict[str, Any], timeout: float, what: str) -> dict[str, Any]:
        assert self.proc is not None and self.proc.stdin is not None and self.proc.stdout is not None
        try:
            self.proc.stdin.write((json.dumps(message, separators=(",", ":")) + "\n").encode())
        except (BrokenPipeError, OSError):
            self._died(what)
        line = self._read_line(timeout, what)
        try:
            reply = json.loads(line)
        except (json.JSONDecodeError, UnicodeDecodeError, RecursionError) as exc:
            shown = line[:80].decode("utf-8", "replace")
            self.stop(grace=0.2)
            why = " (nested too deeply)" if isinstance(exc, RecursionError) else ""
            raise PlannerProtocolError(
                f"external planner printed something that is not JSON{why} in answer to {what}: {shown!r} "
                f"(print logs to stderr, one JSON object per line to stdout)") from None
        if not isinstance(reply, dict):
            self.stop(grace=0.2)
            raise PlannerProtocolError(f"external planner answered {what} with {type(reply).__name__}, expected a JSON object")
        if reply.get("type") == "error":
            raise PlannerProtocolError(f"external planner reported an error: {reply.get('message', '(no message)')}")
        return reply

    def _read_line(self, timeout: float, what: str) -> bytes:
        assert self.proc is not None and self.proc.stdout is not None
        deadline = time.monotonic() + timeout
        fd = self.proc.stdout.fileno()
        with selectors.DefaultSelector() as sel:
            sel.register(fd, selectors.EVENT_READ)
            while b"\n" not in self._buffer:
                remaining = deadline - time.monotonic()
                if remaining <= 0 or not sel.select(remaining):
                    self.timed_out = True
                    self.stop(grace=0.2)
                    raise PlannerProtocolError(
                        f"external planner did not answer {what} within {timeout:g} s "
                        f"(hung or too slow; it was restarted){self.stderr_tail()}")
                chunk = os.read(fd, 65536)
                if not chunk:
                    self._died(what)
                self._buffer += chunk
                if len(self._buffer) > MAX_LINE:
                    self.stop(grace=0.2)
                    raise PlannerProtocolError(f"external planner sent over {MAX_LINE} bytes without a newline in answer to {what}")
        line, _, self._buffer = self._buffer.partition(b"\n")
        return line

    def _died(self, what: str) -> None:
        assert self.proc is not None
        try:
            code = self.proc.wait(timeout=1.0)
        except subprocess.TimeoutExpired:
            code = None
        time.sleep(0.01)  # let the stderr thread catch the last lines
        tail = self.stderr_tail()
        self.stop(grace=0.2)
        status = f"exited with status {code}" if code is not None and code >= 0 else (
            f"was killed by signal {-code}" if code is not None else "closed its stdout")
        raise PlannerProtocolError(f"external planner {status} while handling {what}{tail}")


_PROCESSES: dict[tuple[str, ...], ExternalProcess] = {}


def running_pids() -> set[int]:
    """The pids of the exec: planner programs this process runs (not a planner's leftovers)."""
    return {p.proc.pid for p in _PROCESSES.values() if p.proc is not None}


_CLOSING = [False]   # set by _shutdown_all: the process is ending, no program is started again


def _shutdown_all() -> None:
    """Stop every exec: planner program of this process, for good: an episode still running in
    another thread (a pool worker stopping while its episode runs) must not start one again, or it
    would outlive the process."""
    _CLOSING[0] = True
    for proc in list(_PROCESSES.values()):
        proc.stop(grace=0.5)
    _PROCESSES.clear()


atexit.register(_shutdown_all)


def check_start(planner: Any, keep_running: bool) -> None:
    """Start an external planner's program once (SubjectLoadError if it cannot start: missing
    interpreter, bad format, ...), so that this is found at session start, not item by item.
    ``keep_running``: leave it up for the episodes of this process (else stop it again)."""
    process = getattr(planner, "process", None)
    if not isinstance(process, ExternalProcess) or process.alive:
        return
    process.start()
    if not keep_running:
        process.stop(grace=0.5)


class ExternalPlanner:
    """Planner-protocol adapter around a shared ExternalProcess (one per command line).

    ``tick_timeout`` bounds each answer; run_scenario sets it to the run's tick limit, so an
    external planner is held to the same limit as an in-process one (also outside the main
    thread, where no alarm signal is available)."""

    def __init__(self, process: ExternalProcess, tick_timeout: float = DEFAULT_TICK_TIMEOUT,
                 reset_timeout: float = RESET_TIMEOUT):
        self.process = process
        self.tick_timeout = tick_timeout
        self.reset_timeout = reset_timeout      # run_scenario sets it from --nav-reset-timeout
        self.name = "exec:" + shlex.join(process.argv)
        self.version: str | None = None

    def reset(self, scenario: Scenario) -> None:
        from ..scenario.dump import scenario_to_dict

        if self.process.reset_timeout_message is not None:   # one slow start-up, not one per item
            raise PlannerProtocolError(
                f"{self.process.reset_timeout_message} [not retried: an earlier reset of this planner "
                f"timed out; give it longer with --nav-reset-timeout / ini nav_reset_timeout]")
        try:
            reply = self.process.request(
                {"type": "reset", "protocol": PROTOCOL, "version": PROTOCOL_VERSION,
                 "scenario": scenario_to_dict(scenario)},
                self.reset_timeout, "reset")
        except PlannerProtocolError as exc:
            if self.process.timed_out:
                self.process.reset_timeout_message = str(exc)
            raise
        if reply.get("type") != "ready":
            raise PlannerProtocolError(f"external planner answered reset with {reply.get('type')!r}, expected 'ready'")
        if reply.get("name"):
            self.name = str(reply["name"])
        if reply.get("version") is not None:
            self.version = str(reply["version"])

    def act(self, obs: Observation) -> Command:
        reply = self.process.request(
            {"type": "observation", "tick": obs.tick, "time": obs.time,
             "pose": obs.pose.tolist(), "velocity": obs.velocity.tolist(),
             "ranges": obs.ranges.tolist(), "angles": obs.angles.tolist(), "goal": obs.goal.tolist(),
             "waypoints": obs.waypoints.tolist(), **_terrain_fields(obs)},
            self.tick_timeout, f"the observation of tick {obs.tick}")
        if reply.get("type") != "command":
            raise PlannerProtocolError(f"external planner answered an observation with {reply.get('type')!r}, expected 'command'")
        values = []
        for key in ("vx", "vy", "wz"):
            value = reply.get(key, 0.0)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise PlannerProtocolError(f"external planner's command field {key!r} is {value!r}, expected a number")
            values.append(float(value))
        return Command(*values)


def exec_factory(command: str, *, cwd: str | None = None,
                 tick_timeout: float = DEFAULT_TICK_TIMEOUT):
    """A planner factory for ``exec:COMMAND``: every planner it makes shares one process."""
    argv = shlex.split(command)
    if not argv:
        raise SubjectLoadError("subject 'exec:' names no program: write exec:PATH [ARGS...], e.g. exec:./my_planner")
    exe = argv[0]
    if os.sep in exe:
        exe_path = exe if os.path.isabs(exe) else os.path.join(cwd or os.getcwd(), exe)
        if not os.path.exists(exe_path):
            raise SubjectLoadError(f"subject 'exec:{command}': no such program {exe_path!r}")
        if os.path.isdir(exe_path) or not os.access(exe_path, os.X_OK):
            raise SubjectLoadError(f"subject 'exec:{command}': {exe_path!r} is not executable (chmod +x it)")
    elif shutil.which(exe) is None:
        raise SubjectLoadError(f"subject 'exec:{command}': no such program {exe!r} on PATH "
                               f"(give its path, e.g. exec:./{exe}, or install it)")
    key = (cwd or "", *argv)

    def factory() -> ExternalPlanner:
        process = _PROCESSES.get(key)
        if process is None:
            process = _PROCESSES[key] = ExternalProcess(argv, cwd=cwd)
        return ExternalPlanner(process, tick_timeout=tick_timeout)

    factory.__name__ = f"exec:{command}"
    return factory


def _terrain_fields(obs: Observation) -> dict[str, Any]:
    """The observation's attitude, and its 3D lidar points rounded to the millimetre (a float32's
    full repr would triple the line) when a 3D lidar is fitted."""
    out: dict[str, Any] = {}
    if obs.attitude is not None:
        out["attitude"] = [float(a) for a in obs.attitude]
    if obs.points is not None:
        import numpy as np
        out["points"] = np.round(np.asarray(obs.points, dtype=float), 3).tolist()
    return out
