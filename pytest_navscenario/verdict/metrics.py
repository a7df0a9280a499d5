"""Per-episode metrics: pure functions of the scenario and the recorded trajectory.

``compute_metrics`` fills every field of ``result.Metrics``. Definitions (physics-rate
samples unless said otherwise; NaN means "not defined for this episode"):

* min_clearance: least distance between the footprint and any obstacle over all physics
  steps (exact for boxes and true circles, 0 on contact), with the obstacle, time and robot
  position. Coarse bounds from the robot centre prune pairs, the exact box-box distance is
  computed for the rest (see paths.py). A reported collision overrides it with 0 at the hit.
* min_obstacle_gap: narrowest obstacle-obstacle gap of the scenario (gaps.min_obstacle_gap).
* path_length: sum of the steps of the centre (over the ground: with its height, for a body that
  rides it); shortest_path_length: paths.reference_path, the
  shortest collision-free path from the start through each waypoint's tolerance disc (a
  waypoint counts as passed anywhere within mission.waypoint_tolerance, as in the simulation)
  to the goal point; path_efficiency = shortest / (driven + still to go), where "still to go"
  is the straight distance to the goal point when the run ended inside the goal tolerance
  (stopping short of the exact point costs nothing), else the shortest collision-free path
  from the last position through the waypoints not yet passed to the goal (1 = optimal; below
  1 for detours and for runs that ended early; NaN if the robot did not move; above 1 only if
  the robot cut closer to obstacles than half its width, or by at most ~0.5 % of the waypoint
  tolerance where the reference touches a disc's rim at a sample next to the exact optimum);
  max/mean_deviation: distance of each pose to the exact shortest-path polyline (through the
  waypoints' exact points).
* duration, mean_speed = path_length / duration, goal position error (m) and goal yaw error
  (degrees, wrapped to [0, 180]) of the last pose.
* smoothness: mean |jerk| (m/s^3) of the planar motion, from the measured velocity turned
  into the world frame, by finite differences; angular_smoothness: mean |d wz / dt| (rad/s^2).
* max_pitch, max_roll (degrees), climb (m above the start): a body that rides the ground; NaN for
  the planar body.
* reference_mean/max_deviation: with ``scenario.reference`` (inline (t, x, y) rows or a CSV
  file with header ``t,x,y``, relative to the scenario file's folder): the simulated position
  interpolated at each reference time inside the simulated time span, distance to the
  reference point. Both clocks start at 0 (the episode start). With ``reference.compare: path``
  the comparison is spatial instead, blind to the pace: mean is the mean distance of the simulated
  positions to the recorded path, max the largest distance between the two paths either way (the
  Hausdorff distance: a run that took the same way slower is close; one that left the recorded
  way, or stopped half-way along it, is not).
"""
from __future__ import annotations

import csv
import math
import os
from collections import OrderedDict
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..core.errors import ScenarioError
from .gaps import (box_box_distance, clearance_obstacles, footprint_core, is_outlined, min_obstacle_gap,
                   obstacle_shapes)
from .paths import path_through, reference_path, shortest_path
from ..scenario.motion import displacement, tracks
from ..sim.trajectory import Collision, Trajectory
from .result import Metrics
from ..scenario.model import Scenario

NAN = float("nan")
MOVED = 1e-9  # m: a robot that drove less than this "did not move" (path efficiency is NaN)


