"""pytest options for ROS bags of episodes: ``pytest scenarios/ --nav-bag=failed``.

``--nav-bag=failed|all|none`` (default none: writing a bag costs more than simulating the
episode), ``--nav-bag-format=mcap|sqlite3|ros1`` (default mcap: a rosbag2 folder with one
.mcap file, opens in Foxglove; ros1 writes a .bag file) and ``--nav-bag-dir=DIR`` (default
``nav-bags``), each with an ini twin (nav_bag, nav_bag_format, nav_bag_dir).

Bags are written on the controller (never by xdist workers) from ``report.nav``: when bags are
on, ``pytest_configure`` asks the core plugin to include trajectories in the payload. One bag per
episode, named after the node id (the artifacts' folder naming: safe and unique).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from .options import option_value as _value, resolve_path

MODES = ("none", "failed", "all")
FORMATS = ("mcap", "sqlite3", "ros1")  # = bags.FORMATS, repeated so loading the plugin imports no numpy
DEFAULT_DIR = "nav-bags"

# (option, ini name, help)
OPTIONS = (
    ("--nav-bag", "nav_bag",
     "write a ROS bag per episode: failed (episodes whose outcome is not success), all, or none "
     "(default; bags cost more than the simulation)."),
    ("--nav-bag-format", "nav_bag_format",
     "bag format: mcap (rosbag2 + MCAP, default, opens in Foxglove), sqlite3 (rosbag2 .db3) or "
     "ros1 (.bag)."),
    ("--nav-bag-dir", "nav_bag_dir",
     f"folder for the bags (default {DEFAULT_DIR} under the rootdir); one bag per episode, named "
     f"after its node id."),
)


@dataclass
class BagState:
    mode: str
    fmt: str
    folder: Path
    written: list[Path] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    missing_trajectory: int = 0


_STATE = pytest.StashKey[BagState]()


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("navscenario-bags", "ROS bags of episodes (pytest-navscenario)")
    metavars = {"nav_bag": "{failed,all,none}", "nav_bag_format": "{" + ",".join(FORMATS) + "}",
                "nav_bag_dir": "DIR"}
    for opt, ini, text in OPTIONS:
        group.addoption(opt, dest=ini, default=None, metavar=metavars[ini], help=f"{text} [ini: {ini}]")
    parser.addini("nav_bag", OPTIONS[0][2], default="none")
    parser.addini("nav_bag_format", OPTIONS[1][2], default="mcap")
    parser.addini("nav_bag_dir", OPTIONS[2][2], default=DEFAULT_DIR)


def read_bag_settings(config: pytest.Config) -> BagState:
    """Parse and check the three options; pytest.UsageError names the option and the choices."""
    mode, where, _ = _value(config, "nav_bag")
    mode = mode.lower() or "none"
    if mode not in MODES:
        raise pytest.UsageError(f"{where}: expected one of {', '.join(MODES)}, got {mode!r} "
                                f"(e.g. --nav-bag=failed)")
    fmt, where, _ = _value(config, "nav_bag_format")
    fmt = fmt.lower() or "mcap"
    if fmt not in FORMATS:
        raise pytest.UsageError(f"{where}: expected one of {', '.join(FORMATS)}, got {fmt!r}")
    raw, where, base = _value(config, "nav_bag_dir")
    folder = resolve_path(raw or DEFAULT_DIR, base)
    if folder.exists() and not folder.is_dir():
        raise pytest.UsageError(f"{where}: {raw!r} exists and is not a folder; give a folder (created if missing)")
    return BagState(mode=mode, fmt=fmt, folder=folder)


def pytest_configure(config: pytest.Config) -> None:
    state = read_bag_settings(config)
    config.stash[_STATE] = state
    if state.mode != "none":
        from .payload import request_clouds, request_trajectories
        request_trajectories(config, state.mode)
        request_clouds(config)


def bag_path_for(state: BagState, record: dict[str, Any]) -> Path:
    """Where the bag of one episode goes (``<dir>/<safe node id>[-rN]``, ``.bag`` for ROS 1)."""
    from ..core.files import folder_name
    from ..ros.bag_writer import default_bag_path

    stem = folder_name(record["nodeid"])
    if record.get("repeat"):
        stem += f"-r{int(record['repeat'])}"
    return default_bag_path(state.folder, stem, state.fmt)


def pytest_navscenario_episode_report(config: pytest.Config, report: pytest.TestReport,
                                      payload: dict[str, Any], artifact_dir: Any) -> None:
    state = config.stash.get(_STATE, None)
    if state is None or state.mode == "none":
        return
    record = payload["record"]
    if state.mode == "failed" and record.get("passed"):
        return
    if payload.get("trajectory") is None or record.get("error"):   # (an episode that never finished)
        state.missing_trajectory += 1
        return
    from ..ros.bag_writer import write_episode_bag
    from ..core.errors import NavScenarioError
    from .payload import episode_from_payload

    path = bag_path_for(state, record)
    try:
        path = write_episode_bag(episode_from_payload(payload), path, fmt=state.fmt)
    except NavScenarioError as exc:  # names the bag and the reason
        state.errors.append(f"{record['nodeid']}: {exc}")
        return
    except Exception as exc:  # one bad bag must not end the run: reported at the end
        state.errors.append(f"{record['nodeid']}: cannot write bag {path}: {type(exc).__name__}: {exc}")
        return
    state.written.append(path)


def pytest_terminal_summary(terminalreporter: Any, exitstatus: int, config: pytest.Config) -> None:
    state = config.stash.get(_STATE, None)
    if state is None or state.mode == "none" or hasattr(config, "workerinput"):
        return
    tr = terminalreporter
    if state.written:
        tr.write_line(f"navscenario: wrote {len(state.written)} {state.fmt} bag(s) to {state.folder} "
                      f"(--nav-bag={state.mode})")
    for err in state.errors:
        tr.write_line(f"navscenario: error: {err}", red=True)
    if state.missing_trajectory:
        tr.write_line(f"navscenario: warning: {state.missing_trajectory} episode(s) arrived without a "
                      f"trajectory, so no bag was written for them", yellow=True)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """A bag that could not be written makes an otherwise green run exit with status 3."""
    state = session.config.stash.get(_STATE, None)
    if state is not None and state.errors and session.exitstatus == 0:
        session.exitstatus = pytest.ExitCode.INTERNAL_ERROR
