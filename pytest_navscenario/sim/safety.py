"""The collision safety layer, as on the real robot.

Each control tick it takes the robot's *measured* velocity (a constant twist), predicts the footprint
swept over ``safety.horizon`` seconds, grows it by ``safety.margin`` and halts the robot if the sweep
touches an obstacle. A robot standing still never triggers it, and neither does one that is already
within the margin of an obstacle but moving parallel to it or away from it (only approaching counts).

How, and what it costs: bounding circles make the common case (nothing within reach of the farthest
any footprint point can travel over the horizon) about a microsecond of plain Python. Otherwise the
footprint is sampled along the constant-twist arc every ``SAMPLE_SPACING`` of point motion and its
exact distance to each nearby obstacle is computed in one vectorised numpy pass (box-box: vertex to
rectangle both ways plus a separating-axis overlap test; circles analytically).
Sampling can make the layer halt up to half a sample spacing early (1 cm; more only when a point
travels over ``MAX_SAMPLES * SAMPLE_SPACING`` = 1.28 m within the horizon), never late. Same shapes as
geometry.py (boxes and true circles), without building shapely polygons in the loop.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..scenario.ground.surface import ground_height
from ..scenario.geometry import bounding_radius, convex_parts, footprint_part_distance, footprint_radius
from ..scenario.model import BoxObstacle, MeshObstacle, PolygonObstacle, Scenario
from ..scenario.motion import moving_indices

SAMPLE_SPACING = 0.02   # m: the most any footprint point moves between two sweep samples
MAX_SAMPLES = 64


def twist_poses(x: float, y: float, yaw: float, vx: float, vy: float, wz: float,
                times: np.ndarray) -> np.ndarray:
    """Poses (n, 3) reached from (x, y, yaw) after ``times`` holding the robot-frame twist (vx, vy, wz).

    Exact arcs: the displacement over T is T * sinc(wz T / 2) * R(yaw + wz T / 2) (vx, vy).
    """
    times = np.asarray(times, dtype=float)
    half = wz * times / 2.0
    scale = times * np.sinc(half / math.pi)   # np.sinc(u) = sin(pi u) / (pi u)
    mid = yaw + half
    c, s = np.cos(mid), np.sin(mid)
    out = np.empty((len(times), 3))
    out[:, 0] = x + scale * (c * vx - s * vy)
    out[:, 1] = y + scale * (s * vx + c * vy)
    out[:, 2] = yaw + wz * times
    return out


def _rect_distance(px: np.ndarray, py: np.ndarray, hx: Any, hy: Any) -> np.ndarray:
    """Distance from points (px, py), given in a rectangle's own frame, to the rectangle of half
    sizes (hx, hy); 0 inside."""
    qx = np.maximum(np.abs(px) - hx, 0.0)
    qy = np.maximum(np.abs(py) - hy, 0.0)
    return np.hypot(qx, qy)


class SafetyLayer:
    """Per-model safety geometry; ``check`` is called once per tick with the measured state."""

    def __init__(self, scenario: Scenario, walls: tuple = ()):
        """``walls``: terrain faces the body cannot cross, each with the unit vector to its low
        side, the height halfway up it and its top's (``scenario.ground.traversable.walls_from_below``):
        obstacles for a robot on that side, standing below halfway up, whose lidar's scan plane
        (``lidar.mount_height`` above the ground it stands on) is below the face's top: a real
        layer works on the sensor's view, and a riser under the scan plane is not in it (as glass
        is not)."""
        safety = scenario.robot.safety
        self.horizon = float(safety.horizon)
        self.margin = float(safety.margin)
        fp = scenario.robot.footprint
        self.circle_robot = fp.shape == "circle"
        self.robot_r = float(fp.radius) if self.circle_robot else 0.0
        self.hl, self.hw = fp.length / 2.0, fp.width / 2.0
        self.robot_corners = np.array([(self.hl, self.hw), (-self.hl, self.hw),
                                       (-self.hl, -self.hw), (self.hl, -self.hw)])
        self.robot_radius = footprint_radius(fp)
        obstacles = tuple(scenario.obstacles) + tuple(face for face, _ in walls)
        n_own = len(scenario.obstacles)
        self.low_side = {n_own + k: (face.x, face.y, ux, uy, mid, top)
                         for k, (face, (ux, uy, mid, top)) in enumerate(walls)}
        self.scenario, self.plane = scenario, float(scenario.robot.lidar.mount_height)
        self.names = [o.name for o in obstacles]
        n = len(obstacles)
        self.is_box = np.array([isinstance(o, BoxObstacle) for o in obstacles], dtype=bool)
        self.centres = np.array([(o.x, o.y) for o in obstacles], dtype=float).reshape(n, 2)
        yaw = np.array([math.radians(o.yaw) if isinstance(o, BoxObstacle) else 0.0 for o in obstacles])
        self.cos, self.sin = np.cos(yaw), np.sin(yaw)
        self.half = np.array([(o.length / 2.0, o.width / 2.0) if isinstance(o, BoxObstacle)
                              else (0.0, 0.0) for o in obstacles], dtype=float).reshape(n, 2)
        # polygons and meshes: their convex parts (world frame), a bounding circle for the bounds
        self.parts = {j: convex_parts(o) for j, o in enumerate(obstacles)
                      if isinstance(o, (PolygonObstacle, MeshObstacle))}
        self.obs_r = np.array([0.0 if isinstance(o, BoxObstacle) else
                               bounding_radius(o) if j in self.parts else o.radius
                               for j, o in enumerate(obstacles)])
        # world corners of box obstacles (n, 4, 2); cylinders: their centre repeated
        local = np.stack([self.half * sign for sign in ((1, 1), (-1, 1), (-1, -1), (1, -1))], axis=1)
        self.corners = np.empty((n, 4, 2))
        self.corners[..., 0] = self.centres[:, None, 0] + self.cos[:, None] * local[..., 0] \
            - self.sin[:, None] * local[..., 1]
        self.corners[..., 1] = self.centres[:, None, 1] + self.sin[:, None] * local[..., 0] \
            + self.cos[:, None] * local[..., 1]
        self.bound = np.hypot(self.half[:, 0], self.half[:, 1]) + self.obs_r
        self._shape = list(zip(self.centres[:, 0].tolist(), self.centres[:, 1].tolist(),
                               self.cos.tolist(), self.sin.tolist(), self.half[:, 0].tolist(),
                               self.half[:, 1].tolist(), self.obs_r.tolist()))
        # moving obstacles are checked apart, where they are now and with their velocity
        # an obstacle the lidar cannot see (glass) is not seen by this layer either (a real one
        # works on the same sensor); moving ones are checked apart, with their velocity
        unseen = [j for j, o in enumerate(obstacles) if not getattr(o, "visible_to_lidar", True)]
        self.moving = [j for j in moving_indices(obstacles) if j not in unseen]
        self.moving_slots = [k for k, j in enumerate(moving_indices(obstacles)) if j not in unseen]
        self.static = np.ones(n, dtype=bool)
        self.static[moving_indices(obstacles)] = False
        self.static[unseen] = False
        static = [j for j in range(n) if self.static[j]]
        self._movers = [(j, float(self.centres[j, 0]), float(self.centres[j, 1]), float(self.bound[j]))
                        for j in self.moving]
        self._circles = ([(j, float(self.centres[j, 0]), float(self.centres[j, 1]), float(self.bound[j]))
                          for j in static] if len(static) <= 32 else None)

    def distances(self, poses: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """Exact footprint-obstacle distances (0 on overlap) for poses (k, 3) and obstacles ``idx``:
        an array (k, len(idx))."""
        X, Y = poses[:, 0:1], poses[:, 1:2]
        C, S = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
        cx, cy = self.centres[idx, 0], self.centres[idx, 1]
        oc, os_ = self.cos[idx], self.sin[idx]
        hx, hy = self.half[idx, 0], self.half[idx, 1]
        if self.circle_robot:
            # robot centre into each obstacle frame; boxes: point-rectangle, cylinders: half = 0
            dx, dy = X - cx, Y - cy
            d = _rect_distance(dx * oc + dy * os_, -dx * os_ + dy * oc, hx, hy)
            return np.maximum(d - self.obs_r[idx] - self.robot_r, 0.0)
        # obstacle corners (cylinders: centre) into each sample's robot frame
        ox = self.corners[idx, :, 0][None] - X[:, :, None]     # (k, m, 4)
        oy = self.corners[idx, :, 1][None] - Y[:, :, None]
        Cn, Sn = C[:, :, None], S[:, :, None]
        rx, ry = ox * Cn + oy * Sn, -ox * Sn + oy * Cn
        d = _rect_distance(rx, ry, self.hl, self.hw).min(axis=2)
        d = np.maximum(d - self.obs_r[idx], 0.0)
        box = self.is_box[idx]
        if box.any():
            # robot corners into each box obstacle's frame
            wx = X + C * self.robot_corners[:, 0] - S * self.robot_corners[:, 1]   # (k, 4)
            wy = Y + S * self.robot_corners[:, 0] + C * self.robot_corners[:, 1]
            bi = idx[box]
            dx = wx[:, None, :] - self.centres[bi, 0][None, :, None]              # (k, b, 4)
            dy = wy[:, None, :] - self.centres[bi, 1][None, :, None]
            bc, bs = self.cos[bi][None, :, None], self.sin[bi][None, :, None]
            bx, by = dx * bc + dy * bs, -dx * bs + dy * bc
            hx, hy = self.half[bi, 0][None, :, None], self.half[bi, 1][None, :, None]
            d2 = _rect_distance(bx, by, hx, hy)
            db = np.minimum(d[:, box], d2.min(axis=2))
            # crossing rectangles (no corner inside the other): separating-axis test, 0 on overlap
            rxb, ryb = rx[:, box], ry[:, box]
            overlap = ((rxb.min(axis=2) <= self.hl) & (rxb.max(axis=2) >= -self.hl)
                       & (ryb.min(axis=2) <= self.hw) & (ryb.max(axis=2) >= -self.hw)
                       & (bx.min(axis=2) <= hx[..., 0]) & (bx.max(axis=2) >= -hx[..., 0])
                       & (by.min(axis=2) <= hy[..., 0]) & (by.max(axis=2) >= -hy[..., 0]))
            db[overlap] = 0.0
            d[:, box] = db
        return d

    def check(self, x: float, y: float, yaw: float, vx: float, vy: float, wz: float,
              moving: list[list[float]] | None = None, z: float | None = None) -> str | None:
        """The name of the obstacle the predicted sweep would hit, or None (robot may go on).

        ``moving``: per moving obstacle (in scenario order) [dx, dy, vx, vy], its offset from its
        scenario position and its velocity now (MovingObstacles.now); each is predicted to hold its
        velocity over the horizon, like the robot its twist, and the sweep is checked relative to
        it. ``z``: the height the robot stands at (its base's), for the terrain's faces (else the
        ground's under its centre)."""
        speed = math.hypot(vx, vy)
        # No point of the footprint moves farther than this over the horizon.
        travel = (speed + abs(wz) * self.robot_radius) * self.horizon
        n = int(min(MAX_SAMPLES, max(1, math.ceil(travel / SAMPLE_SPACING))))
        threshold = self.margin + travel / n / 2.0       # half a sample spacing: sampling never misses
        reach = self.robot_radius + threshold + travel
        if self._circles is not None:       # few obstacles: plain Python beats numpy's overhead
            hypot = math.hypot
            near = [j for j, cx, cy, r in self._circles if hypot(cx - x, cy - y) - r < reach]
        else:
            gap = np.hypot(self.centres[:, 0] - x, self.centres[:, 1] - y) - self.bound
            near = np.flatnonzero((gap < reach) & self.static).tolist()
        if self.low_side and near:
            near = self._walls_for(near, x, y, z)
        movers = self._near_movers(x, y, reach, moving) if moving is not None else []
        if not near and not movers:
            return None
        # Tier 2, a cheap lower bound: the obstacle lies in the half-plane behind its point q
        # nearest to the robot's centre, so the robot is at least (|p - q| - the robot's extent
        # towards it) away now; over the horizon that shrinks at most by the approach along u,
        # the velocity's turning (speed |wz| t^2 / 2) and the extent's growth (R |wz| t).
        # Rules out e.g. corridor walls beside the robot.
        c, s = math.cos(yaw), math.sin(yaw)
        hl, hw, rr = self.hl, self.hw, self.robot_r
        h = self.horizon
        wvx, wvy = c * vx - s * vy, s * vx + c * vy
        turning = abs(wz) * h * (speed * h / 2.0 + self.robot_radius)
        limit = self.margin
        close = []
        parts = self.parts
        for j in near:
            if j in parts:          # no cheap bound for a polygon: its exact distance decides
                close.append(j)
                continue
            cx, cy, oc, os_, hx, hy, r = self._shape[j]
            dx, dy = x - cx, y - cy
            px, py = dx * oc + dy * os_, -dx * os_ + dy * oc        # robot centre, obstacle frame
            qx = px - (hx if px > hx else (-hx if px < -hx else px))
            qy = py - (hy if py > hy else (-hy if py < -hy else py))
            gap = math.hypot(qx, qy)
            if gap > r:
                ux, uy = (qx * oc - qy * os_) / gap, (qx * os_ + qy * oc) / gap   # world direction
                extent = rr if self.circle_robot else hl * abs(ux * c + uy * s) + hw * abs(uy * c - ux * s)
                if gap - r - extent + min(0.0, h * (wvx * ux + wvy * uy)) - turning > limit:
                    continue
            close.append(j)
        if not close and not movers:
            return None
        times = np.linspace(0.0, self.horizon, n + 1)
        poses = twist_poses(x, y, yaw, vx, vy, wz, times)
        idx = np.asarray(close + [j for j, _, _ in movers], dtype=int)
        dist = np.empty((n + 1, len(idx)))
        if close:
            dist[:, :len(close)] = self._columns(poses, close)   # (n + 1, m)
        for col, (j, offset, vel) in enumerate(movers, start=len(close)):
            rel = poses.copy()      # the robot relative to the obstacle's scenario position
            rel[:, 0] -= offset[0] + vel[0] * times
            rel[:, 1] -= offset[1] + vel[1] * times
            dist[:, col] = self._columns(rel, [j])[:, 0]
        now, future = dist[0], dist[1:]
        # hit: a future sample within the threshold, or (already within it) any approach at all
        hit = np.where(now > threshold, future <= threshold, future < now - 1e-9)
        if not hit.any():
            return None
        first = np.where(hit.any(axis=0), hit.argmax(axis=0), n + 1)  # earliest sample per obstacle
        order = np.lexsort((future.min(axis=0), first))
        return self.names[int(idx[order[0]])]

    def _walls_for(self, near: list[int], x: float, y: float, z: float | None) -> list[int]:
        """``near`` without the terrain faces that are no wall for a robot at (x, y), standing at
        height ``z``: those it is not on the low side of, standing below halfway up the face (a
        dock's edge seen from on top, a pit's rim from the floor: a 2D layer cannot see a drop, the
        3D one's ground layer halts for it), and those whose top is under its scan plane."""
        low = self.low_side
        if not any(j in low for j in near):
            return near
        level = float(ground_height(self.scenario, x, y)) if z is None else z
        seen = level + self.plane
        return [j for j in near if j not in low
                or ((x - low[j][0]) * low[j][2] + (y - low[j][1]) * low[j][3] > 0.0
                    and level < low[j][4] and low[j][5] > seen)]

    def _columns(self, poses: np.ndarray, indices: list[int]) -> np.ndarray:
        """Distances (k, len(indices)) of the footprint at ``poses`` to the obstacles ``indices``:
        boxes and cylinders analytically (``distances``), polygons and meshes part by part."""
        parts = self.parts
        if not any(j in parts for j in indices):
            return self.distances(poses, np.asarray(indices))
        out = np.empty((len(poses), len(indices)))
        simple = [k for k, j in enumerate(indices) if j not in parts]
        if simple:
            out[:, simple] = self.distances(poses, np.asarray([indices[k] for k in simple]))
        for k, j in enumerate(indices):
            if j in parts:
                out[:, k] = np.min([self._convex_distance(poses, verts) for verts in parts[j]], axis=0)
        return out

    def _convex_distance(self, poses: np.ndarray, verts: np.ndarray) -> np.ndarray:
        """Exact distance (k,) of the footprint at ``poses`` to one convex part (V, 2), 0 on overlap."""
        if self.circle_robot:
            return footprint_part_distance(0.0, 0.0, self.robot_r, poses, verts)
        return footprint_part_distance(self.hl, self.hw, 0.0, poses, verts)

    def _near_movers(self, x: float, y: float, reach: float, moving: list[list[float]]
                     ) -> list[tuple[int, tuple[float, float], tuple[float, float]]]:
        """The moving obstacles that may come within reach over the horizon: (index, offset,
        velocity) each."""
        out = []
        hypot, h = math.hypot, self.horizon
        if len(self.moving_slots) != len(moving):
            moving = [moving[k] for k in self.moving_slots]
        for (j, cx, cy, bound), (ox, oy, ovx, ovy) in zip(self._movers, moving):
            if hypot(cx + ox - x, cy + oy - y) - bound < reach + hypot(ovx, ovy) * h:
                out.append((j, (ox, oy), (ovx, ovy)))
        return out