def compute_metrics(scenario: Scenario, trajectory: Trajectory, *,
                    collision: Collision | None = None) -> Metrics:
    """All metrics of one episode (see the module docstring for the definitions)."""
    t = np.asarray(trajectory.t, dtype=float)
    pose = np.asarray(trajectory.pose, dtype=float).reshape(-1, 3)
    vel = np.asarray(trajectory.velocity, dtype=float).reshape(-1, 3)
    if not len(t) == len(pose) == len(vel):
        raise ValueError(
            f"trajectory arrays disagree: t has {len(t)} samples, pose {len(pose)}, velocity {len(vel)} "
            f"(scenario {scenario.name or scenario.source or '?'}); every physics-rate array needs one row per time stamp")
    xy = pose[:, :2]

    clear, clear_name, clear_t, clear_x, clear_y = min_clearance(scenario, t, pose)
    if collision is not None:
        clear, clear_name, clear_t = 0.0, collision.obstacle, float(collision.time)
        clear_x, clear_y = _position_at(t, xy, clear_t)
    gap, gap_a, gap_b = min_obstacle_gap(scenario)

    z = getattr(trajectory, "z", None)
    if z is not None and len(z) == len(xy) and len(xy) > 1:   # over the ground: up and down slopes count
        path_length = float(np.sqrt(np.diff(xy[:, 0]) ** 2 + np.diff(xy[:, 1]) ** 2 + np.diff(z) ** 2).sum())
    else:
        path_length = float(np.sqrt(np.diff(xy[:, 0]) ** 2 + np.diff(xy[:, 1]) ** 2).sum()) if len(xy) > 1 else 0.0
    sp = shortest_path(scenario)
    ref = reference_path(scenario)   # through the waypoints' tolerance discs (= sp without waypoints)
    shortest = ref.length if ref is not None else NAN
    goal = scenario.mission.goal
    goal_err = math.hypot(pose[-1, 0] - goal.x, pose[-1, 1] - goal.y) if len(pose) else NAN
    efficiency = (shortest / (path_length + remaining_length(scenario, trajectory, xy))
                  if path_length > MOVED else NAN)
    if sp is not None and len(xy):
        dev = polyline_distance(xy, sp.points)
        max_dev, mean_dev = float(dev.max()), float(dev.mean())
    else:
        max_dev = mean_dev = NAN
    duration = float(trajectory.duration)
    yaw_err = abs(math.degrees(wrap_angle(pose[-1, 2] - goal.yaw_rad))) if len(pose) else NAN
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
        **attitude(trajectory),
    )


def attitude(trajectory: Trajectory) -> dict[str, float]:
    """max_pitch and max_roll (degrees, largest magnitude) and climb (m above the start) of a body
    that rides the ground; NaN for the planar body (no attitude recorded)."""
    pitch, roll, z = (getattr(trajectory, k, None) for k in ("pitch", "roll", "z"))
    if pitch is None or roll is None or z is None or not len(z):
        return {}
    return {"max_pitch": float(np.degrees(np.abs(pitch).max())), "max_roll": float(np.degrees(np.abs(roll).max())),
            "climb": float(np.max(z) - z[0])}


def remaining_length(scenario: Scenario, trajectory: Trajectory, xy: np.ndarray) -> float:
    """How far the robot still had to go from its last position: straight to the goal point when
    it stopped inside the goal tolerance after every waypoint (so stopping short of the exact
    point costs nothing); otherwise the shortest collision-free path from there through the
    waypoints not yet passed to the goal, or straight lines if its last position is boxed in."""
    if not len(xy):
        return NAN
    m = scenario.mission
    passed = min(len(trajectory.waypoint_times), len(m.waypoints))
    stops = [(float(xy[-1, 0]), float(xy[-1, 1])), *((w.x, w.y) for w in m.waypoints[passed:]),
             (m.goal.x, m.goal.y)]
    straight = float(sum(math.dist(a, b) for a, b in zip(stops, stops[1:])))
    if passed == len(m.waypoints) and straight <= m.goal_tolerance.position:
        return straight
    completion = path_through(scenario, stops)
    return completion.length if completion is not None else straight


