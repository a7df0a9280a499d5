"""Shortest collision-free paths for the robot's footprint, and exact planar distances.

Two jobs that share one small geometry kernel:

* ``shortest_path(scenario)``: the shortest path from the start through the waypoints (in
  order) to the goal that keeps the footprint clear of every obstacle. The yardstick of the
  path-efficiency and deviation metrics, and the search's validity check (``path_exists``).
* exact, vectorised distances between boxes, circles and "rounded boxes" (used for the
  clearance metric and ``min_obstacle_gap``).

Inflation choice (configuration space). Each obstacle is grown by the footprint's half
WIDTH for a box footprint (radius for a circle) and the robot centre is treated as a point.
For a box robot this is the optimistic bound: the robot can drive lengthwise through any gap
wider than itself, which is how a legged robot passes a door; turning in place near an
obstacle may still need more room. Growing by the half diagonal instead would declare doors
the robot really fits through impassable.

The grown shapes are exact Minkowski sums (a box grows into a rounded box, a cylinder into a
bigger circle) whose round parts are replaced by *circumscribed* polygons: straight sides keep
the exact inflation, corners bulge out by at most ``INFLATION_TOLERANCE`` (1 cm). The path is
therefore never closer than the inflation radius to an obstacle, and at most ~1 cm longer per
corner it wraps than the true optimum. Gaps narrower than ``robot width + 2 x tolerance`` at a
rounded corner may be judged closed.

Algorithm: reduced visibility graph (only edges tangent to the convex grown polygons at their
ends) + Dijkstra, vectorised with numpy. Results are cached on the exact inputs (footprint,
start, waypoints, goal, obstacles): hashing those frozen dataclasses costs ~3 us where
``content_hash`` costs ~0.3 ms, and the answer does not depend on anything else.
"""
from __future__ import annotations

import heapq
import math
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from .scenario import BoxObstacle, CylinderObstacle, Footprint, Obstacle, Scenario

INFLATION_TOLERANCE = 0.01   # m: how far polygonised round parts may bulge beyond the true shape
CACHE_SIZE = 4096            # scenarios remembered by shortest_path / min_obstacle_gap
_TOL = 1e-9                  # m: touching counts as free (a path may graze a grown obstacle)


@dataclass(frozen=True)
class ShortestPath:
    """A collision-free path for the footprint's centre: total ``length`` (m) and its
    vertices ``points`` ((k, 2) read-only array, start first, goal last)."""
    length: float
    points: np.ndarray


# --------------------------------------------------------------------------------------------
# Geometry kernel: rounded boxes (box core with half extents hl, hw, rotated, plus radius rho).
# A box obstacle has rho = 0, a cylinder hl = hw = 0 and rho = its radius; the same for the robot.


@dataclass(frozen=True)
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
        _remember(_SHAPES_CACHE, key, hit)
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
    best = None
    for sx, sy in ((1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)):
        avx = ax + sx * ahl * ac - sy * ahw * as_
        avy = ay + sx * ahl * as_ + sy * ahw * ac
        bvx = bx + sx * bhl * bc - sy * bhw * bs
        bvy = by + sx * bhl * bs + sy * bhw * bc
        d = np.minimum(point_box_distance(avx, avy, bx, by, bc, bs, bhl, bhw),
                       point_box_distance(bvx, bvy, ax, ay, ac, as_, ahl, ahw))
        best = d if best is None else np.minimum(best, d)
    return np.where(separated, best, 0.0)


def shape_pair_distance(a: Shapes, ia, b: Shapes, ib) -> np.ndarray:
    """Exact distances between rounded boxes ``a[ia]`` and ``b[ib]`` (index arrays), 0 on overlap."""
    core = box_box_distance(a.x[ia], a.y[ia], a.cos[ia], a.sin[ia], a.hl[ia], a.hw[ia],
                            b.x[ib], b.y[ib], b.cos[ib], b.sin[ib], b.hl[ib], b.hw[ib])
    return np.maximum(core - a.rho[ia] - b.rho[ib], 0.0)


