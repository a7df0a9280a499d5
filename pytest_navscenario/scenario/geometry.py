"""Planar geometry with shapely: footprint and obstacle outlines. Shared by the safety layer,
the metrics and the search's validity check. Angles in radians unless a name says degrees."""
from __future__ import annotations

import functools
import math

import numpy as np
import shapely
import shapely.geometry.polygon
from shapely.geometry import Point, Polygon

from .model import BoxObstacle, CylinderObstacle, Footprint, MeshObstacle, Obstacle, PolygonObstacle, Scenario

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
    """The obstacle's outline seen from above, where the scenario places it."""
    if isinstance(obs, BoxObstacle):
        return rectangle(obs.x, obs.y, obs.length, obs.width, math.radians(obs.yaw))
    if isinstance(obs, CylinderObstacle):
        return Point(obs.x, obs.y).buffer(obs.radius, quad_segs=CIRCLE_SEGMENTS)
    if isinstance(obs, (PolygonObstacle, MeshObstacle)):
        return Polygon(place(outline_points(obs), obs.x, obs.y, obs.yaw_rad))
    raise TypeError(f"unknown obstacle type {type(obs).__name__}")


def outline_points(obs: Obstacle) -> tuple[tuple[float, float], ...]:
    """A polygon's or mesh's outline in its own frame."""
    return obs.points if isinstance(obs, PolygonObstacle) else obs.footprint


