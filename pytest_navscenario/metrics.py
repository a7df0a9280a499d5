"""Per-episode metrics: pure functions of the scenario and the recorded trajectory.

``compute_metrics`` fills every field of ``result.Metrics``. Definitions (physics-rate
samples unless said otherwise; NaN means "not defined for this episode"):

* min_clearance: least distance between the footprint and any obstacle over all physics
  steps (exact for boxes and true circles, 0 on contact), with the obstacle, time and robot
  position. Coarse bounds from the robot centre prune pairs, the exact box-box distance is
  computed for the rest (see paths.py). A reported collision overrides it with 0 at the hit.
* min_obstacle_gap: narrowest obstacle-obstacle gap of the scenario (paths.min_obstacle_gap).
* path_length: sum of the steps of the centre; shortest_path_length: paths.shortest_path;
  path_efficiency = shortest / driven; max/mean_deviation: distance of each pose to the
  shortest-path polyline.
* duration, mean_speed = path_length / duration, goal position error (m) and goal yaw error
  (degrees, wrapped to [0, 180]) of the last pose.
* smoothness: mean |jerk| (m/s^3) of the planar motion, from the measured velocity turned
  into the world frame, by finite differences; angular_smoothness: mean |d wz / dt| (rad/s^2).
* reference_mean/max_deviation: with ``scenario.reference`` (inline (t, x, y) rows or a CSV
  file with header ``t,x,y``, relative to the scenario file's folder): the simulated position
  interpolated at each reference time inside the simulated time span, distance to the
  reference point. Both clocks start at 0 (the episode start).
"""
from __future__ import annotations

import csv
import math
import os
from collections import OrderedDict
from pathlib import Path

import numpy as np

from .errors import ScenarioError
from .paths import (box_box_distance, footprint_core, min_obstacle_gap, obstacle_shapes,
                    point_box_distance, shortest_path)
from .result import Collision, Metrics, Trajectory
from .scenario import Scenario

NAN = float("nan")
MOVED = 1e-9  # m: a robot that drove less than this "did not move" (path efficiency is NaN)


def compute_metrics(scenario: Scenario, trajectory: Trajectory, *,
                    collision: Collision | None = None) -> Metrics:
    """All metrics of one episode (see the module docstring for the definitions)."""
    t = np.asarray(trajectory.t, dtype=float)
    pose = np.asarray(trajectory.pose, dtype=float).reshape(-1, 3)
    vel = np.asarray(trajectory.velocity, dtype=float).reshape(-1, 3)
    xy = pose[:, :2]

    clear, clear_name, clear_t, clear_x, clear_y = min_clearance(scenario, t, pose)
    if collision is not None:
        clear, clear_name, clear_t = 0.0, collision.obstacle, float(collision.time)
        clear_x, clear_y = _position_at(t, xy, clear_t)
    gap, gap_a, gap_b = min_obstacle_gap(scenario)

    path_length = float(np.hypot(*np.diff(xy, axis=0).T).sum()) if len(xy) > 1 else 0.0
    sp = shortest_path(scenario)
    shortest = sp.length if sp is not None else NAN
    efficiency = shortest / path_length if path_length > MOVED else NAN
    if sp is not None and len(xy):
        dev = polyline_distance(xy, sp.points)
        max_dev, mean_dev = float(dev.max()), float(dev.mean())
    else:
        max_dev = mean_dev = NAN
    duration = float(trajectory.duration)
    goal = scenario.mission.goal
    if len(pose):
        goal_err = math.hypot(pose[-1, 0] - goal.x, pose[-1, 1] - goal.y)
        yaw_err = abs(math.degrees(wrap_angle(pose[-1, 2] - goal.yaw_rad)))
    else:
        goal_err = yaw_err = NAN
    jerk, ang_acc = smoothness(t, pose, vel)
    ref_mean, ref_max = reference_deviation(scenario, t, xy)
    return Metrics(
        min_clearance=clear, min_clearance_obstacle=clear_name, min_clearance_time=clear_t,
        min_clearance_x=clear_x, min_clearance_y=clear_y,
        min_obstacle_gap=gap, min_gap_obstacles=f"{gap_a}|{gap_b}" if gap_a else "",
        path_length=path_length, shortest_path_length=shortest, path_efficiency=efficiency,
        max_deviation=max_dev, mean_deviation=mean_dev,
        duration=duration, mean_speed=path_length / duration if duration > 0 else NAN,
        goal_position_error=goal_err, goal_yaw_error=yaw_err,
        smoothness=jerk, angular_smoothness=ang_acc,
        reference_mean_deviation=ref_mean, reference_max_deviation=ref_max,
    )