# --------------------------------------------------------------------------------------------
# Obstacle-obstacle gap


def min_obstacle_gap(scenario: Scenario) -> tuple[float, str, str]:
    """The narrowest gap between two obstacles: ``(distance m, name a, name b)``, 0 when they
    touch or overlap; ``(inf, "", "")`` with fewer than two obstacles. Exact (true circles)."""
    key = tuple(scenario.obstacles)
    hit = _GAP_CACHE.get(key)
    if hit is None:
        hit = _min_gap(obstacle_shapes(key))
        _remember(_GAP_CACHE, key, hit)
    return hit


def _min_gap(shapes: Shapes) -> tuple[float, str, str]:
    if len(shapes) < 2:
        return math.inf, "", ""
    i, j = np.triu_indices(len(shapes), 1)
    d = shape_pair_distance(shapes, i, shapes, j)
    k = int(np.argmin(d))
    return float(d[k]), shapes.names[i[k]], shapes.names[j[k]]


# --------------------------------------------------------------------------------------------
# Shortest path


def inflation_radius(footprint: Footprint) -> float:
    """How much obstacles grow for the path search: half the width of a box footprint (the
    robot drives lengthwise through gaps), the radius of a circle. See the module docstring."""
    return float(footprint.radius) if footprint.shape == "circle" else footprint.width / 2.0


def inflated_polygon(obs: Obstacle, r: float, tol: float = INFLATION_TOLERANCE) -> np.ndarray:
    """Counter-clockwise vertices ((m, 2) array) of a convex polygon containing ``obs`` grown
    by ``r``: exact on straight sides, round parts circumscribed within ``tol``."""
    if isinstance(obs, CylinderObstacle):
        big = obs.radius + r
        n = int(np.clip(math.ceil(math.pi / math.acos(big / (big + tol))), 8, 64))
        ang = (np.arange(n) + 0.5) * (2 * math.pi / n)
        rad = big / math.cos(math.pi / n)
        return np.column_stack([obs.x + rad * np.cos(ang), obs.y + rad * np.sin(ang)])
    hl, hw = obs.length / 2.0, obs.width / 2.0
    if r <= 0:
        local = np.array([(hl, -hw), (hl, hw), (-hl, hw), (-hl, -hw)])
    else:
        q = int(np.clip(math.ceil((math.pi / 2) / (2 * math.acos(r / (r + tol)))), 1, 8))
        step = (math.pi / 2) / q
        rad = r / math.cos(step / 2)
        pts = []
        for k, (cx, cy) in enumerate(((hl, -hw), (hl, hw), (-hl, hw), (-hl, -hw))):
            start = -math.pi / 2 + k * math.pi / 2
            for j in range(q):
                a = start + (j + 0.5) * step
                pts.append((cx + rad * math.cos(a), cy + rad * math.sin(a)))
        local = np.array(pts)
    yaw = math.radians(obs.yaw)
    c, s = math.cos(yaw), math.sin(yaw)
    return np.column_stack([obs.x + c * local[:, 0] - s * local[:, 1],
                            obs.y + s * local[:, 0] + c * local[:, 1]])


def shortest_path(scenario: Scenario) -> ShortestPath | None:
    """Shortest collision-free path of the footprint's centre from the start through every
    waypoint (in order) to the goal, or None if there is none (a wall closes the way, or a
    mission point lies inside a grown obstacle). Cached; ~1 ms for ten obstacles uncached."""
    m = scenario.mission
    key = (scenario.robot.footprint, (m.start.x, m.start.y),
           tuple((w.x, w.y) for w in m.waypoints), (m.goal.x, m.goal.y), tuple(scenario.obstacles))
    try:
        return _PATH_CACHE[key]
    except KeyError:
        pass
    stops = np.array([key[1], *key[2], key[3]], dtype=float)
    polys = [inflated_polygon(o, inflation_radius(scenario.robot.footprint)) for o in scenario.obstacles]
    result = _plan(stops, polys)
    _remember(_PATH_CACHE, key, result)
    return result


