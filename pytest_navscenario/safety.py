"""The collision safety layer, as on the real robot.

Each control tick it takes the robot's *measured* velocity (a constant twist), predicts the footprint
swept over ``safety.horizon`` seconds, grows it by ``safety.margin`` and halts the robot if the sweep
touches an obstacle. A robot standing still never triggers it, and neither does one that is already
within the margin of an obstacle but moving parallel to it or away from it (only approaching counts).

Cost: a numpy distance prefilter (bounding circles) makes the common case, nothing within reach,
a few microseconds; only then are sample footprints built and tested with shapely (STRtree over the
obstacles grown by the margin, built once per model and reused).
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.strtree import STRtree

from .geometry import footprint_polygon, footprint_polygons, footprint_radius, obstacle_polygon
from .scenario import BoxObstacle, Scenario

SAMPLE_STEP = 0.05               # m of travel between sample footprints along the sweep
SAMPLE_TURN = math.radians(10)   # rad of turn between sample footprints
MAX_SAMPLES = 24


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


class SafetyLayer:
    """Per-model safety geometry; ``check`` is called once per tick with the measured state."""

    def __init__(self, scenario: Scenario):
        safety = scenario.robot.safety
        self.horizon = float(safety.horizon)
        self.margin = float(safety.margin)
        self.footprint = scenario.robot.footprint
        self.names = [o.name for o in scenario.obstacles]
        self.polygons = [obstacle_polygon(o) for o in scenario.obstacles]
        self.centres = np.array([(o.x, o.y) for o in scenario.obstacles], dtype=float).reshape(-1, 2)
        self.radii = np.array([math.hypot(o.length / 2.0, o.width / 2.0) if isinstance(o, BoxObstacle)
                               else o.radius for o in scenario.obstacles], dtype=float)
        self.robot_radius = footprint_radius(self.footprint)
        self._tree: STRtree | None = None
        self._grown: list | None = None

    def _grown_tree(self) -> STRtree:
        if self._tree is None:
            self._grown = shapely.buffer(np.array(self.polygons, dtype=object), self.margin,
                                         quad_segs=8) if self.margin > 0 else np.array(self.polygons)
            self._tree = STRtree(self._grown)
        return self._tree

    def check(self, x: float, y: float, yaw: float, vx: float, vy: float, wz: float) -> str | None:
        """The name of the obstacle the predicted sweep would hit, or None (robot may go on)."""
        speed = math.hypot(vx, vy)
        if not len(self.radii):
            return None
        reach = self.robot_radius + self.margin + speed * self.horizon
        gap = np.hypot(self.centres[:, 0] - x, self.centres[:, 1] - y) - self.radii
        if not (gap < reach).any():          # the common case: nothing within reach
            return None

        n = int(min(MAX_SAMPLES, max(1, math.ceil(max(speed * self.horizon / SAMPLE_STEP,
                                                          abs(wz) * self.horizon / SAMPLE_TURN)))))
        poses = twist_poses(x, y, yaw, vx, vy, wz, np.linspace(0.0, self.horizon, n + 1))
        polys = footprint_polygons(self.footprint, poses)
        coords = shapely.get_coordinates(polys).reshape(n + 1, -1, 2)
        pairs = np.concatenate([coords[:-1], coords[1:]], axis=1)        # (n, 2P, 2)
        hulls = shapely.convex_hull(shapely.multipoints(pairs))
        tree = self._grown_tree()
        hull_idx, obs_idx = tree.query(hulls, predicate="intersects")
        if not len(hull_idx):
            return None
        now = footprint_polygon(self.footprint, x, y, yaw)
        # earliest hull first; within one hull, the obstacle the robot would be closest to
        for k in np.unique(hull_idx):
            candidates = obs_idx[hull_idx == k]
            best, best_dist = None, math.inf
            for j in candidates:
                poly = self.polygons[j]
                d_now = now.distance(poly)
                if d_now <= self.margin:
                    # already within the margin: stop only if the motion brings it closer
                    future = shapely.distance(polys[1:k + 2], poly).min()
                    if not future < d_now - 1e-9:
                        continue
                d_future = float(shapely.distance(polys[k:k + 2], poly).min())
                if d_future < best_dist:
                    best, best_dist = j, d_future
            if best is not None:
                return self.names[best]
        return None
