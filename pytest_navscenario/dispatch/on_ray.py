"""Episodes as Ray tasks: on a local Ray instance (``auto``) or on a running cluster (``HOST:PORT``).

Optional: needs ``pip install "pytest-navscenario[ray]"``; ``ray`` is imported only here, when an
executor is made. Each job is one task (``run_job_on_worker``, one CPU); Ray runs a task again when the
worker process or node running it dies (``MAX_RETRIES``), and since an episode is a pure function
of its job, the retry gives the same bits and each job still has exactly one result.

Before any episode, ``check_nodes`` runs a small task on every node with CPUs: it imports
pytest-navscenario, loads the subject (imports the package, or finds the ``exec:`` program) and
reports versions, so a node that cannot run the episodes is named up front, with what it lacks.
"""
from __future__ import annotations

import contextlib
import logging
import os
import shlex
import shutil
import socket
import sys
from typing import Any, Iterator, Sequence

from .jobs import EpisodeError, EpisodeJob, Pending, run_job_on_worker
from ..verdict.result import EpisodeResult

MIN_RAY = (2, 9)
MAX_RETRIES = 3            # runs of a task whose worker or node died, beyond the first
CONNECT_TIMEOUT = 5.0      # s, for the TCP check of a cluster address
PROBE_TIMEOUT = 120.0      # s, for every node to answer the up-front check
INSTALL_HINT = 'pip install "pytest-navscenario[ray]"'


class RaySetupError(Exception):
    """Ray cannot be used as asked: not installed, address unreachable, nodes missing the subject."""


def import_ray() -> Any:
    try:
        import ray
    except ImportError as exc:
        raise RaySetupError(f"--nav-ray needs Ray, which is not installed here ({exc}); install it "
                            f"with: {INSTALL_HINT}") from None
    version = tuple(int(p) for p in ray.__version__.split(".")[:2] if p.isdigit())
    if version < MIN_RAY:
        raise RaySetupError(f"--nav-ray needs Ray >= {'.'.join(map(str, MIN_RAY))}, found {ray.__version__}; "
                            f"upgrade with: {INSTALL_HINT} --upgrade")
    return ray


def _split_address(address: str) -> tuple[str, int]:
    host_port = address.split("://", 1)[-1].rstrip("/")
    host, sep, port = host_port.rpartition(":")
    if not sep or not host or not port.isdigit():
        raise RaySetupError(f"--nav-ray={address!r}: give 'auto' (start a local Ray instance) or the "
                            f"address of a running cluster as HOST:PORT, e.g. --nav-ray=10.0.0.5:6379 "
                            f"(the address `ray start --head` prints)")
    return host, int(port)


def _reachable(address: str) -> None:
    host, port = _split_address(address)
    try:
        with socket.create_connection((host, port), timeout=CONNECT_TIMEOUT):
            pass
    except OSError as exc:
        raise RaySetupError(
            f"--nav-ray={address}: no Ray cluster answers at {host}:{port} ({exc.strerror or exc}). "
            f"Start one there with `ray start --head --port={port}` (it prints the address to use), "
            f"check the host and port, or use --nav-ray=auto for a local instance") from None


@contextlib.contextmanager
def _own_sigterm() -> Iterator[None]:
    """Keep this process's SIGTERM handler across ray.init, which installs one that exits at once
    (the plugin's handler ends the run like Ctrl-C, so what finished is written)."""
    import signal
    import threading

    main = threading.current_thread() is threading.main_thread()
    before = signal.getsignal(signal.SIGTERM) if main else None
    try:
        yield
    finally:
        if main and before is not None:
            signal.signal(signal.SIGTERM, before)