def path_exists(scenario: Scenario) -> bool:
    """True if the footprint can get from the start through the waypoints to the goal."""
    return shortest_path(scenario) is not None


def clear_caches() -> None:
    """Forget cached paths, gaps and shapes (for benchmarks measuring the uncached cost)."""
    _PATH_CACHE.clear()
    _GAP_CACHE.clear()
    _SHAPES_CACHE.clear()


def _plan(stops: np.ndarray, polys: list[np.ndarray]) -> ShortestPath | None:
    if not polys:
        return _make_path(stops)
    k = len(polys)
    sizes = np.array([len(p) for p in polys])
    mmax = int(sizes.max())
    # padded (k, mmax, 2) vertices and half-planes n.x <= d (padding repeats the last row)
    verts = np.stack([np.concatenate([p, np.repeat(p[-1:], mmax - len(p), 0)]) for p in polys])
    normals = np.empty_like(verts)
    offsets = np.empty(verts.shape[:2])
    for j, p in enumerate(polys):
        e = np.roll(p, -1, 0) - p
        nrm = np.column_stack([e[:, 1], -e[:, 0]]) / np.hypot(e[:, 0], e[:, 1])[:, None]
        pad = mmax - len(p)
        normals[j] = np.concatenate([nrm, np.repeat(nrm[-1:], pad, 0)])
        offsets[j] = np.concatenate([(nrm * p).sum(1), np.repeat((nrm[-1] * p[-1]).sum(), pad)])

    def inside(points: np.ndarray) -> np.ndarray:  # (n, k) strictly inside polygon j
        proj = np.einsum("kmc,nc->nkm", normals, points)
        return (proj < offsets[None] - 1e-7).all(axis=2)

    if inside(stops).any():
        return None
    # nodes: the mission stops, then polygon vertices not buried inside another polygon
    owner = np.repeat(np.arange(k), sizes)
    allv = np.concatenate(polys)
    prev = np.concatenate([np.roll(p, 1, 0) for p in polys])
    after = np.concatenate([np.roll(p, -1, 0) for p in polys])
    buried = inside(allv)
    buried[np.arange(len(allv)), owner] = False
    keep = ~buried.any(axis=1)
    ns = len(stops)
    nodes = np.concatenate([stops, allv[keep]])
    owner = np.concatenate([np.full(ns, -1), owner[keep]])
    prev = np.concatenate([stops, prev[keep]])
    after = np.concatenate([stops, after[keep]])
    n = len(nodes)
    i, j = np.triu_indices(n, 1)
    p, q = nodes[i], nodes[j]
    d = q - p
    # reduced visibility graph: at a polygon vertex the edge must be tangent to its polygon
    ok = _tangent(d, p, prev[i], after[i]) & _tangent(-d, q, prev[j], after[j])
    i, j, p, q, d = i[ok], j[ok], p[ok], q[ok], d[ok]
    free = _segments_free(p, q, d, verts, normals, offsets, sizes)
    i, j = i[free], j[free]
    length = np.hypot(*(nodes[j] - nodes[i]).T)
    adj: list[list[tuple[int, float]]] = [[] for _ in range(n)]
    for a, b, w in zip(i.tolist(), j.tolist(), length.tolist()):
        adj[a].append((b, w))
        adj[b].append((a, w))
    route = [0]
    for leg in range(ns - 1):
        hops = _dijkstra(adj, leg, leg + 1)
        if hops is None:
            return None
        route.extend(hops[1:])
    return _make_path(nodes[route])


