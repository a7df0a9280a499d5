"""The signals requirements name (issue 34), computed once per episode as arrays from the recorded
trajectory, sampled every control tick (``dt`` = 1 / control_rate, from t = 0 to the episode's end).

``episode_signals(scenario, trajectory, names)`` computes only the names asked for: built-ins
(``scenario/requirements.BUILTIN_SIGNALS``), ``d_waypointN``, and the scenario's declared signals
(distance to obstacles, inside a region, speed toward an obstacle, a user's function). A sample at
time t reads the state of the last physics step at or before t. Distances of the footprint are
exact (the same kernels as ``metrics.min_clearance``); a moving obstacle is measured where it was.
"""
from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Mapping

import numpy as np

from ..core.errors import ScenarioError
from ..scenario.model import Scenario
from ..scenario.motion import displacement, tracks
from ..scenario.requirements import BUILTIN_SIGNALS, WAYPOINT_SIGNAL, Signal
from ..sim.trajectory import Trajectory
from .gaps import box_box_distance, clearance_obstacles, footprint_core, is_outlined, obstacle_shapes, static_obstacles


@dataclass(frozen=True, eq=False)
class Samples:
    """The recorded trajectory at the control ticks: ``times`` (n,), the physics index and the
    tick index of each sample, the poses (n, 3)."""
    scenario: Scenario
    trajectory: Trajectory
    dt: float
    times: np.ndarray
    index: np.ndarray
    tick: np.ndarray
    pose: np.ndarray


def samples(scenario: Scenario, trajectory: Trajectory) -> Samples:
    dt = 1.0 / scenario.simulation.control_rate
    t = np.asarray(trajectory.t, dtype=float)
    n = int(math.floor(trajectory.duration / dt + 1e-6)) + 1 if len(t) else 0
    times = np.arange(n) * dt
    index = np.clip(np.searchsorted(t, times + 1e-9, side="right") - 1, 0, max(len(t) - 1, 0))
    tick_t = np.asarray(trajectory.tick_t, dtype=float)
    tick = np.clip(np.searchsorted(tick_t, times + 1e-9, side="right") - 1, 0, max(len(tick_t) - 1, 0))
    pose = np.asarray(trajectory.pose, dtype=float).reshape(-1, 3)[index] if n else np.zeros((0, 3))
    return Samples(scenario, trajectory, dt, times, index, tick, pose)


# --------------------------------------------------------------------------- built-ins

def _speed(s: Samples) -> np.ndarray:
    v = np.asarray(s.trajectory.velocity, dtype=float).reshape(-1, 3)[s.index]
    return np.hypot(v[:, 0], v[:, 1])


def _acceleration(s: Samples) -> np.ndarray:
    speed = _speed(s)
    return np.gradient(speed, s.dt) if len(speed) > 1 else np.zeros_like(speed)


def _command_speed(s: Samples) -> np.ndarray:
    cmd = np.asarray(s.trajectory.command, dtype=float).reshape(-1, 3)
    if not len(cmd):
        return np.zeros(len(s.times))
    c = cmd[s.tick]
    return np.hypot(c[:, 0], c[:, 1])


def _attitude(name: str, scale: float, relative: bool = False) -> Callable[[Samples], np.ndarray]:
    def compute(s: Samples) -> np.ndarray:
        values = getattr(s.trajectory, name)
        if values is None or not len(values):
            return np.zeros(len(s.times))
        out = np.asarray(values, dtype=float)[s.index] * scale
        return out - float(values[0]) * scale if relative else out
    return compute


def _lidar_min(s: Samples) -> np.ndarray:
    ranges = np.asarray(s.trajectory.ranges, dtype=float)
    if ranges.ndim != 2 or not ranges.shape[1] or not len(ranges):
        return np.full(len(s.times), float(s.scenario.robot.lidar.range_max))
    return ranges.min(axis=1)[s.tick]


def _clearance(s: Samples) -> np.ndarray:
    """To the nearest obstacle, and on terrain to the nearest face or steep slope the body cannot
    cross (``gaps.clearance_obstacles``, as the ``min_clearance`` metric)."""
    best = footprint_distance(s, range(len(s.scenario.obstacles)))
    if s.scenario.terrain and len(s.times):
        terrain = clearance_obstacles(s.scenario)[len(static_obstacles(s.scenario)):]
        if terrain:
            best = np.minimum(best, _static_distance(s, terrain))
    return best


