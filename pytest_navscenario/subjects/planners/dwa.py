"""Dynamic-window planner (Fox, Burgard, Thrun 1997), lidar-based and footprint-aware.

Each tick it samples velocity commands (vx, vy, wz) inside the *dynamic window*, the set the
robot can reach within one tick from its current command given the acceleration limits; rolls
each one out as a constant twist over ``horizon`` seconds; measures the clearance between the
robot's footprint (box or circle) at every rollout pose and the lidar points; drops the
commands whose rollout comes closer than the safety layer's margin plus a buffer (so the
safety layer's own sweep stays clear: it slows down near obstacles); and picks the best of
the rest by a weighted sum of progress towards the target, heading, clearance and speed.
Near the goal of a mission with a yaw tolerance it turns to the goal yaw.

Local minima (a dead end, the outer wall of a bend, circling): when the robot has not got
``stall_progress`` closer to its target for ``stall_time`` seconds, it aims, for the rest of that
leg, at a point along a route planned on a grid of every lidar return it has seen (see
``_route.py``; no map from the scenario is used), and it does not stand still while stuck. When
no command is admissible it takes the one with the most room (it backs off) instead of freezing.
Within a metre of its target an omnidirectional robot may arrive sideways (the heading term
fades), which lets a long body reach a waypoint in a corner.

Speed (stall recovery aside, which plans only when stuck): the commands live on a fixed grid (one step = what the acceleration limits allow in one
tick) whose rollouts are computed once per robot description and shared by every instance; the
candidates of each dynamic window are gathered once into one contiguous matrix that maps lidar
points into every rollout pose's frame. A tick is then one small matrix product (rollout poses x
nearby lidar points, float32) and a handful of array operations.
"""
from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np

from ..protocol import Command, Observation
from ...scenario.model import Scenario
from ._common import RobotParams, require_reset, wrap_angle
from ._route import LidarGrid

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
                 reverse_speed: float, cap: float, weights: tuple):
        self.steps, self.w, self.weights = steps, window, weights
        self.vx = _grid(-reverse_speed, p.max_speed, p.max_accel * p.tick / window)
        self.vy = _grid(-p.max_lateral_speed, p.max_lateral_speed, p.max_accel * p.tick / window)
        self.wz = _grid(-p.max_yaw_rate, p.max_yaw_rate, p.max_yaw_accel * p.tick / window)
        self.shape = (len(self.vx), len(self.vy), len(self.wz))
        self.max_window = min(2 * window + 1, len(self.vx)) * min(2 * window + 1, len(self.vy)) \
            * min(2 * window + 1, len(self.wz))
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
        self.windows: dict[tuple[int, int, int], _Window] = {}

    def window(self, idx: tuple[int, int, int]) -> "_Window":
        """The candidates of the dynamic window around grid command ``idx`` (cached)."""
        win = self.windows.get(idx)
        if win is None:
            w = self.w
            axes = [np.array(sorted({min(max(i + d, 0), n - 1) for d in range(-w, w + 1)}))
                    for i, n in zip(idx, self.shape)]
            I, J, K = (a.ravel() for a in np.meshgrid(*axes, indexing="ij"))
            win = self.windows[idx] = _Window(self, I, J, K)
        return win