def _tangent(d, v, a, b) -> np.ndarray:
    """Does the line through vertex v along d leave both neighbours a, b on one side?
    (Always true for mission stops, whose neighbours are themselves.)"""
    c1 = d[:, 0] * (a[:, 1] - v[:, 1]) - d[:, 1] * (a[:, 0] - v[:, 0])
    c2 = d[:, 0] * (b[:, 1] - v[:, 1]) - d[:, 1] * (b[:, 0] - v[:, 0])
    scale = np.hypot(d[:, 0], d[:, 1])
    return c1 * c2 >= -1e-12 * scale * scale


def _segments_free(p, q, d, verts, normals, offsets, sizes) -> np.ndarray:
    """For each segment p->q: does it stay out of the interior of every convex polygon?"""
    centre = np.array([v[: s].mean(0) for v, s in zip(verts, sizes)])
    radius = np.array([np.hypot(*(v[: s] - c).T).max() for v, s, c in zip(verts, sizes, centre)])
    # broad phase: segment to bounding-circle distance
    seg2 = np.maximum((d * d).sum(1), 1e-300)
    rel = centre[None, :, :] - p[:, None, :]                              # (e, k, 2)
    t = np.clip((rel * d[:, None, :]).sum(2) / seg2[:, None], 0.0, 1.0)
    gap = np.hypot(*(rel - t[..., None] * d[:, None, :]).transpose(2, 0, 1))
    e, jj = np.nonzero(gap < radius[None, :] - 1e-7)
    if len(e) == 0:
        return np.ones(len(p), dtype=bool)
    nrm, off, vv = normals[jj], offsets[jj], verts[jj]                    # (c, m, ...)
    pp, qq, dd = p[e], q[e], d[e]
    sep_poly = (((nrm * pp[:, None, :]).sum(2) >= off - _TOL)
                & ((nrm * qq[:, None, :]).sum(2) >= off - _TOL)).any(1)
    side = dd[:, None, 0] * (vv[..., 1] - pp[:, None, 1]) - dd[:, None, 1] * (vv[..., 0] - pp[:, None, 0])
    slack = _TOL * np.sqrt(seg2[e])[:, None]
    sep_line = (side >= -slack).all(1) | (side <= slack).all(1)
    blocked = ~(sep_poly | sep_line)
    free = np.ones(len(p), dtype=bool)
    free[e[blocked]] = False
    return free


def _dijkstra(adj: list[list[tuple[int, float]]], src: int, dst: int) -> list[int] | None:
    dist = {src: 0.0}
    back: dict[int, int] = {}
    heap = [(0.0, src)]
    done = set()
    while heap:
        du, u = heapq.heappop(heap)
        if u in done:
            continue
        if u == dst:
            path = [u]
            while u != src:
                u = back[u]
                path.append(u)
            return path[::-1]
        done.add(u)
        for v, w in adj[u]:
            nd = du + w
            if nd < dist.get(v, math.inf):
                dist[v] = nd
                back[v] = u
                heapq.heappush(heap, (nd, v))
    return None


def _make_path(points: np.ndarray) -> ShortestPath:
    pts = np.array(points, dtype=float).reshape(-1, 2)
    if len(pts) > 1:  # drop repeated points (a waypoint equal to the start, ...)
        step = np.hypot(*np.diff(pts, axis=0).T)
        pts = pts[np.concatenate([[True], step > 0])]
    pts.setflags(write=False)
    length = float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0
    return ShortestPath(length, pts)


# --------------------------------------------------------------------------------------------

_PATH_CACHE: OrderedDict[Any, ShortestPath | None] = OrderedDict()
_GAP_CACHE: OrderedDict[Any, tuple[float, str, str]] = OrderedDict()
_SHAPES_CACHE: OrderedDict[Any, Shapes] = OrderedDict()


def _remember(cache: OrderedDict, key: Any, value: Any) -> None:
    cache[key] = value
    if len(cache) > CACHE_SIZE:
        cache.popitem(last=False)