def _static_distance(s: Samples, boxes: tuple) -> np.ndarray:
    """The footprint's least distance (n,) to static boxes, all at once (terrain faces: up to
    ``traversable.MAX_BARRIERS``)."""
    hl, hw, rho = footprint_core(s.scenario.robot.footprint)
    sh = obstacle_shapes(boxes)
    out = np.empty(len(s.pose))
    step = max(1, 100_000 // len(sh))          # samples per pass: bounded temporaries
    for a in range(0, len(s.pose), step):
        pose = s.pose[a:a + step]
        c, sn = np.cos(pose[:, 2:3]), np.sin(pose[:, 2:3])
        d = box_box_distance(pose[:, 0:1], pose[:, 1:2], c, sn, hl, hw, sh.x[None], sh.y[None], sh.cos[None],
                             sh.sin[None], sh.hl[None], sh.hw[None])
        out[a:a + step] = np.maximum(d - rho - sh.rho[None], 0.0).min(axis=1)
    return out


def _to_point(x: float, y: float) -> Callable[[Samples], np.ndarray]:
    return lambda s: np.hypot(s.pose[:, 0] - x, s.pose[:, 1] - y)


BUILTINS: Mapping[str, Callable[[Samples], np.ndarray]] = {
    "time": lambda s: s.times.copy(),
    "x": lambda s: s.pose[:, 0].copy(),
    "y": lambda s: s.pose[:, 1].copy(),
    "heading": lambda s: np.degrees(np.arctan2(np.sin(s.pose[:, 2]), np.cos(s.pose[:, 2]))),
    "speed": _speed,
    "yaw_rate": lambda s: np.degrees(np.asarray(s.trajectory.velocity, dtype=float).reshape(-1, 3)[s.index, 2]),
    "acceleration": _acceleration,
    "command_speed": _command_speed,
    "clearance": _clearance,
    "d_goal": lambda s: _to_point(s.scenario.mission.goal.x, s.scenario.mission.goal.y)(s),
    "pitch": _attitude("pitch", 180.0 / math.pi),
    "roll": _attitude("roll", 180.0 / math.pi),
    "height": _attitude("z", 1.0, relative=True),
    "lidar_min": _lidar_min,
}
assert set(BUILTINS) == set(BUILTIN_SIGNALS), "every built-in signal is declared in scenario/requirements.py"


# --------------------------------------------------------------------------- obstacles and regions

def matching(scenario: Scenario, patterns: Iterable[str]) -> list[int]:
    """Indices of the obstacles a signal's names or patterns (person*) match."""
    names = [o.name for o in scenario.obstacles]
    return [i for i, name in enumerate(names) if any(fnmatch.fnmatchcase(name, p) for p in patterns)]


def _relative(s: Samples, moving: Mapping[int, object], i: int) -> np.ndarray:
    if i not in moving:
        return s.pose
    rel = s.pose.copy()
    rel[:, :2] -= displacement(moving[i], s.times)
    return rel


def footprint_distance(s: Samples, indices: Iterable[int]) -> np.ndarray:
    """The footprint's least distance (n,) to the obstacles ``indices`` at each sample (0 on
    overlap; +inf without obstacles)."""
    from ..scenario.geometry import convex_parts, footprint_part_distance

    obstacles = s.scenario.obstacles
    hl, hw, rho = footprint_core(s.scenario.robot.footprint)
    moving = tracks(obstacles)
    best = np.full(len(s.times), np.inf)
    for i in indices:
        obs = obstacles[i]
        poses = _relative(s, moving, i)
        if is_outlined(obs):
            for part in convex_parts(obs):
                best = np.minimum(best, footprint_part_distance(hl, hw, rho, poses, part))
            continue
        sh = obstacle_shapes((obs,))
        c, sn = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        d = box_box_distance(poses[:, 0], poses[:, 1], c, sn, hl, hw, sh.x[0], sh.y[0], sh.cos[0], sh.sin[0],
                             sh.hl[0], sh.hw[0])
        best = np.minimum(best, np.maximum(d - rho - sh.rho[0], 0.0))
    return best


def _centre(obs) -> tuple[float, float]:
    from ..scenario.geometry import obstacle_polygon
    if is_outlined(obs):
        c = obstacle_polygon(obs).centroid
        return float(c.x), float(c.y)
    return float(obs.x), float(obs.y)


def speed_toward(s: Samples, indices: Iterable[int]) -> np.ndarray:
    """The robot's own velocity along the direction to the nearest of the obstacles' centres
    (> 0 approaching), m/s; 0 without obstacles."""
    obstacles = s.scenario.obstacles
    moving = tracks(obstacles)
    v = np.asarray(s.trajectory.velocity, dtype=float).reshape(-1, 3)[s.index]
    c, sn = np.cos(s.pose[:, 2]), np.sin(s.pose[:, 2])
    vx, vy = v[:, 0] * c - v[:, 1] * sn, v[:, 0] * sn + v[:, 1] * c
    best_d = np.full(len(s.times), np.inf)
    out = np.zeros(len(s.times))
    for i in indices:
        cx, cy = _centre(obstacles[i])
        ox = np.full(len(s.times), cx)
        oy = np.full(len(s.times), cy)
        if i in moving:
            off = displacement(moving[i], s.times)
            ox, oy = ox + off[:, 0], oy + off[:, 1]
        dx, dy = ox - s.pose[:, 0], oy - s.pose[:, 1]
        d = np.hypot(dx, dy)
        along = (vx * dx + vy * dy) / np.maximum(d, 1e-9)
        nearer = d < best_d
        out = np.where(nearer, along, out)
        best_d = np.minimum(best_d, d)
    return out


def inside(s: Samples, region) -> np.ndarray:
    """Signed distance of the robot centre to the region's boundary: > 0 inside, < 0 outside, m."""
    x, y = s.pose[:, 0], s.pose[:, 1]
    if region.radius is not None:
        return region.radius - np.hypot(x - region.x, y - region.y)
    import shapely
    poly = shapely.Polygon(region.points)
    d = shapely.distance(poly.exterior, shapely.points(x, y))
    return np.where(shapely.contains_xy(poly, x, y), d, -d)


def _user(s: Samples, signal: Signal) -> np.ndarray:
    from ..core.user_code import load_object

    source = s.scenario.source
    project = [str(Path(source).resolve().parent)] if source else []
    fn = load_object(signal.function, what=f"signal {signal.name!r}", project=project, error=ScenarioError)
    values = np.asarray(fn(s.trajectory, s.scenario, s.times.copy()), dtype=float)
    if values.shape != s.times.shape or not np.all(np.isfinite(values) | np.isinf(values)):
        raise ScenarioError(f"signal {signal.name!r}: {signal.function} returned shape {values.shape} "
                            f"(or NaN); it must return one number per tick time, shape {s.times.shape}",
                            path=source, field="signals",
                            hint="return an array as long as the tick times it is given (its third argument)")
    return values


def declared(s: Samples, signal: Signal) -> np.ndarray:
    if signal.distance_to:
        return footprint_distance(s, matching(s.scenario, signal.distance_to))
    if signal.inside is not None:
        return inside(s, signal.inside)
    if signal.speed_toward:
        return speed_toward(s, matching(s.scenario, (signal.speed_toward,)))
    return _user(s, signal)


def episode_signals(scenario: Scenario, trajectory: Trajectory, names: Iterable[str],
                    at: Samples | None = None) -> dict[str, np.ndarray]:
    """The signals ``names`` over the episode, each a float array with one value per sample."""
    s = at if at is not None else samples(scenario, trajectory)
    by_name = {sig.name: sig for sig in scenario.signals}
    out: dict[str, np.ndarray] = {}
    for name in names:
        if name in BUILTINS:
            out[name] = np.asarray(BUILTINS[name](s), dtype=float)
        elif name in by_name:
            out[name] = np.asarray(declared(s, by_name[name]), dtype=float)
        elif name.startswith(WAYPOINT_SIGNAL) and name[len(WAYPOINT_SIGNAL):].isdigit():
            k = int(name[len(WAYPOINT_SIGNAL):])
            wp = scenario.mission.waypoints[k - 1]
            out[name] = _to_point(wp.x, wp.y)(s)
        else:
            raise KeyError(name)
    return out


def signal_unit(scenario: Scenario, name: str) -> str:
    """The unit of a signal ("" for a user's function)."""
    if name in BUILTIN_SIGNALS:
        return BUILTIN_SIGNALS[name][0]
    if name.startswith(WAYPOINT_SIGNAL):
        return "m"
    sig = next((x for x in scenario.signals if x.name == name), None)
    if sig is None or sig.function:
        return ""
    return "m/s" if sig.speed_toward else "m"
