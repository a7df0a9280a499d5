"""Exact planar distances between obstacles and the robot (a small geometry kernel of rounded
boxes), the narrowest obstacle-obstacle gap of a scenario, and which obstacles the paths keep clear
of (``verdict/paths.py`` plans among them). Vectorised with numpy, cached on the exact inputs."""
from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

from ..scenario.model import BoxObstacle, CylinderObstacle, Footprint, MeshObstacle, Obstacle, PolygonObstacle, Scenario

CACHE_SIZE = 4096            # scenarios remembered by shortest_path / min_obstacle_gap


# --------------------------------------------------------------------------------------------
# Geometry kernel: rounded boxes (box core with half extents hl, hw, rotated, plus radius rho).
# A box obstacle has rho = 0, a cylinder hl = hw = 0 and rho = its radius; the same for the robot.


@dataclass(frozen=True, eq=False)
class Shapes:
    """Obstacles (or any set of rounded boxes) as parallel numpy arrays."""
    names: tuple[str, ...]
    x: np.ndarray
    y: np.ndarray
    cos: np.ndarray
    sin: np.ndarray
    hl: np.ndarray
    hw: np.ndarray
    rho: np.ndarray

    def __len__(self) -> int:
        return len(self.names)


def obstacle_shapes(obstacles: Sequence[Obstacle]) -> Shapes:
    """Rounded-box arrays of the obstacles (cached: the search asks for the same ones often)."""
    key = tuple(obstacles)
    hit = _SHAPES_CACHE.get(key)
    if hit is None:
        hit = _build_shapes(key)
        remember(_SHAPES_CACHE, key, hit)
    return hit


def _build_shapes(obstacles: tuple[Obstacle, ...]) -> Shapes:
    rows = []
    for obs in obstacles:
        if isinstance(obs, BoxObstacle):
            yaw = math.radians(obs.yaw)
            rows.append((obs.x, obs.y, math.cos(yaw), math.sin(yaw), obs.length / 2, obs.width / 2, 0.0))
        elif isinstance(obs, CylinderObstacle):
            rows.append((obs.x, obs.y, 1.0, 0.0, 0.0, 0.0, obs.radius))
        else:
            raise TypeError(f"unknown obstacle type {type(obs).__name__} (expected a box or a cylinder)")
    arr = np.array(rows, dtype=float).reshape(-1, 7)
    cols = [np.ascontiguousarray(arr[:, i]) for i in range(7)]
    for c in cols:
        c.setflags(write=False)
    return Shapes(tuple(o.name for o in obstacles), *cols)


def footprint_core(footprint: Footprint) -> tuple[float, float, float]:
    """(half length, half width, rounding radius) of the footprint as a rounded box."""
    if footprint.shape == "circle":
        return 0.0, 0.0, float(footprint.radius)
    return footprint.length / 2.0, footprint.width / 2.0, 0.0


def point_box_distance(px, py, bx, by, bc, bs, bhl, bhw):
    """Distance from points to solid rotated boxes (0 inside); all arguments broadcast."""
    dx = px - bx
    dy = py - by
    u = np.abs(dx * bc + dy * bs) - bhl
    v = np.abs(dy * bc - dx * bs) - bhw
    return np.hypot(np.maximum(u, 0.0), np.maximum(v, 0.0))


def box_box_distance(ax, ay, ac, as_, ahl, ahw, bx, by, bc, bs, bhl, bhw):
    """Distance between solid rotated boxes (0 when they touch or overlap); broadcasts.

    Separating-axis test for overlap; for disjoint convex polygons the distance is attained
    at a vertex of one of them, so it is the least vertex-to-box distance both ways.
    Degenerate boxes (zero extents) are points, which makes this work for circles too.
    """
    dx = bx - ax
    dy = by - ay
    cab = np.abs(ac * bc + as_ * bs)
    sab = np.abs(as_ * bc - ac * bs)
    separated = ((np.abs(dx * ac + dy * as_) > ahl + bhl * cab + bhw * sab)
                 | (np.abs(dy * ac - dx * as_) > ahw + bhl * sab + bhw * cab)
                 | (np.abs(dx * bc + dy * bs) > bhl + ahl * cab + ahw * sab)
                 | (np.abs(dy * bc - dx * bs) > bhw + ahl * sab + ahw * cab))
    # the four corners of each box at once, on a leading axis (the same operations, element by
    # element, as one corner at a time: a quarter of the numpy calls, issue 35)
    lead = (4,) + (1,) * np.ndim(separated)
    sx, sy = _CORNER_X.reshape(lead), _CORNER_Y.reshape(lead)
    avx = ax + sx * ahl * ac - sy * ahw * as_
    avy = ay + sx * ahl * as_ + sy * ahw * ac
    bvx = bx + sx * bhl * bc - sy * bhw * bs
    bvy = by + sx * bhl * bs + sy * bhw * bc
    d = np.minimum(point_box_distance(avx, avy, bx, by, bc, bs, bhl, bhw),
                   point_box_distance(bvx, bvy, ax, ay, ac, as_, ahl, ahw))
    return np.where(separated, d.min(axis=0), 0.0)


_CORNER_X = np.array([1.0, 1.0, -1.0, -1.0])    # the corners' signs along a box's length and width
_CORNER_Y = np.array([1.0, -1.0, 1.0, -1.0])


