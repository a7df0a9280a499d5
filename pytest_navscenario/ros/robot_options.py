"""What every world importer (``import sdf``, ``import aerialist``, ``from-map``) asks of the robot:
the robot from ``--robot FILE`` (the ``robot:`` section of a YAML file, e.g. an existing scenario),
its footprint from ``--footprint`` and its drive from ``--drive`` (instead of the default 0.9 x
0.5 m omnidirectional box); and the mission's timeout, derived from the route's length and the
robot's speed unless ``--timeout`` is given."""
from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path

from ..core.errors import NavScenarioError, ScenarioError
from ..scenario.model import Footprint, Robot, Scenario

TIMEOUT_FACTOR = 2.0      # the derived timeout: this many times the driving time at top speed ...
TIMEOUT_EXTRA = 10.0      # ... plus this many seconds (turning, accelerating, a detour)
MIN_TIMEOUT = 30.0        # s, never less (the default a hand-written scenario has)


class RobotOptionError(NavScenarioError):
    """--robot, --footprint or --drive cannot be used."""


def add_robot_arguments(p: argparse.ArgumentParser, default_timeout: str = "derived", *, timeout: bool = True,
                        default_robot: str = "the built-in 0.9 x 0.5 m omnidirectional box") -> None:
    """--robot, --footprint, --drive and (``timeout``) --timeout; ``default_robot`` says what the
    importer uses without them."""
    p.add_argument("--robot", default=None, metavar="FILE",
                   help="a YAML file with a robot: section (an existing scenario file works): the seed's robot "
                        f"(footprint, drive, limits, lidar); default {default_robot}")
    p.add_argument("--footprint", default=None, metavar="SHAPE",
                   help="the robot's footprint: circle:RADIUS or box:LENGTHxWIDTH in metres (e.g. circle:0.2, "
                        "box:0.6x0.45); overrides the --robot file's")
    p.add_argument("--drive", choices=("diff", "omni"), default=None,
                   help="the robot's drive: diff (differential, no sideways motion) or omni; overrides the --robot "
                        "file's")
    if not timeout:
        return
    p.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help="mission timeout (default: derived from the route's length and the robot's top speed: "
                        f"{TIMEOUT_FACTOR:g} times the driving time plus {TIMEOUT_EXTRA:g} s, at least "
                        f"{MIN_TIMEOUT:g} s; the output says how)")


def parse_footprint(text: str) -> Footprint:
    """``circle:R`` or ``box:LxW`` (metres) -> Footprint, with an error naming the option."""
    kind, _, size = text.partition(":")
    try:
        values = [float(v) for v in size.lower().split("x")] if size else []
    except ValueError:
        values = []
    ok = all(math.isfinite(v) and 0 < v <= 50 for v in values)
    if kind == "circle" and len(values) == 1 and ok:
        return Footprint(shape="circle", radius=values[0])
    if kind == "box" and len(values) == 2 and ok:
        return Footprint(shape="box", length=values[0], width=values[1])
    raise RobotOptionError(f"--footprint {text!r}: expected circle:RADIUS or box:LENGTHxWIDTH in metres "
                           f"(0 < size <= 50), e.g. --footprint circle:0.2 or --footprint box:0.6x0.45")


def robot_from_args(args: argparse.Namespace) -> tuple[Robot, str]:
    """The seed's robot from --robot / --footprint / --drive, and a note saying where it came from."""
    robot, parts = Robot(), []
    if args.robot:
        robot = read_robot(Path(args.robot))
        parts.append(f"the robot: section of {args.robot}")
    if args.footprint:
        robot = dataclasses.replace(robot, footprint=parse_footprint(args.footprint))
        parts.append(f"--footprint {args.footprint}")
    if args.drive:
        robot = dataclasses.replace(robot, drive=args.drive)
        parts.append(f"--drive {args.drive}")
    fp = robot.footprint
    shape = f"a circle of radius {fp.radius:g} m" if fp.shape == "circle" else f"a {fp.length:g} x {fp.width:g} m box"
    how = " and ".join(parts) if parts else "the default (no --robot, --footprint or --drive)"
    return robot, f"robot: {shape}, {robot.drive} drive, top speed {robot.limits.max_speed:g} m/s, from {how}"


def read_robot(path: Path) -> Robot:
    """The ``robot:`` section of a YAML file, validated by the scenario loader; errors name the
    user's file and line. A file with only a robot (no mission) is read as if it had one."""
    from ..scenario.loader import loads_scenario

    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RobotOptionError(f"--robot {path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise RobotOptionError(f"--robot {path}: cannot read: {exc}") from None
    import yaml
    try:
        top = yaml.safe_load(text)
    except yaml.YAMLError:
        top = None      # the loader says where
    keys = set(top) if isinstance(top, dict) else set()
    if isinstance(top, dict) and "robot" not in keys:
        raise RobotOptionError(f"--robot {path}: the file has no robot: section (its keys: "
                               f"{', '.join(sorted(map(str, keys))) or 'none'})")
    # appended lines leave the user's line numbers as they are
    tail = ("" if "version" in keys else "\nversion: 1") + \
           ("" if "mission" in keys else "\nmission: {start: {x: 0, y: 0}, goal: {x: 1000, y: 0}}")
    try:
        return loads_scenario(text.rstrip("\n") + tail + "\n", source=path).robot
    except ScenarioError as exc:
        raise RobotOptionError(f"--robot: {exc}") from None


def top_speed(robot: Robot) -> float:
    """The fastest the robot can drive (m/s): forward and, on an omnidirectional drive, sideways at once."""
    lateral = robot.limits.max_lateral_speed if robot.drive == "omni" else 0.0
    return math.hypot(robot.limits.max_speed, lateral)


def route_length(scenario: Scenario) -> tuple[float, str]:
    """The shortest collision-free route's length for the scenario's footprint (m), and how it was
    measured (straight legs when no collision-free route exists)."""
    from ..verdict.paths import reference_path

    path = reference_path(scenario)
    if path is not None:
        return path.length, "the shortest collision-free route"
    m = scenario.mission
    pts = [m.start, *m.waypoints, m.goal]
    return sum(math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(pts, pts[1:])), "the straight legs (no free route)"


def mission_timeout(scenario: Scenario, given: float | None) -> tuple[float, str]:
    """The timeout to write and a note: ``given`` (--timeout) when set, else TIMEOUT_FACTOR times the
    route's driving time at the robot's forward top speed plus TIMEOUT_EXTRA, at least MIN_TIMEOUT."""
    if given is not None:
        if not (math.isfinite(given) and given > 0):
            raise RobotOptionError(f"--timeout must be a positive number of seconds, got {given}")
        return float(given), f"timeout {given:g} s (--timeout)"
    length, how = route_length(scenario)
    speed = scenario.robot.limits.max_speed
    timeout = max(MIN_TIMEOUT, float(math.ceil(TIMEOUT_FACTOR * length / speed + TIMEOUT_EXTRA)))
    return timeout, (f"timeout {timeout:g} s: {how} is {length:.1f} m, {length / speed:.1f} s at the robot's "
                     f"{speed:g} m/s; {TIMEOUT_FACTOR:g} times that plus {TIMEOUT_EXTRA:g} s"
                     + (f", at least {MIN_TIMEOUT:g} s" if timeout == MIN_TIMEOUT else "") + " (--timeout to set it)")