def probe_node(subject: Any, cwd: str | None) -> dict[str, Any]:
    """Runs on a node: can it load the subject? Which versions does it have?"""
    from importlib.metadata import version

    import pytest_navscenario
    info: dict[str, Any] = {"host": socket.gethostname(), "error": "",
                            "versions": {"python": sys.version.split()[0],
                                         "pytest-navscenario": pytest_navscenario.__version__}}
    try:
        for dist in ("mujoco", "numpy"):
            info["versions"][dist] = version(dist)
        from ..sim import episode  # noqa: F401  (the simulation loads: MuJoCo and numpy import)
        spec = subject.strip() if isinstance(subject, str) else None
        if spec is not None and spec.startswith("exec:"):
            info["error"] = _exec_missing(spec[len("exec:"):].strip(), cwd)
        else:
            from ..subjects.loading import make_planner
            make_planner(subject)
    except Exception as exc:
        info["error"] = f"{type(exc).__name__}: {exc}"
    return info


def _exec_missing(command: str, cwd: str | None) -> str:
    """'' if the exec: program is there and executable, else what is missing."""
    argv = shlex.split(command)
    if not argv:
        return "the exec: subject names no program"
    if cwd and not os.path.isdir(cwd):
        return f"the working folder {cwd} does not exist (exec: planners start in the folder pytest runs in)"
    exe = argv[0]
    if os.sep in exe:
        path = os.path.normpath(exe if os.path.isabs(exe) else os.path.join(cwd or os.getcwd(), exe))
        if not os.path.exists(path):
            return f"no program {path}"
        if not os.access(path, os.X_OK):
            return f"{path} is not executable"
        return ""
    return "" if shutil.which(exe) else f"no program {exe!r} on its PATH"