def min_clearance(scenario: Scenario, t: np.ndarray, pose: np.ndarray
                  ) -> tuple[float, str, float, float, float]:
    """``(distance, obstacle, time, x, y)`` of the closest approach of the footprint to any
    obstacle over the poses; the earliest one on ties; ``(inf, "", nan, nan, nan)`` with no
    obstacles or no poses."""
    shapes = obstacle_shapes(scenario.obstacles)
    pose = np.asarray(pose, dtype=float).reshape(-1, 3)
    if not len(shapes) or not len(pose):
        return math.inf, "", NAN, NAN, NAN
    hl, hw, rho = footprint_core(scenario.robot.footprint)
    px, py = pose[:, 0:1], pose[:, 1:2]
    # distance of the robot centre to each obstacle: bounds the footprint's distance
    centre = point_box_distance(px, py, shapes.x, shapes.y, shapes.cos, shapes.sin,
                                shapes.hl, shapes.hw) - shapes.rho          # (n, k)
    lower = centre - (math.hypot(hl, hw) + rho)     # the footprint reaches at most this far
    upper = np.maximum(centre - (min(hl, hw) + rho), 0.0)   # ... and at least this far
    ii, kk = np.nonzero(lower <= upper.min() + 1e-12)
    yaw = pose[ii, 2]
    exact = box_box_distance(pose[ii, 0], pose[ii, 1], np.cos(yaw), np.sin(yaw), hl, hw,
                             shapes.x[kk], shapes.y[kk], shapes.cos[kk], shapes.sin[kk],
                             shapes.hl[kk], shapes.hw[kk])
    exact = np.maximum(exact - rho - shapes.rho[kk], 0.0)
    best = int(np.argmin(exact))        # candidates are in time order: first minimum = earliest
    i, k = int(ii[best]), int(kk[best])
    return float(exact[best]), shapes.names[k], float(t[i]), float(pose[i, 0]), float(pose[i, 1])


