"""Dynamic-window planner (Fox, Burgard, Thrun 1997), lidar-based and footprint-aware.

Each tick it samples velocity commands (vx, vy, wz) inside the *dynamic window*, the set the
robot can reach within one tick from its current command given the acceleration limits; rolls
each one out as a constant twist over ``horizon`` seconds; measures the clearance between the
robot's footprint (box or circle) at every rollout pose and the lidar points; drops the
commands whose rollout comes closer than the safety layer's margin plus a buffer (so the
safety layer's own sweep stays clear: it slows down near obstacles); and picks the best of
the rest by a weighted sum of progress towards the target, heading, clearance and speed.
Near the goal of a mission with a yaw tolerance it turns to the goal yaw.

Speed: the commands live on a fixed grid (one step = what the acceleration limits allow in one
tick) whose rollouts are computed once per robot description and shared by every instance; the
candidates of each dynamic window are gathered once into one contiguous matrix that maps lidar
points into every rollout pose's frame. A tick is then one small matrix product (rollout poses x
nearby lidar points, float32) and a handful of array operations.
"""
from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np

from ..planner import Command, Observation
from ..scenario import Scenario
from ._common import RobotParams, require_reset, target_in_robot_frame, wrap_angle

TABLE_CACHE_SIZE = 4    # robot descriptions x settings whose rollout tables are kept


def _grid(lo: float, hi: float, step: float) -> np.ndarray:
    """Multiples of ``step`` in [lo, hi], always holding 0, lo and hi."""
    if hi - lo < 1e-12:
        return np.array([0.0])
    k = np.arange(math.ceil(lo / step - 1e-9), math.floor(hi / step + 1e-9) + 1)
    values = set((k * step).tolist()) | {0.0, lo, hi}
    return np.array(sorted(v for v in values if lo - 1e-12 <= v <= hi + 1e-12))


def _rollout(vx, vy, wz, t):
    """Poses (x, y, yaw) at times ``t`` of a constant twist from the origin (exact arcs)."""
    th = wz * t
    # sin(wt)/w and (1 - cos(wt))/w without dividing by a small w
    s_over_w = t * np.sinc(th / math.pi)
    c_over_w = t * np.sin(th / 2.0) * np.sinc(th / (2.0 * math.pi))
    x = vx * s_over_w - vy * c_over_w
    y = vx * c_over_w + vy * s_over_w
    return x, y, th


def footprint_distance(px, py, x, y, th, half_length, half_width, radius=0.0):
    """Distance from points (px, py) to a box (half extents) or circle (``radius``, zero half
    extents) footprint at pose (x, y, th); 0 inside. Broadcasts over all arguments."""
    c, s = np.cos(th), np.sin(th)
    dx, dy = px - x, py - y
    ex = np.maximum(np.abs(c * dx + s * dy) - half_length, 0.0)
    ey = np.maximum(np.abs(-s * dx + c * dy) - half_width, 0.0)
    return np.maximum(np.hypot(ex, ey) - radius, 0.0)