def shape_pair_distance(a: Shapes, ia, b: Shapes, ib) -> np.ndarray:
    """Exact distances between rounded boxes ``a[ia]`` and ``b[ib]`` (index arrays), 0 on overlap."""
    core = box_box_distance(a.x[ia], a.y[ia], a.cos[ia], a.sin[ia], a.hl[ia], a.hw[ia],
                            b.x[ib], b.y[ib], b.cos[ib], b.sin[ib], b.hl[ib], b.hw[ib])
    return np.maximum(core - a.rho[ia] - b.rho[ib], 0.0)


# --------------------------------------------------------------------------------------------
# Obstacle-obstacle gap


def static_obstacles(scenario: Scenario) -> tuple[Obstacle, ...]:
    """The obstacles that do not move: what the shortest path, path efficiency and the gap are
    measured among (a moving obstacle is somewhere else a moment later; its clearance is measured
    where it was, see metrics.min_clearance)."""
    obstacles = scenario.obstacles
    if not any(getattr(o, "motion", None) is not None for o in obstacles):
        return tuple(obstacles)
    return tuple(o for o in obstacles if getattr(o, "motion", None) is None)


def path_obstacles(scenario: Scenario) -> tuple[Obstacle, ...]:
    """What a path must keep the footprint clear of: the static obstacles, and on terrain the
    ground the body cannot cross (``traversable.barriers``: a step above its climb height, a
    slope too steep, a pit's walls)."""
    statics = static_obstacles(scenario)
    if not scenario.terrain:
        return statics
    from ..scenario.ground.traversable import barriers
    return statics + barriers(scenario)


def clearance_obstacles(scenario: Scenario) -> tuple[Obstacle, ...]:
    """What the footprint's clearance is measured to: the static obstacles, and on terrain what
    the body cannot cross (``traversable.barriers``, issue 36): a face as the line it stands on (a
    box of no width, so the distance is to the face, not to the path search's 2 cm wall), a steep
    slope or patch as its area. A body without declared limits (an MJCF robot) adds nothing."""
    statics = static_obstacles(scenario)
    if not scenario.terrain:
        return statics
    from ..scenario.ground.traversable import WALL, barriers
    walls = barriers(scenario)
    faces = _FACES_CACHE.get(walls)
    if faces is None:
        faces = tuple(replace(b, width=0.0) if b.width == WALL else b for b in walls)
        remember(_FACES_CACHE, walls, faces)
    return statics + faces


def is_terrain_face(scenario: Scenario, name: str) -> bool:
    """True when ``name`` (a clearance's obstacle) is one of the terrain's faces or steep areas,
    not an obstacle of the scenario."""
    return bool(name) and bool(scenario.terrain) and all(o.name != name for o in scenario.obstacles)


def min_obstacle_gap(scenario: Scenario) -> tuple[float, str, str]:
    """The narrowest gap between two static obstacles: ``(distance m, name a, name b)``, 0 when
    they touch or overlap; ``(inf, "", "")`` with fewer than two. Exact (true circles)."""
    key = static_obstacles(scenario)
    hit = _GAP_CACHE.get(key)
    if hit is None:
        simple = tuple(o for o in key if not is_outlined(o))
        hit = _min_gap(obstacle_shapes(simple))
        if len(simple) < len(key):
            hit = min(hit, _outline_gap(key), key=lambda g: g[0])
        remember(_GAP_CACHE, key, hit)
    return hit


def is_outlined(obs: Obstacle) -> bool:
    """A polygon or mesh obstacle (measured by its outline's convex parts, not as a rounded box)."""
    return isinstance(obs, (PolygonObstacle, MeshObstacle))


def _outline_gap(obstacles: tuple[Obstacle, ...]) -> tuple[float, str, str]:
    """The narrowest gap of the pairs with a polygon or mesh in them (exact: outlines are
    polygons, a cylinder is its centre's distance minus its radius)."""
    from shapely.geometry import Point

    from ..scenario.geometry import obstacle_polygon

    best = (math.inf, "", "")
    shapes = [Point(o.x, o.y) if isinstance(o, CylinderObstacle) else obstacle_polygon(o) for o in obstacles]
    for i, a in enumerate(obstacles):
        for j in range(i + 1, len(obstacles)):
            b = obstacles[j]
            if not (is_outlined(a) or is_outlined(b)):
                continue
            d = shapes[i].distance(shapes[j])
            d -= (a.radius if isinstance(a, CylinderObstacle) else 0.0) + \
                (b.radius if isinstance(b, CylinderObstacle) else 0.0)
            d = max(d, 0.0)
            if d < best[0]:
                best = (d, a.name, b.name)
    return best


def _min_gap(shapes: Shapes) -> tuple[float, str, str]:
    if len(shapes) < 2:
        return math.inf, "", ""
    i, j = np.triu_indices(len(shapes), 1)
    d = shape_pair_distance(shapes, i, shapes, j)
    k = int(np.argmin(d))
    return float(d[k]), shapes.names[i[k]], shapes.names[j[k]]


_GAP_CACHE: OrderedDict[Any, tuple[float, str, str]] = OrderedDict()
_SHAPES_CACHE: OrderedDict[Any, Shapes] = OrderedDict()
_FACES_CACHE: OrderedDict[Any, tuple] = OrderedDict()    # a terrain's barriers -> their faces as lines


def clear_gap_caches() -> None:
    """Forget every remembered gap, shape table and terrain face."""
    _GAP_CACHE.clear()
    _SHAPES_CACHE.clear()
    _FACES_CACHE.clear()


def remember(cache: OrderedDict, key: Any, value: Any) -> None:
    """Put ``value`` in the least-recently-filled ``cache``, dropping the oldest past CACHE_SIZE."""
    cache[key] = value
    if len(cache) > CACHE_SIZE:
        cache.popitem(last=False)