def min_clearance(scenario: Scenario, t: np.ndarray, pose: np.ndarray
                  ) -> tuple[float, str, float, float, float]:
    """``(distance, obstacle, time, x, y)`` of the closest approach of the footprint to any
    obstacle over the poses; the earliest one on ties; ``(inf, "", nan, nan, nan)`` with no
    obstacles or no poses. On terrain, a face or a steep slope the body cannot cross counts as an
    obstacle, named after its element ("steps 'stairs' (0.17 m step)": ``gaps.clearance_obstacles``).

    Exact at every pose but cheap: the distance of the robot centre to an obstacle bounds the
    footprint's (within the footprint's outer and inner radius). A pass over every
    ``COARSE_STRIDE``-th pose, widened by how far the robot moves around it, keeps the windows
    that may hold the minimum; a full-rate centre pass inside them keeps the poses that may;
    only those get the exact box-to-box distance.

    A moving obstacle is measured where it was at each moment: the robot's poses relative to the
    obstacle's motion (shifted by its displacement at that time) against the obstacle where the
    scenario places it.
    """
    pose = np.asarray(pose, dtype=float).reshape(-1, 3)
    t = np.asarray(t, dtype=float)
    if not len(pose) or not (scenario.obstacles or scenario.terrain):
        return math.inf, "", NAN, NAN, NAN
    footprint = scenario.robot.footprint
    best = closest_approach(clearance_obstacles(scenario), footprint, pose)
    for j, track in tracks(scenario.obstacles).items():
        rel = pose.copy()
        rel[:, :2] -= displacement(track, t)
        hit = closest_approach((scenario.obstacles[j],), footprint, rel)
        if hit is not None and (best is None or hit[0] < best[0] or (hit[0] == best[0] and hit[2] < best[2])):
            best = hit
    if best is None:
        return math.inf, "", NAN, NAN, NAN
    dist, name, i = best
    return dist, name, float(t[i]), float(pose[i, 0]), float(pose[i, 1])


def culprit_clearance(result: Any) -> tuple[str, float, float] | None:
    """(obstacle, distance, time) of the closest approach to the obstacle the outcome is about (a
    safety stop's or a collision's), when that is not the obstacle of ``min_clearance``: a robot
    stopped for a person can pass nearer a wall, and the clearance that explains the stop is the
    person's. None otherwise (or without a trajectory)."""
    import dataclasses

    event = result.safety_stop or result.collision
    name = getattr(event, "obstacle", "") if event is not None else ""
    m = result.metrics
    if not name or name == m.min_clearance_obstacle:
        return None
    try:
        obstacle = result.scenario.obstacle(name)
    except KeyError:
        return None
    one = dataclasses.replace(result.scenario, obstacles=(obstacle,), terrain=())   # that obstacle alone
    dist, _, time, _, _ = min_clearance(one, result.trajectory.t, result.trajectory.pose)
    return (name, dist, time) if math.isfinite(dist) else None


def closest_approach(obstacles: Sequence, footprint, pose: np.ndarray) -> tuple[float, str, int] | None:
    """(distance, obstacle name, pose index) of the footprint's closest approach, over the poses
    (x, y, yaw) ``pose``, to ``obstacles`` where they stand (boxes, cylinders, polygons, meshes;
    0 where they overlap); None without obstacles or poses."""
    simple = tuple(o for o in obstacles if not is_outlined(o))
    best = _closest_simple(simple, footprint, pose) if len(simple) else None
    for obs in obstacles:
        if is_outlined(obs):
            hit = _closest_outlined(obs, footprint, pose, best[0] if best is not None else math.inf)
            if hit is not None and (best is None or hit[0] < best[0] or (hit[0] == best[0] and hit[2] < best[2])):
                best = hit
    return best


