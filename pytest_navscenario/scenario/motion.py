"""Where a moving obstacle is at a time: a pure, vectorised function of the scenario and the time.

The simulation writes these positions into MuJoCo's mocap bodies, and the verdict, the plots, the
HTML view and the bags compute them again from the same function, so all of them agree bit for bit
without recording obstacle poses. An obstacle keeps its orientation while it moves (a translation).
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .model import Obstacle


def is_moving(obs: Obstacle) -> bool:
    return getattr(obs, "motion", None) is not None


def moving_indices(obstacles: Sequence[Obstacle]) -> list[int]:
    """Indices of the obstacles that move, in scenario order."""
    return [i for i, o in enumerate(obstacles) if is_moving(o)]


class Track:
    """One moving obstacle's motion: ``positions(times)`` (n, 2) and ``velocity(t)``.

    A path is unrolled into one cycle of knots (time, point): once = the path, back-and-forth = the
    path and back, loop = the path and back to its first point; the time since ``start`` is taken
    modulo the cycle's duration for the periodic modes and clamped for once (np.interp holds the
    ends). Before ``start`` the obstacle stands at its first point.
    """

    def __init__(self, obs: Obstacle):
        m = obs.motion
        assert m is not None
        self.origin = (float(obs.x), float(obs.y))
        self.start = float(m.start)
        self.constant = m.velocity is not None
        if self.constant:
            self.vel = (float(m.velocity[0]), float(m.velocity[1]))
            return
        pts = np.asarray(m.path, dtype=float).reshape(-1, 2)
        if m.mode == "back-and-forth":
            pts = np.concatenate([pts, pts[-2::-1]])
        elif m.mode == "loop":
            pts = np.concatenate([pts, pts[:1]])
        seg = np.hypot(np.diff(pts[:, 0]), np.diff(pts[:, 1]))
        self.knots = np.concatenate([[0.0], np.cumsum(seg)]) / float(m.speed)
        self.points = pts
        self.periodic = m.mode != "once"
        self.period = float(self.knots[-1])
        self.seg_vel = np.diff(pts, axis=0) / np.maximum(np.diff(self.knots), 1e-300)[:, None]

    def _tau(self, times: np.ndarray) -> np.ndarray:
        tau = np.maximum(np.asarray(times, dtype=float) - self.start, 0.0)
        if self.periodic and self.period > 0.0:
            tau = np.mod(tau, self.period)
        return tau

    def positions(self, times: np.ndarray) -> np.ndarray:
        """(n, 2) world positions of the obstacle's centre at ``times`` (s)."""
        times = np.asarray(times, dtype=float).reshape(-1)
        out = np.empty((len(times), 2))
        if self.constant:
            dt = np.maximum(times - self.start, 0.0)
            out[:, 0] = self.origin[0] + self.vel[0] * dt
            out[:, 1] = self.origin[1] + self.vel[1] * dt
            return out
        tau = self._tau(times)
        out[:, 0] = np.interp(tau, self.knots, self.points[:, 0])
        out[:, 1] = np.interp(tau, self.knots, self.points[:, 1])
        return out

    def velocity(self, t: float) -> tuple[float, float]:
        """The obstacle's velocity (m/s, world frame) at time ``t``: 0 before the start and after
        the end of a once path."""
        if t < self.start:
            return 0.0, 0.0
        if self.constant:
            return self.vel
        tau = float(self._tau(np.array([t]))[0])
        if not self.periodic and tau >= self.period:
            return 0.0, 0.0
        k = int(np.searchsorted(self.knots, tau, side="right")) - 1
        k = min(max(k, 0), len(self.seg_vel) - 1)
        return float(self.seg_vel[k, 0]), float(self.seg_vel[k, 1])

    def end_time(self) -> float:
        """When the motion stops (inf for periodic and constant-velocity motion)."""
        if self.constant or self.periodic:
            return math.inf
        return self.start + self.period


def tracks(obstacles: Sequence[Obstacle]) -> dict[int, Track]:
    """A Track per moving obstacle, keyed by its index in ``obstacles``."""
    return {i: Track(obstacles[i]) for i in moving_indices(obstacles)}


def displacement(track: Track, times: np.ndarray) -> np.ndarray:
    """(n, 2) offsets of the obstacle from where the scenario places it (its x, y) at ``times``."""
    pos = track.positions(times)
    pos[:, 0] -= track.origin[0]
    pos[:, 1] -= track.origin[1]
    return pos