class _Window:
    """Everything a tick needs about the candidates of one dynamic window, precomputed so
    that a tick costs a few dozen numpy calls on small arrays."""

    __slots__ = ("n", "rot3", "half", "score_rows", "static", "stop_yaw", "reach", "cand",
                 "speed", "still", "commands")

    def __init__(self, table: _Table, I, J, K):
        g = (I * table.shape[1] + J) * table.shape[2] + K
        steps = table.steps
        x, y, th = table.x[g], table.y[g], table.th[g]                   # (n, steps)
        c, s = np.cos(th), np.sin(th)
        self.n = n = len(g)
        # a lidar point p (robot frame now) in each rollout pose's frame: rot @ p + off
        rot = np.empty((n, steps, 2, 2), dtype=np.float32)
        rot[:, :, 0, 0], rot[:, :, 0, 1], rot[:, :, 1, 0], rot[:, :, 1, 1] = c, s, -s, c
        off = np.empty((n, steps, 2), dtype=np.float32)
        off[:, :, 0], off[:, :, 1] = -(c * x + s * y), s * x - c * y
        rot3 = np.empty((n * steps * 2, 3), dtype=np.float32)   # [rot | off] for [px, py, 1]
        rot3[:, :2], rot3[:, 2] = rot.reshape(-1, 2), off.reshape(-1)
        self.rot3 = rot3
        self.half = np.tile(np.asarray(table.half, dtype=np.float32), n * steps)[:, None]
        # rows that give, times [tx, ty, 1, |target|^2]: |target - rollout pose_k|^2 (n*steps
        # rows), then the target in the end pose's frame: forward (n rows), left (n rows)
        ex, ey, ec, es = x[:, -1], y[:, -1], c[:, -1], s[:, -1]
        zero = np.zeros_like(ex)
        rows = [np.stack([-2 * x, -2 * y, x * x + y * y, np.ones_like(x)], axis=-1).reshape(-1, 4),
                np.stack([ec, es, -(ec * ex + es * ey), zero], axis=-1),
                np.stack([-es, ec, es * ex - ec * ey, zero], axis=-1)]
        self.score_rows = np.ascontiguousarray(np.concatenate(rows))
        _, _, _, wv, wt = table.weights
        self.static = table.vel[g] * wv - table.turn[g] * wt
        self.stop_yaw = table.stop_yaw[g]
        self.reach = float(table.reach[g].max())
        self.cand = [(int(i), int(j), int(k)) for i, j, k in zip(I, J, K)]
        self.commands = [Command(float(table.vx[i]), float(table.vy[j]), float(table.wz[k]))
                         for i, j, k in self.cand]
        self.speed = np.abs(table.vx[I]) + np.abs(table.vy[J])
        self.still = (self.speed == 0.0) & (table.wz[K] == 0.0)


_TABLES: "OrderedDict[tuple, _Table]" = OrderedDict()
_BEAM_GEOMETRY: "OrderedDict[bytes, tuple]" = OrderedDict()