def _closest_outlined(obs, footprint, pose: np.ndarray, beat: float) -> tuple[float, str, int] | None:
    """The closest approach to a polygon or mesh obstacle: exact footprint-to-part distances, only
    at the poses whose centre may come closer than the best so far (``beat``, or the exact distance
    at the pose nearest to the obstacle's centre), part by part within its bounding circle."""
    from ..scenario.geometry import convex_parts, footprint_part_distance

    hl, hw, rho = footprint_core(footprint)
    r_out = math.hypot(hl, hw) + rho
    parts = convex_parts(obs)
    centres = [p.mean(axis=0) for p in parts]
    radii = [float(np.hypot(*(p - c).T).max()) for p, c in zip(parts, centres)]
    gaps = np.min([np.hypot(pose[:, 0] - c[0], pose[:, 1] - c[1]) - r for c, r in zip(centres, radii)], axis=0)
    nearest = int(np.argmin(gaps))
    beat = min(beat, min(float(footprint_part_distance(hl, hw, rho, pose[nearest:nearest + 1], p)[0])
                         for p in parts))
    best = None
    for part, c, r in zip(parts, centres, radii):
        idx = np.flatnonzero(np.hypot(pose[:, 0] - c[0], pose[:, 1] - c[1]) - r - r_out <= beat + 1e-12)
        if not len(idx):
            continue
        d = footprint_part_distance(hl, hw, rho, pose[idx], part)
        k = int(np.argmin(d))
        hit = (float(d[k]), obs.name, int(idx[k]))
        if best is None or hit[0] < best[0] or (hit[0] == best[0] and hit[2] < best[2]):
            best = hit
            beat = min(beat, hit[0])
    return best


def _closest_simple(obstacles: tuple, footprint, pose: np.ndarray) -> tuple[float, str, int] | None:
    """``closest_approach`` among boxes and cylinders (rounded boxes, vectorised with pruning)."""
    shapes = obstacle_shapes(obstacles)
    n, k = len(pose), len(shapes)
    if not k or not n:
        return None
    hl, hw, rho = footprint_core(footprint)
    r_out, r_in = math.hypot(hl, hw) + rho, min(hl, hw) + rho
    ox, oy, oc, os_, ohl, ohw, orho = (a[:, None] for a in (
        shapes.x, shapes.y, shapes.cos, shapes.sin, shapes.hl, shapes.hw, shapes.rho))
    x, y = pose[:, 0], pose[:, 1]
    # 1. every S-th pose; window w = poses [w*S, (w+1)*S), which stay within reach[w] of pose w*S
    stride = COARSE_STRIDE
    rep = np.arange(n) // stride * stride
    away = np.sqrt((x - x[rep]) ** 2 + (y - y[rep]) ** 2)
    reach = np.maximum.reduceat(away, np.arange(0, n, stride))
    centre = _centre_distance(x[::stride], y[::stride], ox, oy, oc, os_, ohl, ohw, orho)  # (k, nw)
    bound = np.maximum(centre - r_in, 0.0).min()
    kw, ww = np.nonzero(centre - reach - r_out <= bound + 1e-12)
    # 2. every pose of the kept windows
    idx = (ww[:, None] * stride + np.arange(stride)).ravel()
    kk = np.repeat(kw, stride)
    inside = idx < n
    idx, kk = idx[inside], kk[inside]
    centre = _centre_distance(x[idx], y[idx], shapes.x[kk], shapes.y[kk], shapes.cos[kk], shapes.sin[kk],
                              shapes.hl[kk], shapes.hw[kk], shapes.rho[kk])
    bound = min(bound, np.maximum(centre - r_in, 0.0).min())
    keep = centre - r_out <= bound + 1e-12
    idx, kk = idx[keep], kk[keep]
    order = np.lexsort((kk, idx))   # time first: the first minimum is the earliest
    idx, kk = idx[order], kk[order]
    # 3. exact footprint-obstacle distance
    yaw = pose[idx, 2]
    exact = box_box_distance(x[idx], y[idx], np.cos(yaw), np.sin(yaw), hl, hw,
                             shapes.x[kk], shapes.y[kk], shapes.cos[kk], shapes.sin[kk],
                             shapes.hl[kk], shapes.hw[kk])
    exact = np.maximum(exact - rho - shapes.rho[kk], 0.0)
    best = int(np.argmin(exact))
    i, j = int(idx[best]), int(kk[best])
    return float(exact[best]), shapes.names[j], i


COARSE_STRIDE = 10  # poses per window of the coarse clearance pass