class _Table:
    """Velocity grid and rollouts for one robot + settings, and the dynamic windows seen so far."""

    def __init__(self, p: RobotParams, horizon: float, steps: int, window: int,
                 reverse_speed: float, cap: float):
        self.steps = steps
        self.vx = _grid(-reverse_speed, p.max_speed, p.max_accel * p.tick / window)
        self.vy = _grid(-p.max_lateral_speed, p.max_lateral_speed, p.max_accel * p.tick / window)
        self.wz = _grid(-p.max_yaw_rate, p.max_yaw_rate, p.max_yaw_accel * p.tick / window)
        self.shape = (len(self.vx), len(self.vy), len(self.wz))
        VX, VY, WZ = (a.ravel() for a in np.meshgrid(self.vx, self.vy, self.wz, indexing="ij"))
        t = np.linspace(horizon / steps, horizon, steps)
        self.x, self.y, self.th = _rollout(VX[:, None], VY[:, None], WZ[:, None], t)  # (G, steps)
        self.vel = VX / max(p.max_speed, 1e-9)
        self.turn = np.abs(WZ) / max(p.max_yaw_rate, 1e-9)
        # yaw reached if the robot braked as hard as it can after the next tick (Fox et al.)
        self.stop_yaw = WZ * p.tick + np.sign(WZ) * WZ ** 2 / (2.0 * max(p.max_yaw_accel, 1e-9))
        if p.circle:
            self.half, self.radius, self.body = (0.0, 0.0), p.half_length, p.half_length
        else:
            self.half, self.radius = (p.half_length, p.half_width), 0.0
            self.body = math.hypot(p.half_length, p.half_width)
        self.reach = np.hypot(self.x, self.y).max(axis=1) + self.body + cap     # (G,)
        self.cap = cap
        self.windows: dict[tuple[int, int, int], tuple] = {}

    def window(self, idx: tuple[int, int, int], w: int) -> tuple:
        """Candidates of the dynamic window around grid command ``idx`` (cached): the rows
        mapping a point [px, py, 1] into each rollout pose's frame, the footprint's half
        extents per row, rollout positions, end poses, speed scores, reach, grid indices."""
        cached = self.windows.get(idx)
        if cached is None:
            axes = [np.unique(np.clip(np.arange(i - w, i + w + 1), 0, n - 1))
                    for i, n in zip(idx, self.shape)]
            I, J, K = (a.ravel() for a in np.meshgrid(*axes, indexing="ij"))
            g = (I * self.shape[1] + J) * self.shape[2] + K
            x, y, th = self.x[g], self.y[g], self.th[g]
            c, s = np.cos(th), np.sin(th)
            # lx = c px + s py - (c x + s y);  ly = -s px + c py + (s x - c y)
            A = np.empty((len(g), self.steps, 2, 3), dtype=np.float32)
            A[:, :, 0, 0], A[:, :, 0, 1], A[:, :, 0, 2] = c, s, -(c * x + s * y)
            A[:, :, 1, 0], A[:, :, 1, 1], A[:, :, 1, 2] = -s, c, s * x - c * y
            half = np.tile(np.asarray(self.half, dtype=np.float32), len(g) * self.steps)[:, None]
            cached = (A.reshape(-1, 3), half, x, y, x[:, -1].copy(), y[:, -1].copy(),
                      th[:, -1].copy(), self.vel[g], self.turn[g], self.stop_yaw[g], float(self.reach[g].max()), np.stack([I, J, K], axis=1))
            self.windows[idx] = cached
        return cached


_TABLES: "OrderedDict[tuple, _Table]" = OrderedDict()


def _table(p: RobotParams, *settings) -> _Table:
    key = (p,) + settings
    table = _TABLES.get(key)
    if table is None:
        table = _TABLES[key] = _Table(p, *settings)
        while len(_TABLES) > TABLE_CACHE_SIZE:
            _TABLES.popitem(last=False)
    else:
        _TABLES.move_to_end(key)
    return table