def polyline_distance(points: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Distance of each of the (n, 2) points to the polyline through the (m, 2) vertices."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    line = np.asarray(line, dtype=float).reshape(-1, 2)
    if len(line) == 1:
        return np.hypot(*(points - line[0]).T)
    a, d = line[:-1], np.diff(line, axis=0)                       # (s, 2)
    seg2 = np.maximum((d * d).sum(1), 1e-300)
    rel = points[:, None, :] - a[None]                            # (n, s, 2)
    u = np.clip((rel * d).sum(2) / seg2, 0.0, 1.0)
    off = rel - u[..., None] * d
    return np.sqrt((off * off).sum(2).min(1))


def wrap_angle(a: float) -> float:
    """Wrap an angle in radians to [-pi, pi)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


def smoothness(t: np.ndarray, pose: np.ndarray, velocity: np.ndarray) -> tuple[float, float]:
    """(mean |planar jerk| m/s^3, mean |angular acceleration| rad/s^2) by finite differences of
    the measured velocity (robot frame, turned into the world frame). Samples with a repeated
    time stamp are skipped; NaN with fewer than 3 (resp. 2) distinct samples."""
    t = np.asarray(t, dtype=float)
    if len(t) < 2:
        return NAN, NAN
    keep = np.concatenate([[True], np.diff(t) > 0])
    t, pose, velocity = t[keep], pose[keep], velocity[keep]
    c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    vw = np.column_stack([c * velocity[:, 0] - s * velocity[:, 1], s * velocity[:, 0] + c * velocity[:, 1]])
    dt = np.diff(t)
    ang = float(np.abs(np.diff(velocity[:, 2]) / dt).mean()) if len(dt) else NAN
    if len(t) < 3:
        return NAN, ang
    acc = np.diff(vw, axis=0) / dt[:, None]
    tm = 0.5 * (t[1:] + t[:-1])
    jerk = np.diff(acc, axis=0) / np.diff(tm)[:, None]
    return float(np.hypot(jerk[:, 0], jerk[:, 1]).mean()), ang


# --------------------------------------------------------------------------------------------
# Reference trajectory


def reference_deviation(scenario: Scenario, t: np.ndarray, xy: np.ndarray) -> tuple[float, float]:
    """(mean, max) distance between the reference points and the simulated positions at the
    same times, over the reference times within the simulated span; NaN without a reference
    or without overlap."""
    ref = load_reference(scenario)
    if ref is None or len(t) == 0:
        return NAN, NAN
    inside = (ref[:, 0] >= t[0]) & (ref[:, 0] <= t[-1])
    if not inside.any():
        return NAN, NAN
    rt = ref[inside, 0]
    sx = np.interp(rt, t, xy[:, 0])
    sy = np.interp(rt, t, xy[:, 1])
    dev = np.hypot(sx - ref[inside, 1], sy - ref[inside, 2])
    return float(dev.mean()), float(dev.max())


def load_reference(scenario: Scenario) -> np.ndarray | None:
    """The scenario's reference trajectory as a (k, 3) array of (t, x, y), sorted by time, or
    None. Inline points win over a file. Raises ScenarioError for a missing or bad file."""
    ref = scenario.reference
    if ref is None:
        return None
    if ref.points:
        arr = np.array(ref.points, dtype=float).reshape(-1, 3)
    elif ref.file:
        arr = _read_reference_csv(scenario, ref.file)
    else:
        return None
    return arr[np.argsort(arr[:, 0], kind="stable")]


_CSV_CACHE: OrderedDict[tuple, np.ndarray] = OrderedDict()


def _read_reference_csv(scenario: Scenario, name: str) -> np.ndarray:
    base = Path(scenario.source).parent if scenario.source else Path.cwd()
    path = (base / name).resolve()
    where = dict(path=scenario.source, field="reference.file")
    try:
        st = os.stat(path)
    except OSError:
        raise ScenarioError(
            f"reference trajectory file {name!r} not found (looked for {path})",
            hint="give the path relative to the scenario file's folder, or inline the points "
                 "under reference.points as [t, x, y] rows", **where) from None
    key = (str(path), st.st_mtime_ns, st.st_size)
    if key in _CSV_CACHE:
        return _CSV_CACHE[key]
    rows = []
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        header = [h.strip().lower() for h in next(reader, [])]
        if any(c not in header for c in ("t", "x", "y")):
            raise ScenarioError(
                f"reference trajectory {path}: header must name the columns t,x,y, got {','.join(header) or 'an empty file'}",
                hint="make the first line of the CSV file 't,x,y' (seconds, metres, metres)", **where)
        cols = [header.index(c) for c in ("t", "x", "y")]
        for row in reader:
            if not row or not "".join(row).strip():
                continue
            try:
                vals = [float(row[c]) for c in cols]
            except (ValueError, IndexError):
                raise ScenarioError(
                    f"reference trajectory {path}:{reader.line_num}: expected three numbers t,x,y, got {','.join(row)!r}",
                    hint="every data row of the CSV file must hold numbers in the t,x,y columns", **where) from None
            if not all(math.isfinite(v) for v in vals):
                raise ScenarioError(
                    f"reference trajectory {path}:{reader.line_num}: non-finite value in {','.join(row)!r}",
                    hint="remove rows with NaN or inf", **where)
            rows.append(vals)
    arr = np.array(rows, dtype=float).reshape(-1, 3)
    arr.setflags(write=False)
    _CSV_CACHE[key] = arr
    if len(_CSV_CACHE) > 64:
        _CSV_CACHE.popitem(last=False)
    return arr


def _position_at(t: np.ndarray, xy: np.ndarray, when: float) -> tuple[float, float]:
    if not len(t):
        return NAN, NAN
    return float(np.interp(when, t, xy[:, 0])), float(np.interp(when, t, xy[:, 1]))