def _centre_distance(px, py, bx, by, bc, bs, bhl, bhw, brho):
    """Distance from points to rounded boxes (negative inside a cylinder); broadcasts."""
    dx = px - bx
    dy = py - by
    u = np.maximum(np.abs(dx * bc + dy * bs) - bhl, 0.0)
    v = np.maximum(np.abs(dy * bc - dx * bs) - bhw, 0.0)
    return np.sqrt(u * u + v * v) - brho


def polyline_distance(points: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Distance of each of the (n, 2) points to the polyline through the (m, 2) vertices."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    line = np.asarray(line, dtype=float).reshape(-1, 2)
    px, py = points[:, 0], points[:, 1]
    if len(line) == 1:
        return np.sqrt((px - line[0, 0]) ** 2 + (py - line[0, 1]) ** 2)
    ax, ay = line[:-1, 0:1], line[:-1, 1:2]                       # (s, 1)
    dx, dy = np.diff(line[:, 0])[:, None], np.diff(line[:, 1])[:, None]
    inv = 1.0 / np.maximum(dx * dx + dy * dy, 1e-300)
    rx = px - ax                                                  # (s, n)
    ry = py - ay
    u = np.clip((rx * dx + ry * dy) * inv, 0.0, 1.0)
    rx -= u * dx
    ry -= u * dy
    return np.sqrt((rx * rx + ry * ry).min(axis=0))


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
    if not (np.diff(t) > 0).all():
        keep = np.concatenate([[True], np.diff(t) > 0])
        t, pose, velocity = t[keep], pose[keep], velocity[keep]
    yaw = pose[:, 2]
    c, s = np.cos(yaw), np.sin(yaw)
    vx, vy, wz = velocity[:, 0], velocity[:, 1], velocity[:, 2]
    wx = c * vx - s * vy                                  # world-frame velocity
    wy = s * vx + c * vy
    dt = np.diff(t)
    ang = float(np.abs(np.diff(wz) / dt).mean()) if len(dt) else NAN
    if len(t) < 3:
        return NAN, ang
    ax, ay = np.diff(wx) / dt, np.diff(wy) / dt
    dtm = 0.5 * (t[2:] - t[:-2])                          # spacing of the acceleration samples
    jx, jy = np.diff(ax) / dtm, np.diff(ay) / dtm
    return float(np.sqrt(jx * jx + jy * jy).mean()), ang


# --------------------------------------------------------------------------------------------
# Reference trajectory


def reference_deviation(scenario: Scenario, t: np.ndarray, xy: np.ndarray) -> tuple[float, float]:
    """(mean, max) distance between the reference points and the simulated positions at the
    same times, over the reference times within the simulated span; NaN without a reference
    or without overlap."""
    ref = load_reference(scenario)
    if ref is None or len(t) == 0:
        return NAN, NAN
    if scenario.reference.compare == "path":
        return path_deviation(ref[:, 1:3], xy)
    inside = (ref[:, 0] >= t[0]) & (ref[:, 0] <= t[-1])
    if not inside.any():
        return NAN, NAN
    rt = ref[inside, 0]
    sx = np.interp(rt, t, xy[:, 0])
    sy = np.interp(rt, t, xy[:, 1])
    dev = np.hypot(sx - ref[inside, 1], sy - ref[inside, 2])
    return float(dev.mean()), float(dev.max())


def path_deviation(ref_xy: np.ndarray, xy: np.ndarray) -> tuple[float, float]:
    """(mean distance of ``xy`` to the polyline ``ref_xy``, Hausdorff distance between the two
    polylines): where both paths went, not when."""
    import shapely
    from shapely.geometry import LineString, Point

    def line(p: np.ndarray):
        return LineString(p) if len(p) > 1 else Point(p[0])
    ref_line, run_line = line(ref_xy), line(xy)
    to_ref = shapely.distance(shapely.points(xy), ref_line)
    to_run = shapely.distance(shapely.points(ref_xy), run_line)
    return float(to_ref.mean()), float(max(to_ref.max(), to_run.max()))


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