class DynamicWindowPlanner:
    """Fox et al.'s dynamic window approach with footprint-aware clearance from lidar points.

    Parameters (keyword only; defaults tuned on the five seed scenarios):
        horizon: rollout length in seconds (1.5).
        steps: poses checked per rollout (5).
        window: samples on each side of the current command per velocity axis (1: 3 values
            per axis, 27 candidates for an omnidirectional robot, 9 for a differential one).
        reverse_speed: slowest forward speed allowed, m/s, as a positive number (0.2).
        clearance_buffer: metres kept beyond the safety layer's margin (0.05).
        clearance_cap: clearances above this many metres score the same (0.8).
        progress_weight, heading_weight, clearance_weight, velocity_weight: the score weights
            (1.0, 0.4, 0.4, 0.1).
        turn_weight: penalty on the yaw rate, so that ties do not make it wobble (0.05).
        lookahead: metres of the straight lane to the target checked for a blockage; when it
            is blocked the planner aims along the closest free lane instead (3.0; 0 = off).
    """

    name = "dwa"
    version = "1.0"

    def __init__(self, *, horizon: float = 1.5, steps: int = 5, window: int = 1,
                 reverse_speed: float = 0.2, clearance_buffer: float = 0.05,
                 clearance_cap: float = 0.8, progress_weight: float = 1.0,
                 heading_weight: float = 0.4, clearance_weight: float = 0.4,
                 velocity_weight: float = 0.1, turn_weight: float = 0.05,
                 lookahead: float = 3.0):
        if horizon <= 0 or steps < 1 or window < 1:
            raise ValueError("DynamicWindowPlanner: horizon must be > 0, steps >= 1, window >= 1")
        self.horizon = float(horizon)
        self.steps = int(steps)
        self.window = int(window)
        self.reverse_speed = float(reverse_speed)
        self.clearance_buffer = float(clearance_buffer)
        self.clearance_cap = float(clearance_cap)
        self.weights = (float(progress_weight), float(heading_weight),
                        float(clearance_weight), float(velocity_weight))
        self.turn_weight = float(turn_weight)
        self.lookahead = float(lookahead)
        self._p: RobotParams | None = None
        self._idx: tuple[int, int, int] | None = None
        self._goal_phase = False

    # -- episode set-up -------------------------------------------------------------------
    def reset(self, scenario: Scenario) -> None:
        self._p = p = RobotParams.from_scenario(scenario)
        self._t = _table(p, self.horizon, self.steps, self.window, self.reverse_speed,
                         self.clearance_cap)
        self._idx = None          # current command as grid indices, set from the first observation
        self._goal_phase = False
        self._beams_shape = None
        self._side = 0.0          # side (+1 left, -1 right) of the last detour around a blockage

    def _beams(self, angles: np.ndarray) -> None:
        """Per-episode lidar geometry: float32 unit vectors of the beams, and the inflation
        that covers the surface between two neighbouring beams (half the beam spacing at the
        rollouts' reach)."""
        t = self._t
        self._beams_shape = angles.shape
        self._unit = np.stack([np.cos(angles), np.sin(angles)]).astype(np.float32)
        spacing = float(np.max(np.diff(angles))) if len(angles) > 1 else 0.0
        reach = float(t.reach.max()) - t.cap
        self._inflation = 0.5 * spacing * reach
        self._min_clear = self._p.safety_margin + self.clearance_buffer + self._inflation
        # detour lanes: every beam direction is a candidate direction
        self._beam_angles = np.asarray(angles, dtype=float)
        diff = self._beam_angles[None, :] - self._beam_angles[:, None]   # [direction, beam]
        self._cos_diff, self._sin_diff = np.cos(diff), np.sin(diff)
        self._lane = self._t.half[1] + self._t.radius + self._min_clear

    # -- one tick -------------------------------------------------------------------------
    def act(self, obs: Observation) -> Command:
        p = require_reset(self._p, "DynamicWindowPlanner")
        t = self._t
        if self._beams_shape != obs.angles.shape:
            self._beams(obs.angles)
        if self._idx is None:
            v = obs.velocity
            self._idx = tuple(int(np.argmin(np.abs(grid - float(value))))
                              for grid, value in zip((t.vx, t.vy, t.wz), v))
        A, half, X, Y, ex, ey, eth, vel, turn, stop_yaw, reach, cand = t.window(self._idx, self.window)
        n = len(cand)

        # Clearance: footprint at every rollout pose vs the lidar points within reach.
        r = obs.ranges
        near = np.flatnonzero(r < min(reach, p.range_max * 0.999))
        if near.size:
            P = np.ones((3, near.size), dtype=np.float32)
            np.multiply(self._unit[:, near], r[near], out=P[:2])
            E = A @ P                                   # (n * steps * 2, points): local x, y
            np.abs(E, out=E)
            E -= half
            np.maximum(E, 0.0, out=E)
            np.square(E, out=E)
            E = E.reshape(n, self.steps, 2, -1)
            d2 = (E[:, :, 0] + E[:, :, 1]).reshape(n, -1).min(axis=1)
            clear = np.sqrt(d2, dtype=float)
            clear -= t.radius + self._inflation
        else:
            clear = np.full(n, t.cap)

        # Score: progress towards the target, heading, clearance, speed.
        tx, ty = target_in_robot_frame(obs.pose, obs.target)
        if self.lookahead > 0 and near.size:
            tx, ty = self._subgoal(tx, ty, r, near)
        d0 = math.hypot(tx, ty)
        # closest approach to the target along the rollout: driving past a near target is fine
        dmin = np.hypot(tx - X, ty - Y).min(axis=1)
        if self._in_goal_phase(obs, d0):
            want = float(wrap_angle(p.goal_yaw - float(obs.pose[2])))
            heading_err = np.abs(wrap_angle(want - stop_yaw))
            progress = np.hypot(tx - ex, ty - ey) * (-1.0 / max(p.goal_tolerance, 1e-6))
        else:
            heading_err = np.abs(wrap_angle(np.arctan2(ty - ey, tx - ex) - eth))
            # a rollout that reaches the target is not penalised for ending past it
            reach_tol = 0.5 * (p.waypoint_tolerance if len(obs.waypoints) else p.goal_tolerance)
            heading_err[dmin < reach_tol] = 0.0
            progress = (d0 - dmin) * (1.0 / (p.max_speed * self.horizon))
        wp, wh, wc, wv = self.weights
        score = progress * wp
        score += heading_err * (-wh / math.pi)
        score += clear * (wc / self.clearance_cap)
        score += vel * wv
        score -= turn * self.turn_weight
        admissible = clear >= self._min_clear
        if admissible.any():
            score[~admissible] = -np.inf
            best = int(np.argmax(score))
        else:  # nothing is safe: brake as hard as the window allows (lowest speed, most room)
            speed = np.abs(t.vx[cand[:, 0]]) + np.abs(t.vy[cand[:, 1]])
            best = int(np.lexsort((-clear, speed))[0])
        i, j, k = (int(v) for v in cand[best])
        self._idx = (i, j, k)
        return Command(float(t.vx[i]), float(t.vy[j]), float(t.wz[k]))

    def _subgoal(self, tx: float, ty: float, r: np.ndarray, near: np.ndarray) -> tuple[float, float]:
        """The target, or a detour point when lidar points block the straight lane to it.

        Lidar-only DWA falls into the local minimum in front of an obstacle that sits on the
        straight line (every rollout that makes progress is inadmissible). Like the vector
        field histogram, look for the free lane (robot half width + clearance wide, as long as
        the distance to the target, at most ``lookahead``) whose direction is closest to the
        target's, keeping to the side chosen before, and aim along it instead.
        """
        d0 = math.hypot(tx, ty)
        length = min(d0, self.lookahead)
        rn = r[near]
        bearing = math.atan2(ty, tx)
        rel = self._beam_angles[near] - bearing
        along = np.cos(rel) * rn
        lateral = np.abs(np.sin(rel) * rn)
        if not np.any((lateral < self._lane) & (along > 0.0) & (along < length)):
            self._side = 0.0
            return tx, ty
        along = self._cos_diff[:, near] * rn                 # (directions, points)
        lateral = np.abs(self._sin_diff[:, near] * rn)
        blocked = ((lateral < self._lane) & (along > 0.0) & (along < length)).any(axis=1)
        if blocked.all():
            return tx, ty
        offset = wrap_angle(self._beam_angles - bearing)
        cost = np.abs(offset) + np.where(offset * self._side < 0.0, 0.5, 0.0)
        cost[blocked] = np.inf
        j = int(np.argmin(cost))
        self._side = 1.0 if offset[j] > 0.0 else -1.0
        phi = float(self._beam_angles[j])
        return length * math.cos(phi), length * math.sin(phi)

    def _in_goal_phase(self, obs: Observation, dist: float) -> bool:
        """Turning to the goal yaw: the target is the goal, the mission checks the yaw and the
        robot is within the position tolerance (with hysteresis so it does not flicker)."""
        p = self._p
        if p.goal_yaw_tolerance is None or len(obs.waypoints):
            return False
        limit = p.goal_tolerance * (0.9 if self._goal_phase else 0.6)
        self._goal_phase = dist < limit
        return self._goal_phase