def place(points, x: float, y: float, yaw: float) -> np.ndarray:
    """(n, 2) points of an obstacle's own frame, turned by ``yaw`` (rad) and moved to (x, y)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    c, s = math.cos(yaw), math.sin(yaw)
    return np.column_stack([x + c * pts[:, 0] - s * pts[:, 1], y + s * pts[:, 0] + c * pts[:, 1]])


def polygon_problem(points) -> str | None:
    """Why ``points`` are not a simple polygon with an area (None if they are)."""
    if len(points) < 3:
        return f"a polygon needs at least three points, got {len(points)}"
    pts = np.asarray(points, dtype=float)
    rel = pts - pts[0]
    if np.abs(rel[:, 0, None] * rel[None, :, 1] - rel[:, 1, None] * rel[None, :, 0]).max() <= 1e-12:
        return "the polygon has no area (its points lie on a line)"
    poly = Polygon(points)
    if not poly.is_valid:
        import shapely.validation
        return f"the polygon is not simple: {shapely.validation.explain_validity(poly)}"
    if poly.area <= 1e-12:
        return "the polygon has no area"
    return None


@functools.lru_cache(maxsize=1024)
def convex_parts_local(points: tuple[tuple[float, float], ...]) -> tuple[np.ndarray, ...]:
    """A simple polygon split into convex parts that cover it exactly (counter-clockwise (k, 2)
    arrays, in the polygon's own frame): the polygon itself if it is convex, else its constrained
    Delaunay triangles merged greedily along shared edges while the union stays convex
    (Hertel-Mehlhorn; at most four times the optimal number of parts). MuJoCo collides each part
    as its own convex geom, the path search grows each part."""
    poly = shapely.geometry.polygon.orient(Polygon(points), 1.0)
    if poly.convex_hull.area - poly.area <= 1e-9 * max(poly.area, 1.0):
        return (_ccw(poly),)
    parts = [shapely.geometry.polygon.orient(t, 1.0)
             for t in shapely.constrained_delaunay_triangles(poly).geoms]
    merged = True
    while merged:
        merged = False
        for i in range(len(parts)):
            for j in range(i + 1, len(parts)):
                shared = parts[i].intersection(parts[j])
                if shared.length <= 1e-12:            # no common edge
                    continue
                union = parts[i].union(parts[j])
                if union.geom_type == "Polygon" and union.convex_hull.area - union.area <= 1e-9:
                    parts[i] = shapely.geometry.polygon.orient(union.simplify(0.0), 1.0)
                    del parts[j]
                    merged = True
                    break
            if merged:
                break
    return tuple(_ccw(p) for p in parts)


def _ccw(poly: Polygon) -> np.ndarray:
    pts = np.asarray(poly.exterior.coords)[:-1].copy()
    pts.flags.writeable = False
    return pts


def convex_parts(obs: Obstacle) -> list[np.ndarray]:
    """The convex parts of a polygon or mesh obstacle in the world, where the scenario places it."""
    return [place(p, obs.x, obs.y, obs.yaw_rad) for p in convex_parts_local(tuple(outline_points(obs)))]


def bounding_radius(obs: Obstacle) -> float:
    """Radius of a circle around (obs.x, obs.y) that holds the obstacle."""
    if isinstance(obs, BoxObstacle):
        return math.hypot(obs.length, obs.width) / 2.0
    if isinstance(obs, CylinderObstacle):
        return obs.radius
    pts = np.asarray(outline_points(obs), dtype=float).reshape(-1, 2)
    return float(np.hypot(pts[:, 0], pts[:, 1]).max()) if len(pts) else 0.0


def obstacle_polygons(scenario: Scenario) -> list[Polygon]:
    return [obstacle_polygon(o) for o in scenario.obstacles]


def convex_point_distance(points: np.ndarray, verts: np.ndarray) -> np.ndarray:
    """Distance (n,) of points (n, 2) to the convex polygon with counter-clockwise vertices
    ``verts`` (V, 2); 0 inside."""
    a = verts[None, :, :]
    e = (np.roll(verts, -1, axis=0) - verts)[None, :, :]                # (1, V, 2)
    p = points[:, None, :] - a                                           # (n, V, 2)
    inside = (e[..., 0] * p[..., 1] - e[..., 1] * p[..., 0] >= 0).all(axis=1)
    t = np.clip((p * e).sum(-1) / np.maximum((e * e).sum(-1), 1e-300), 0.0, 1.0)
    d = np.hypot(p[..., 0] - t * e[..., 0], p[..., 1] - t * e[..., 1]).min(axis=1)
    return np.where(inside, 0.0, d)


def footprint_part_distance(hl: float, hw: float, rho: float, poses: np.ndarray, verts: np.ndarray
                            ) -> np.ndarray:
    """Exact distance (k,) between a rounded-box footprint (half length ``hl`` along the heading,
    half width ``hw``, rounding ``rho``: a box has rho = 0, a circle hl = hw = 0) at ``poses``
    (k, 3) and one convex polygon (V, 2, counter-clockwise); 0 on overlap.

    Disjoint convex shapes are nearest at a vertex of one of them: the least vertex-to-shape
    distance both ways; overlap by separating axes (the box's two, the polygon's edge normals)."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    X, Y = poses[:, 0:1], poses[:, 1:2]
    C, S = np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])
    ox, oy = verts[None, :, 0] - X, verts[None, :, 1] - Y                 # (k, V)
    rx, ry = ox * C + oy * S, -ox * S + oy * C                             # polygon, footprint frame
    d1 = np.hypot(np.maximum(np.abs(rx) - hl, 0.0), np.maximum(np.abs(ry) - hw, 0.0)).min(axis=1)
    corners = np.array([(hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw)])
    wx = X + C * corners[:, 0] - S * corners[:, 1]                         # (k, 4)
    wy = Y + S * corners[:, 0] + C * corners[:, 1]
    d2 = convex_point_distance(np.stack([wx, wy], axis=-1).reshape(-1, 2), verts).reshape(-1, 4).min(axis=1)
    edges = np.roll(verts, -1, axis=0) - verts
    normals = np.column_stack([edges[:, 1], -edges[:, 0]])                 # outward for CCW
    proj_part = verts @ normals.T                                          # (V, E)
    proj_box = wx[:, :, None] * normals[:, 0] + wy[:, :, None] * normals[:, 1]   # (k, 4, E)
    sep = ((proj_box.min(axis=1) > proj_part.max(axis=0))
           | (proj_box.max(axis=1) < proj_part.min(axis=0))).any(axis=1)
    sep |= (rx.min(axis=1) > hl) | (rx.max(axis=1) < -hl) | (ry.min(axis=1) > hw) | (ry.max(axis=1) < -hw)
    return np.where(sep, np.maximum(np.minimum(d1, d2) - rho, 0.0), 0.0)
