"""Dynamic-window planner (Fox, Burgard, Thrun 1997), lidar-based and footprint-aware.

Each tick it samples velocity commands (vx, vy, wz) inside the *dynamic window*, the set the
robot can reach within one tick from its current command given the acceleration limits; rolls
each one out as a constant twist over ``horizon`` seconds; measures the clearance between the
robot's footprint (box or circle) at every rollout pose and the lidar points; drops the
commands whose rollout comes closer than the safety layer's margin plus a buffer; and picks
the best of the rest by a weighted sum of progress towards the target, heading, clearance
and speed. Near the goal of a mission with a yaw tolerance it turns to the goal yaw.

Speed: the velocity grid and every rollout pose are precomputed at ``reset``; a tick is one
small matrix product (rollout poses x lidar points) and a handful of array operations.
"""
from __future__ import annotations

import math

import numpy as np

from ..planner import Command, Observation
from ..scenario import Scenario
from ._common import RobotParams, require_reset, target_in_robot_frame, wrap_angle


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
    """

    name = "dwa"
    version = "1.0"

    def __init__(self, *, horizon: float = 1.5, steps: int = 5, window: int = 1,
                 reverse_speed: float = 0.2, clearance_buffer: float = 0.05,
                 clearance_cap: float = 0.8, progress_weight: float = 1.0,
                 heading_weight: float = 0.4, clearance_weight: float = 0.4,
                 velocity_weight: float = 0.1):
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
        self._p: RobotParams | None = None

    # -- episode set-up -------------------------------------------------------------------
    def reset(self, scenario: Scenario) -> None:
        p = self._p = RobotParams.from_scenario(scenario)
        w = self.window
        # Velocity grids: one grid step = the change the accel limits allow per tick / window.
        self._vx = _grid(-self.reverse_speed, p.max_speed, p.max_accel * p.tick / w)
        self._vy = _grid(-p.max_lateral_speed, p.max_lateral_speed, p.max_accel * p.tick / w)
        self._wz = _grid(-p.max_yaw_rate, p.max_yaw_rate, p.max_yaw_accel * p.tick / w)
        VX, VY, WZ = np.meshgrid(self._vx, self._vy, self._wz, indexing="ij")
        t = np.linspace(self.horizon / self.steps, self.horizon, self.steps)
        x, y, th = _rollout(VX[..., None], VY[..., None], WZ[..., None], t)
        c, s = np.cos(th), np.sin(th)
        # Rows that map a lidar point [px, py, 1] (robot frame now) into each rollout pose's
        # frame: lx = c px + s py - (c x + s y);  ly = -s px + c py + (s x - c y).
        A = np.empty(VX.shape + (self.steps, 2, 3))
        A[..., 0, 0], A[..., 0, 1], A[..., 0, 2] = c, s, -(c * x + s * y)
        A[..., 1, 0], A[..., 1, 1], A[..., 1, 2] = -s, c, s * x - c * y
        self._A = A
        self._end = np.stack([x[..., -1], y[..., -1], th[..., -1]], axis=-1)   # (nvx, nvy, nwz, 3)
        self._reach = np.hypot(x, y).max(axis=-1)                                # rollout extent
        self._vel = VX / max(p.max_speed, 1e-9)
        if p.circle:
            self._half = np.zeros(2)
            self._radius = p.half_length
        else:
            self._half = np.array([p.half_length, p.half_width])
            self._radius = 0.0
        self._body = math.hypot(p.half_length, p.half_width) if not p.circle else p.half_length
        self._angles_key = None
        self._idx = None          # current command as grid indices, set from the first observation
        self._goal_phase = False

    def _index_of(self, grid: np.ndarray, value: float) -> int:
        return int(np.argmin(np.abs(grid - value)))

    def _beams(self, angles: np.ndarray) -> None:
        """Per-episode lidar geometry: unit vectors, and the inflation that covers the surface
        between two neighbouring beams (half the beam spacing at the rollouts' reach)."""
        self._angles_key = (angles.shape, float(angles[0]) if len(angles) else 0.0)
        self._unit = np.stack([np.cos(angles), np.sin(angles)]).astype(float)
        spacing = float(np.max(np.diff(angles))) if len(angles) > 1 else 0.0
        reach = float(self._reach.max()) + self._body
        self._inflation = 0.5 * spacing * reach
        p = self._p
        self._min_clear = p.safety_margin + self.clearance_buffer + self._inflation

    # -- one tick -------------------------------------------------------------------------
    def act(self, obs: Observation) -> Command:
        p = require_reset(self._p, "DynamicWindowPlanner")
        if self._angles_key is None or self._angles_key[0] != obs.angles.shape:
            self._beams(obs.angles)
        if self._idx is None:
            v = obs.velocity
            self._idx = (self._index_of(self._vx, float(v[0])), self._index_of(self._vy, float(v[1])),
                         self._index_of(self._wz, float(v[2])))
        w = self.window
        i, j, k = self._idx
        sx = slice(max(i - w, 0), i + w + 1)
        sy = slice(max(j - w, 0), j + w + 1)
        sw = slice(max(k - w, 0), k + w + 1)
        A = self._A[sx, sy, sw]
        shape = A.shape[:3]
        n = shape[0] * shape[1] * shape[2]

        # Lidar points that can matter: within the window's reach + body + clearance cap.
        reach = float(self._reach[sx, sy, sw].max()) + self._body + self.clearance_cap
        r = obs.ranges
        near = np.flatnonzero((r < reach) & (r < p.range_max * 0.999))
        if near.size:
            P = np.empty((3, near.size))
            rn = r[near]
            np.multiply(self._unit[:, near], rn, out=P[:2])
            P[2] = 1.0
            E = A.reshape(-1, 3) @ P                        # (n * steps * 2, points)
            np.abs(E, out=E)
            E = E.reshape(n * self.steps, 2, -1)
            E -= self._half[None, :, None]
            np.maximum(E, 0.0, out=E)
            np.square(E, out=E)
            d2 = (E[:, 0] + E[:, 1]).min(axis=1).reshape(n, self.steps).min(axis=1)
            clear = np.sqrt(d2) - self._radius - self._inflation
        else:
            clear = np.full(n, np.inf)

        tx, ty = target_in_robot_frame(obs.pose, obs.target)
        end = self._end[sx, sy, sw].reshape(n, 3)
        ex, ey, eth = end[:, 0], end[:, 1], end[:, 2]
        d0 = math.hypot(tx, ty)
        goal_phase = self._in_goal_phase(obs, d0)
        dend = np.hypot(tx - ex, ty - ey)
        if goal_phase:
            want = wrap_angle(p.goal_yaw - float(obs.pose[2]))
            heading_err = np.abs(wrap_angle(want - eth))
            progress = -dend / max(p.goal_tolerance, 1e-6)
        else:
            heading_err = np.abs(wrap_angle(np.arctan2(ty - ey, tx - ex) - eth))
            progress = (d0 - dend) / (p.max_speed * self.horizon)
        wp, wh, wc, wv = self.weights
        score = (wp * progress + wh * (1.0 - heading_err / math.pi)
                 + wc * np.minimum(clear, self.clearance_cap) / self.clearance_cap
                 + wv * self._vel[sx, sy, sw].reshape(n))
        admissible = clear >= self._min_clear
        if admissible.any():
            best = int(np.argmax(np.where(admissible, score, -np.inf)))
        else:  # nothing is safe: brake as hard as the window allows (lowest speed, most room)
            speed = np.abs(self._vx[sx]).repeat(shape[1] * shape[2]) \
                + np.abs(np.tile(self._vy[sy].repeat(shape[2]), shape[0]))
            best = int(np.lexsort((-clear, speed))[0])
        bi, rem = divmod(best, shape[1] * shape[2])
        bj, bk = divmod(rem, shape[2])
        self._idx = (sx.start + bi, sy.start + bj, sw.start + bk)
        return Command(float(self._vx[self._idx[0]]), float(self._vy[self._idx[1]]),
                       float(self._wz[self._idx[2]]))

    def _in_goal_phase(self, obs: Observation, dist: float) -> bool:
        """Turning to the goal yaw: the target is the goal, the mission checks the yaw and the
        robot is within the position tolerance (with hysteresis so it does not flicker)."""
        p = self._p
        if p.goal_yaw_tolerance is None or len(obs.waypoints):
            return False
        limit = p.goal_tolerance * (0.9 if self._goal_phase else 0.6)
        self._goal_phase = dist < limit
        return self._goal_phase
