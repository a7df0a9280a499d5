"""Planar geometry with shapely: footprint and obstacle outlines. Shared by the safety layer,
the metrics and the search's validity check. Angles in radians unless a name says degrees."""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import Point, Polygon

from .model import BoxObstacle, CylinderObstacle, Footprint, Obstacle, Scenario

CIRCLE_SEGMENTS = 16  # quad_segs for buffered circles: 64-gon, < 0.1 % radius error


def rectangle(cx: float, cy: float, length: float, width: float, yaw: float) -> Polygon:
    """A rectangle centred on (cx, cy), ``length`` along the direction ``yaw`` (rad)."""
    c, s = math.cos(yaw), math.sin(yaw)
    hl, hw = length / 2.0, width / 2.0
    corners = [(hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw)]
    return Polygon([(cx + c * px - s * py, cy + s * px + c * py) for px, py in corners])


def footprint_polygon(footprint: Footprint, x: float, y: float, yaw: float) -> Polygon:
    """The robot's outline at pose (x, y, yaw rad)."""
    if footprint.shape == "circle":
        return Point(x, y).buffer(footprint.radius, quad_segs=CIRCLE_SEGMENTS)
    return rectangle(x, y, footprint.length, footprint.width, yaw)


def footprint_polygons(footprint: Footprint, poses: np.ndarray) -> np.ndarray:
    """Vectorised ``footprint_polygon`` over an (n, 3) array of poses: an array of n polygons."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    if footprint.shape == "circle":
        return shapely.buffer(shapely.points(poses[:, :2]), footprint.radius, quad_segs=CIRCLE_SEGMENTS)
    hl, hw = footprint.length / 2.0, footprint.width / 2.0
    local = np.array([(hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw), (hl, hw)])
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    xs = poses[:, 0:1] + c * local[:, 0] - s * local[:, 1]
    ys = poses[:, 1:2] + s * local[:, 0] + c * local[:, 1]
    return shapely.polygons(np.stack([xs, ys], axis=-1))


def footprint_radius(footprint: Footprint) -> float:
    """Radius of the smallest circle around the footprint's centre that contains it."""
    if footprint.shape == "circle":
        return footprint.radius
    return math.hypot(footprint.length / 2.0, footprint.width / 2.0)


def obstacle_polygon(obs: Obstacle) -> Polygon:
    if isinstance(obs, BoxObstacle):
        return rectangle(obs.x, obs.y, obs.length, obs.width, math.radians(obs.yaw))
    if isinstance(obs, CylinderObstacle):
        return Point(obs.x, obs.y).buffer(obs.radius, quad_segs=CIRCLE_SEGMENTS)
    raise TypeError(f"unknown obstacle type {type(obs).__name__}")


def obstacle_polygons(scenario: Scenario) -> list[Polygon]:
    return [obstacle_polygon(o) for o in scenario.obstacles]