class RayExecutor:
    """Jobs as Ray tasks. ``address``: "auto" (start a local instance with ``num_cpus`` CPUs, all
    cores by default) or "HOST:PORT" of a running cluster. Reuses a Ray connection this process
    already has (and then leaves it open)."""

    def __init__(self, address: str, *, num_cpus: int | None = None):
        self.ray = ray = import_ray()
        self.address = address
        self._owned = False
        self._reaper: Any = None     # reaper.Reaper: ends the local instance's processes if we cannot
        self._open: dict[int, Any] = {}
        self._next = 0
        if ray.is_initialized():
            here = ray.get_runtime_context().gcs_address
            if address != "auto" and _split_address(address) != _split_address(here):
                raise RaySetupError(f"--nav-ray={address}: this process is already connected to Ray at "
                                    f"{here}; use that address or --nav-ray=auto")
        elif address == "auto":
            from .reaper import start_reaper

            paths = os.pathsep.join(p for p in sys.path if p and os.path.isdir(p))
            self._reaper = start_reaper()   # first: it notes Ray's processes as they start
            try:
                with _own_sigterm():
                    ray.init(address="local", num_cpus=num_cpus, include_dashboard=False, log_to_driver=False,
                             logging_level=logging.WARNING,
                             runtime_env={"env_vars": {"PYTHONPATH": paths + os.pathsep + "${PYTHONPATH}"}})
            except BaseException:
                if self._reaper is not None:
                    self._reaper.stop()
                raise
            self._owned = True
        else:
            _reachable(address)
            try:
                with _own_sigterm():
                    ray.init(address=address, log_to_driver=False, logging_level=logging.WARNING)
            except Exception as exc:
                raise RaySetupError(f"--nav-ray={address}: cannot join the Ray cluster there: "
                                    f"{type(exc).__name__}: {exc}") from None
            self._owned = True
        self._run = ray.remote(num_cpus=1, max_retries=MAX_RETRIES)(run_job_on_worker)
        self.nodes = [n for n in ray.nodes() if n.get("Alive") and n.get("Resources", {}).get("CPU", 0) > 0]
        self.workers = int(sum(n["Resources"]["CPU"] for n in self.nodes))
        where = "a local Ray instance" if address == "auto" else f"the Ray cluster at {address}"
        self.description = f"{where}: {len(self.nodes)} node(s), {self.workers} CPU(s)"

    # -- the up-front check -------------------------------------------------------------------------
    def check_nodes(self, subject: Any, cwd: str | None) -> list[str]:
        """Run ``probe_node`` on every node with CPUs. Raises RaySetupError naming each node that
        cannot load the subject; returns warnings (versions that differ from this machine's)."""
        from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

        if not self.nodes:
            raise RaySetupError(f"{self.description}: no node offers CPUs for tasks; start worker "
                                f"nodes with `ray start --address=HEAD:PORT`")
        probe = self.ray.remote(num_cpus=0, max_retries=0)(probe_node)
        refs = {}
        for n in self.nodes:
            strategy = NodeAffinitySchedulingStrategy(node_id=n["NodeID"], soft=False)
            refs[n["NodeID"]] = probe.options(scheduling_strategy=strategy).remote(subject, cwd)
        here = probe_node(None, None)["versions"]
        problems, warnings = [], []
        for n in self.nodes:
            name = (f"{n.get('NodeManagerHostname', '?')} ({n.get('NodeManagerAddress', '?')}, "
                    f"node id {str(n['NodeID'])[:8]})")
            try:
                info = self.ray.get(refs[n["NodeID"]], timeout=PROBE_TIMEOUT)
            except Exception as exc:
                first = str(exc).strip().splitlines()[-1] if str(exc).strip() else type(exc).__name__
                problems.append(f"node {name} cannot run pytest-navscenario tasks ({first}); install the "
                                f"same pytest-navscenario there ({INSTALL_HINT})")
                continue
            if info["error"]:
                problems.append(f"node {name} cannot load the subject {_subject_label(subject)}: {info['error']}")
            diff = [f"{k} {v} (here {here.get(k)})" for k, v in info["versions"].items() if here.get(k) != v]
            if diff:
                warnings.append(f"node {name} has {', '.join(diff)}: its episodes may differ from this "
                                f"machine's in the last bits")
        if problems:
            raise RaySetupError("the Ray nodes cannot run the episodes:\n  " + "\n  ".join(problems)
                                + "\nEvery node needs pytest-navscenario and the subject: an importable "
                                  "package (pip install it on each node) or the exec: program at the same "
                                  "path.")
        return warnings

    # -- jobs -------------------------------------------------------------------------------------
    def submit(self, jobs: Sequence[Any]) -> list[Pending]:
        pendings = []
        for job in jobs:
            key, self._next = self._next, self._next + 1
            self._open[key] = self._run.remote(job)
            pendings.append(Pending(job, lambda key=key: self._wait(key), lambda key=key: self._cancel(key)))
        return pendings

    def map(self, jobs: Sequence[Any]) -> list[Any]:
        return [p.result() for p in self.submit(jobs)]

    def _wait(self, key: int) -> Any:
        ref = self._open[key]
        try:
            outcome = self.ray.get(ref)
        except self.ray.exceptions.RayError as exc:   # retries used up, node lost, cluster gone
            outcome = EpisodeError("RayTaskLost", f"Ray could not run this episode: {type(exc).__name__}: "
                                   f"{str(exc).strip().splitlines()[0] if str(exc).strip() else ''}",
                                   "", "Ray", None)
        del self._open[key]
        return outcome

    def _cancel(self, key: int) -> None:
        """Drop one task's result. The task itself is left to finish: Ray cancels a running task
        by raising KeyboardInterrupt in it, which could leave a reused exec: planner mid-answer."""
        self._open.pop(key, None)

    def close(self, cancel: bool = False) -> None:
        """Cancel unfinished tasks (with ``cancel``) and disconnect; a local instance this
        executor started is stopped."""
        if cancel:
            for ref in self._open.values():
                try:
                    self.ray.cancel(ref, force=True)
                except Exception:
                    pass
        self._open.clear()
        try:
            if self._owned and self.ray.is_initialized():
                self.ray.shutdown()
        finally:
            self._owned = False
            reaper, self._reaper = self._reaper, None
            if reaper is not None:   # whatever ray.shutdown left running (its agents linger)
                reaper.stop()


def _subject_label(subject: Any) -> str:
    return repr(subject) if isinstance(subject, str) else getattr(subject, "__qualname__", repr(subject))