def _beam_geometry(angles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(float32 unit vectors (2, beams), detour directions (beams, 2) and their normals, float
    angles) of a lidar's beams, computed once per beam layout and shared read-only, so that the
    episodes of a batch with the same lidar share one array (dwa_batch groups them by it)."""
    key = angles.dtype.str.encode() + angles.tobytes()
    out = _BEAM_GEOMETRY.get(key)
    if out is None:
        unit = np.stack([np.cos(angles), np.sin(angles)]).astype(np.float32)
        beam_angles = np.array(angles, dtype=float)
        c, s = np.cos(beam_angles), np.sin(beam_angles)
        out = (unit, np.stack([c, s], axis=1).astype(np.float32), np.stack([-s, c], axis=1).astype(np.float32),
               beam_angles)
        for a in out:
            a.flags.writeable = False
        _BEAM_GEOMETRY[key] = out
        while len(_BEAM_GEOMETRY) > TABLE_CACHE_SIZE:
            _BEAM_GEOMETRY.popitem(last=False)
    return out


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
        stall_time: seconds without getting ``stall_progress`` metres closer to the target
            after which the planner is stuck in a local minimum (a dead end, the outer wall of
            a bend, circling): for the rest of that leg it follows a route to the target planned
            on the grid of every lidar return seen so far (1.5; 0 = off).
        stall_progress: metres (0.25).
        route_lookahead: metres along that route to the point aimed at (1.5).
        replan_period: seconds between two route plans while routing (2.0).
        route_margin: metres the route keeps beyond the detour lane's half width (0.05).
    """

    name = "dwa"
    version = "1.1"     # 1.1: stall recovery (route on the lidar grid), backing off, sideways arrival

    def __init__(self, *, horizon: float = 1.5, steps: int = 5, window: int = 1,
                 reverse_speed: float = 0.2, clearance_buffer: float = 0.05,
                 clearance_cap: float = 0.8, progress_weight: float = 1.0,
                 heading_weight: float = 0.4, clearance_weight: float = 0.4,
                 velocity_weight: float = 0.1, turn_weight: float = 0.05,
                 lookahead: float = 3.0, stall_time: float = 1.5,
                 stall_progress: float = 0.25, route_lookahead: float = 1.5,
                 replan_period: float = 2.0, route_margin: float = 0.05):
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
        self._weights = self.weights + (self.turn_weight,)
        self.lookahead = float(lookahead)
        self.stall_time = float(stall_time)
        self.stall_progress = float(stall_progress)
        self.route_lookahead = float(route_lookahead)
        self.replan_period = float(replan_period)
        self.near = 1.0
        self.route_margin = float(route_margin)
        self._p: RobotParams | None = None
        self._idx: tuple[int, int, int] | None = None
        self._goal_phase = False
        self._kwargs = dict(horizon=horizon, steps=steps, window=window, reverse_speed=reverse_speed,
                            clearance_buffer=clearance_buffer, clearance_cap=clearance_cap,
                            progress_weight=progress_weight, heading_weight=heading_weight,
                            clearance_weight=clearance_weight, velocity_weight=velocity_weight,
                            turn_weight=turn_weight, lookahead=lookahead, stall_time=stall_time,
                            stall_progress=stall_progress, route_lookahead=route_lookahead,
                            replan_period=replan_period, route_margin=route_margin)
        self._episodes: list[DynamicWindowPlanner] = []     # the batch protocol's episodes

    # -- episode set-up -------------------------------------------------------------------
    def reset(self, scenario: Scenario) -> None:
        self._p = p = RobotParams.from_scenario(scenario)
        self._t = _table(p, self.horizon, self.steps, self.window, self.reverse_speed,
                         self.clearance_cap, self._weights)
        self._idx = None          # current command as grid indices, set from the first observation
        self._goal_phase = False
        self._beams_shape = None
        self._side = 0.0          # side (+1 left, -1 right) of the last detour around a blockage
        m = scenario.mission
        sites = [(m.start.x, m.start.y), (m.goal.x, m.goal.y)] + [(w.x, w.y) for w in m.waypoints]
        self._grid = LidarGrid(np.array(sites, dtype=float), border=min(p.range_max, 10.0))
        self._leg = -1            # remaining waypoints when the current leg started
        self._best, self._best_t = math.inf, 0.0     # closest to the leg's target so far, when
        self._routing, self._plan_t = False, -math.inf

    def _beams(self, angles: np.ndarray) -> None:
        """Per-episode lidar geometry: float32 unit vectors of the beams, and the inflation
        that covers the surface between two neighbouring beams (half the beam spacing at the
        rollouts' reach)."""
        t = self._t
        self._beams_shape = angles.shape
        self._unit, self._dirs, self._dirs_normal, self._beam_angles = _beam_geometry(angles)
        self._points = np.ones((3, len(angles)), dtype=np.float32)   # [px, py, 1] per beam
        self._terms = np.empty((3, self._t.max_window))                # progress, heading, room
        self._term_weights = np.array((0.0, -self.weights[1] / math.pi, self.weights[2] / self._t.cap))
        self._target_vec = np.array((0.0, 0.0, 1.0, 0.0))
        spacing = float(np.max(np.diff(angles))) if len(angles) > 1 else 0.0
        reach = float(t.reach.max()) - t.cap
        self._inflation = 0.5 * spacing * reach
        self._min_clear = self._p.safety_margin + self.clearance_buffer + self._inflation
        # detour lanes: every beam direction is a candidate direction (_beam_geometry)
        self._lane = self._t.half[1] + self._t.radius + self._min_clear
        # the route keeps as far from the walls as a detour lane: where the rollouts can pass
        self._grid.set_inflation(self._lane + self.route_margin)
        self._lane_map = np.zeros((2, 3), dtype=np.float32)

    # -- the batch protocol (subjects/protocol.py): many episodes, one call per tick ----------
    def reset_batch(self, scenarios) -> None:
        """One planner per episode (this one's parameters), each reset with its scenario."""
        self._episodes = []
        for scenario in scenarios:
            planner = DynamicWindowPlanner(**self._kwargs)
            planner.reset(scenario)
            self._episodes.append(planner)

    def act_batch(self, ids, observations) -> list[Command]:
        """The commands ``act`` gives each episode, bit for bit, computed together (dwa_batch.py)."""
        from .dwa_batch import act_batch
        episodes = self._episodes
        return act_batch([episodes[i] for i in ids], observations)

    # -- one tick -------------------------------------------------------------------------
    def act(self, obs: Observation) -> Command:
        """One tick: the dynamic window, each candidate's clearance, the point to aim at, the
        candidates' scores, the choice."""
        require_reset(self._p, "DynamicWindowPlanner")
        win = self._dynamic_window(obs)
        terms = self._terms[:, :win.n]                  # rows: distance to target, heading error,
        clear = terms[2]                                # clearance (one weighted sum in _score)
        points = self._clearance(win, obs.ranges, clear)
        routed, tx, ty = self._aim(obs, points)
        score = self._score(obs, win, terms, tx, ty)
        best = self._choose(win, score, clear, routed)
        self._idx = win.cand[best]
        return win.commands[best]

    def _dynamic_window(self, obs: Observation) -> _Window:
        """The candidates the robot can reach within one tick from its current command (on the
        first tick: the grid command closest to the measured velocity)."""
        t = self._t
        if self._beams_shape != obs.angles.shape:
            self._beams(obs.angles)
        if self._idx is None:
            v = obs.velocity
            self._idx = tuple(int(np.argmin(np.abs(grid - float(value))))
                              for grid, value in zip((t.vx, t.vy, t.wz), v))
        return t.window(self._idx)

    def _clearance(self, win: _Window, r: np.ndarray, clear: np.ndarray) -> np.ndarray | None:
        """Fill ``clear`` with each candidate's clearance: its footprint at every rollout pose
        against the lidar points within reach (capped at ``clearance_cap``). Returns those
        points as [px, py, 1] columns in the robot frame, or None when none is within reach."""
        p, t = self._p, self._t
        n, steps = win.n, self.steps
        near = (r < min(win.reach, p.range_max * 0.999)).nonzero()[0]
        if not near.size:
            clear.fill(t.cap)
            return None
        np.multiply(self._unit, r, out=self._points[:2])
        P = self._points[:, near]                       # (3, m) [px, py, 1], robot frame
        E = win.rot3 @ P                                # (n * steps * 2, m): local x, y
        np.abs(E, out=E)
        E -= win.half
        np.maximum(E, 0.0, out=E)
        np.square(E, out=E)
        E = E.reshape(n * steps, 2, -1)
        d2 = (E[:, 0] + E[:, 1]).reshape(n, -1)         # squared footprint-point distances
        np.minimum.reduce(d2, axis=1, out=clear)
        np.sqrt(clear, out=clear)
        clear -= t.radius + self._inflation
        np.minimum(clear, t.cap, out=clear)
        return P

    def _aim(self, obs: Observation, points: np.ndarray | None) -> tuple[bool, float, float]:
        """(routed, tx, ty): the point to aim at in the robot frame: the next waypoint or the
        goal, a point along the grid route when stalled, or a detour around a blocked lane."""
        routed, tx, ty = self._aim_route(obs)
        if not routed and points is not None and self.lookahead > 0:
            tx, ty = self._subgoal(tx, ty, points)
        return routed, tx, ty

    def _aim_route(self, obs: Observation) -> tuple[bool, float, float]:
        """(routed, tx, ty): the next waypoint or the goal in the robot frame, or, stalled, the
        point along the grid route (before any detour around a blocked lane)."""
        target = obs.waypoints[0] if len(obs.waypoints) else obs.goal
        pose = obs.pose
        dx, dy = float(target[0]) - float(pose[0]), float(target[1]) - float(pose[1])
        c, s = math.cos(float(pose[2])), math.sin(float(pose[2]))
        tx, ty = c * dx + s * dy, -s * dx + c * dy       # target in the robot frame
        if self.stall_time > 0:
            return self._route(obs, obs.ranges, c, s, dx, dy, tx, ty)
        return False, tx, ty

    def _score(self, obs: Observation, win: _Window, terms: np.ndarray, tx: float,
               ty: float) -> np.ndarray:
        """Each candidate's score: progress towards (tx, ty), heading, clearance, speed and
        turning, weighted; -inf for the candidates that come too close (not admissible)."""
        p = self._p
        d0sq = tx * tx + ty * ty
        d0 = math.sqrt(d0sq)
        v = self._target_vec
        v[0], v[1], v[3] = tx, ty, d0sq
        q = win.score_rows @ v
        k_dist = self._distance_and_heading(obs, win, q, d0, terms[0], terms[1])
        # heading linear in the angle, as in Fox et al.
        w = self._term_weights
        w[0] = k_dist
        if p.omni and d0 < self.near:
            # close to the target an omnidirectional robot need not face it: it may slide in
            # sideways, where a long body would not fit nose first (a waypoint in a corner)
            w[1] = -self.weights[1] / math.pi * (d0 / self.near)
        else:
            w[1] = -self.weights[1] / math.pi
        score = w @ terms
        score += win.static
        score[terms[2] < self._min_clear] = -np.inf     # not admissible: too close
        return score

    def _distance_and_heading(self, obs: Observation, win: _Window, q: np.ndarray, d0: float,
                              dist: np.ndarray, heading_err: np.ndarray) -> float:
        """Fill ``dist`` (to the target) and ``heading_err`` per candidate from ``q`` (see
        ``_Window.score_rows``); return the distance term's weight. In the goal phase: the end
        pose's distance and the braking yaw's error to the goal yaw; otherwise the closest
        approach along the rollout and the end pose's bearing to the target."""
        p = self._p
        n, steps = win.n, self.steps
        nk = n * steps
        wp = self._weights[0]
        if self._in_goal_phase(obs, d0):
            want = float(wrap_angle(p.goal_yaw - float(obs.pose[2])))
            np.abs(wrap_angle(want - win.stop_yaw), out=heading_err)
            np.hypot(q[nk:nk + n], q[nk + n:], out=dist)    # distance from the end pose
            return -wp / max(p.goal_tolerance, 1e-6)
        # closest approach along the rollout: driving past a near target is fine
        np.minimum.reduce(q[:nk].reshape(n, steps), axis=1, out=dist)
        np.sqrt(np.maximum(dist, 0.0, out=dist), out=dist)
        np.arctan2(q[nk + n:], q[nk:nk + n], out=heading_err)   # at the end pose
        np.abs(heading_err, out=heading_err)
        # a rollout that reaches the target is not penalised for ending past it
        reach_tol = 0.5 * (p.waypoint_tolerance if len(obs.waypoints) else p.goal_tolerance)
        heading_err[dist < reach_tol] = 0.0
        return -wp / (p.max_speed * self.horizon)

    def _choose(self, win: _Window, score: np.ndarray, clear: np.ndarray, routed: bool) -> int:
        """The best admissible candidate; while stalled, the best one that moves; when none is
        admissible, the hardest brake, then (standing) the one with the most room."""
        best = int(score.argmax())
        if routed and win.still[best] and score[best] > -np.inf:
            # stuck: standing still is the local minimum itself, so take the best move
            moving = np.where(win.still, -np.inf, score)
            if moving.max() > -np.inf:
                best = int(moving.argmax())
        if score[best] == -np.inf:
            # nothing is safe: brake as hard as the window allows (lowest speed, then most
            # room); once standing, take the command with the most room instead (back off,
            # away from what is too close, rather than freeze there)
            best = int(np.lexsort((-clear, win.speed))[0])
            if win.still[best] and win.still[win.cand.index(self._idx)]:
                best = int(np.lexsort((win.speed, -clear))[0])
        return best

    def _route(self, obs: Observation, r: np.ndarray, c: float, s: float, dx: float, dy: float,
               tx: float, ty: float) -> tuple[bool, float, float]:
        """Remember the lidar returns; detect a stall; once stalled, aim along the grid route.

        Returns (routed, tx, ty): the point to aim at in the robot frame."""
        p, grid = self._p, self._grid
        x, y = float(obs.pose[0]), float(obs.pose[1])
        # the robot moves <= 1 m in ten ticks and the lidar sees metres: a scan a second is
        # enough to remember the walls, every other tick once they matter (routing)
        if obs.tick % (2 if self._routing else 10) == 0:
            hit = (r < p.range_max * 0.999).nonzero()[0]
            grid.mark(x, y, c, s, self._unit[:, hit] * r[hit])
        leg = len(obs.waypoints)
        if leg != self._leg:
            self._leg, self._best, self._best_t = leg, math.inf, obs.time
            self._routing, self._plan_t = False, -math.inf
        d = math.hypot(dx, dy)
        if d < self._best - self.stall_progress:
            self._best, self._best_t = d, obs.time
        if not self._routing:
            if obs.time - self._best_t < self.stall_time:
                return False, tx, ty
            self._routing = True
        if d < self.route_lookahead:
            return True, tx, ty
        tol = p.waypoint_tolerance if leg else p.goal_tolerance
        if obs.time - self._plan_t >= self.replan_period - 1e-9:
            self._plan_t = obs.time
            if not grid.plan((x, y), (x + dx, y + dy), 0.6 * tol):
                # no way out near the target (a dead end): plan over everything seen
                grid.plan((x, y), (x + dx, y + dy), 0.6 * tol, border=math.inf)
        point = grid.carrot((x, y), self.route_lookahead)
        if point is None:
            return False, tx, ty
        ex, ey = point[0] - x, point[1] - y
        return True, c * ex + s * ey, -s * ex + c * ey

    def _subgoal(self, tx: float, ty: float, points: np.ndarray) -> tuple[float, float]:
        """The target, or a detour point when lidar points block the straight lane to it.

        Lidar-only DWA falls into the local minimum in front of an obstacle that sits on the
        straight line (every rollout that makes progress is inadmissible). Like the vector
        field histogram, look for the free lane (robot half width + clearance wide, as long as
        the distance to the target, at most ``lookahead``) whose direction is closest to the
        target's, keeping to the side chosen before, and aim along it instead. ``points`` are
        the nearby lidar points as [px, py, 1] columns in the robot frame.
        """
        length = self._set_lane(tx, ty)
        lane = self._lane_map @ points                       # points: [px, py, 1] rows
        np.abs(lane, out=lane)
        if np.minimum.reduce(np.maximum(lane[0], lane[1])) >= 1.0:
            self._side = 0.0
            return tx, ty
        return self._detour(tx, ty, points, length)

    def _set_lane(self, tx: float, ty: float) -> float:
        """Write the map of the straight lane to (tx, ty) into ``_lane_map`` (times [px, py, 1]:
        the lane is the square |u| < 1, |v| < 1 in scaled lane coordinates); return its length."""
        d0 = math.hypot(tx, ty)
        length = min(d0, self.lookahead)
        cb, sb = tx / max(d0, 1e-9), ty / max(d0, 1e-9)
        half_len = max(length / 2.0, 1e-6)
        m = self._lane_map
        m[0, 0], m[0, 1], m[0, 2] = cb / half_len, sb / half_len, -1.0
        m[1, 0], m[1, 1] = -sb / self._lane, cb / self._lane
        return length

    def _detour(self, tx: float, ty: float, points: np.ndarray, length: float) -> tuple[float, float]:
        """The straight lane is blocked: aim along the free lane closest to the target's direction
        (keeping to the side chosen before), or at the target when every lane is blocked."""
        along = self._dirs @ points[:2]                      # (directions, m)
        lateral = np.abs(self._dirs_normal @ points[:2])
        blocked = ((lateral < self._lane) & (np.abs(along - length / 2) < length / 2)).any(axis=1)
        if blocked.all():
            return tx, ty
        offset = wrap_angle(self._beam_angles - math.atan2(ty, tx))
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
