"""Shortest collision-free paths for the robot's footprint.

* ``shortest_path(scenario)``: the shortest path from the start through the waypoints (in
  order) to the goal that keeps the footprint clear of every obstacle. The yardstick of the
  path-efficiency and deviation metrics, and the search's validity check (``path_exists``).
* ``reference_path``: the same through each waypoint's tolerance disc; ``passage_room``: how much
  room the narrowest passage of the way leaves (the search's ranking).

The obstacles are grown by the footprint (``grown.py``: the inflation choice and its tolerance)
and the footprint's centre is routed as a point over the reduced visibility graph among them
(``visibility.py``), by A*. Exact distances between boxes, circles and rounded boxes (the
clearance metric, ``min_obstacle_gap``) are ``gaps.py``.

Results are cached on the exact inputs (footprint, start, waypoints, goal, obstacles): hashing
those frozen dataclasses costs ~3 us where ``content_hash`` costs ~0.3 ms, and the answer does
not depend on anything else.
"""
from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..scenario.model import Obstacle, Scenario
from .gaps import clear_gap_caches, path_obstacles, remember
from .grown import Grown, grow, inside, segments_free
from .grown import INFLATION_TOLERANCE, inflated_polygon, inflation_radius  # noqa: F401  (the path API, as before)
from .visibility import astar, graph, layered_dijkstra


@dataclass(frozen=True, eq=False)
class ShortestPath:
    """A collision-free path for the footprint's centre: total ``length`` (m) and its
    vertices ``points`` ((k, 2) read-only array, start first, goal last)."""
    length: float
    points: np.ndarray


def shortest_path(scenario: Scenario) -> ShortestPath | None:
    """Shortest collision-free path of the footprint's centre from the start through every
    waypoint (in order) to the goal, or None if there is none (a wall closes the way, or a
    mission point lies inside a grown obstacle). Cached; ~1 ms for ten obstacles uncached."""
    m = scenario.mission
    return path_through(scenario, [(m.start.x, m.start.y), *((w.x, w.y) for w in m.waypoints),
                                   (m.goal.x, m.goal.y)])


def path_through(scenario: Scenario, stops: Sequence[tuple[float, float]]) -> ShortestPath | None:
    """Shortest collision-free path for the scenario's footprint through ``stops`` (x, y) in
    order, among the scenario's obstacles; None if there is none. Cached like shortest_path."""
    stops = tuple((float(x), float(y)) for x, y in stops)
    key = (scenario.robot.footprint, stops, path_obstacles(scenario))
    try:
        return _PATH_CACHE[key]
    except KeyError:
        pass
    result = _plan(np.array(stops, dtype=float).reshape(-1, 2), key[2],
                   inflation_radius(scenario.robot.footprint))
    remember(_PATH_CACHE, key, result)
    return result


def path_exists(scenario: Scenario) -> bool:
    """True if the footprint can get from the start through the waypoints to the goal."""
    return shortest_path(scenario) is not None


def passage_room(scenario: Scenario, margins: Sequence[float]) -> float:
    """How much room the narrowest passage of the way leaves: the largest of ``margins`` (m) by
    which the footprint could grow all round and still get from the start through the waypoints
    to the goal among the static obstacles; 0.0 if none. An obstacle the grown footprint would
    overlap at a mission point itself is left out (crowding the start or goal is not a passage).
    Uncached; the largest margin is tried first, so an open layout costs one path search (about
    1 ms for ten obstacles)."""
    m = scenario.mission
    stops = np.array([(m.start.x, m.start.y), *((w.x, w.y) for w in m.waypoints), (m.goal.x, m.goal.y)],
                     dtype=float)
    obstacles, r = path_obstacles(scenario), inflation_radius(scenario.robot.footprint)
    for margin in sorted(margins, reverse=True):
        keep, grown = obstacles, None
        if obstacles:
            grown = grow(obstacles, r + margin)
            at_stop = inside(stops, grown).any(axis=0)
            if at_stop.any():
                keep, grown = tuple(o for o, out in zip(obstacles, at_stop) if not out), None
        if _plan(stops, keep, r + margin, grown) is not None:   # grown: the same obstacles, not again
            return float(margin)
    return 0.0


def clear_caches() -> None:
    """Forget cached paths, gaps and shapes (for benchmarks measuring the uncached cost)."""
    _PATH_CACHE.clear()
    clear_gap_caches()


def _plan(stops: np.ndarray, obstacles: Sequence[Obstacle], r: float, grown: Grown | None = None
          ) -> ShortestPath | None:
    """Shortest path through ``stops`` among ``obstacles`` grown by ``r`` (``grown``: already so)."""
    if not obstacles:
        return _make_path(stops)
    g = grown if grown is not None else grow(obstacles, r)
    if inside(stops, g).any():
        return None
    if segments_free(stops[:-1], stops[1:], g).all():    # nothing in the way: straight legs
        return _make_path(stops)
    nodes, adj = graph(stops, g)
    route = [0]
    for leg in range(len(stops) - 1):
        hops = astar(adj, nodes, leg, leg + 1)
        if hops is None:
            return None
        route.extend(hops[1:])
    return _make_path(nodes[route])


# --------------------------------------------------------------------------------------------
# Paths through tolerance discs: the waypoints count as passed anywhere within their tolerance.

DISC_SAMPLES = 32   # points on a tolerance disc's rim (plus its centre) a path may touch


def path_through_discs(scenario: Scenario, discs: Sequence[tuple[float, float, float]],
                       inflation: float | None = None,
                       obstacles: tuple[Obstacle, ...] | None = None) -> tuple[ShortestPath | None, int]:
    """Shortest collision-free path from the first disc's centre touching every following disc
    (x, y, radius) in order; ``(path or None, number of discs reached in order)``. A disc is
    touched at its centre or at one of ``DISC_SAMPLES`` points on its rim (a path through the
    exact touch point of the optimum is at most r (1 - cos(pi / 32)), 0.5 % of r, longer).
    ``inflation``: obstacle growth (default: the footprint's, as for shortest_path); ``obstacles``:
    what to keep clear of (default: ``path_obstacles``). Cached."""
    r = inflation_radius(scenario.robot.footprint) if inflation is None else inflation
    discs = tuple((float(x), float(y), max(float(t), 0.0)) for x, y, t in discs)
    key = ("discs", r, discs, path_obstacles(scenario) if obstacles is None else tuple(obstacles))
    try:
        return _PATH_CACHE[key]
    except KeyError:
        pass
    result = _plan_discs(discs, key[3], r)
    remember(_PATH_CACHE, key, result)
    return result


def _disc_points(discs: Sequence[tuple[float, float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """Candidate points of each disc (centre, the disc's point nearest the line between its
    neighbours' centres -- exact where a straight leg crosses the disc --, then rim samples)
    and the disc index of each."""
    ang = np.arange(DISC_SAMPLES) * (2 * math.pi / DISC_SAMPLES)
    pts, which = [], []
    for d, (x, y, t) in enumerate(discs):
        ring = [(x, y)] + ([] if t <= 0 else list(zip(x + t * np.cos(ang), y + t * np.sin(ang))))
        if t > 0 and 0 < d < len(discs) - 1:
            ring.append(_nearest_in_disc((x, y, t), discs[d - 1][:2], discs[d + 1][:2]))
        pts.extend(ring)
        which.extend([d] * len(ring))
    return np.array(pts, dtype=float).reshape(-1, 2), np.array(which)


def _nearest_in_disc(disc: tuple[float, float, float], a: tuple[float, float],
                     b: tuple[float, float]) -> tuple[float, float]:
    """The point of the disc nearest to the segment a-b (on the segment if it crosses the disc)."""
    x, y, t = disc
    dx, dy = b[0] - a[0], b[1] - a[1]
    u = max(0.0, min(1.0, ((x - a[0]) * dx + (y - a[1]) * dy) / ((dx * dx + dy * dy) or 1.0)))
    px, py = a[0] + u * dx, a[1] + u * dy
    dist = math.hypot(px - x, py - y)
    if dist <= t:
        return px, py
    return x + (px - x) * t / dist, y + (py - y) * t / dist


def _plan_discs(discs: Sequence[tuple[float, float, float]], obstacles: Sequence[Obstacle],
                r: float) -> tuple[ShortestPath | None, int]:
    pts, which = _disc_points(discs)
    if obstacles:
        g = grow(obstacles, r)
        ok = ~inside(pts, g).any(axis=1)
        pts, which = pts[ok], which[ok]
        if not len(pts) or which[0] != 0:
            return None, 0
        nodes, adj = graph(pts, g, whole=True)     # its Dijkstra reaches most nodes
    else:
        nodes = pts
        dist = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
        adj = [[(j, float(dist[i, j])) for j in range(len(pts)) if j != i] for i in range(len(pts))]
    hops, reached = layered_dijkstra(nodes, adj, which, len(discs))
    return (None if hops is None else _make_path(nodes[hops])), reached


def reference_path(scenario: Scenario) -> ShortestPath | None:
    """The yardstick of path efficiency: the shortest collision-free path from the start through
    each waypoint's tolerance disc (a waypoint counts as passed anywhere within
    ``mission.waypoint_tolerance``, as in the simulation) to the goal point. Without waypoints
    it is shortest_path. Cached."""
    m = scenario.mission
    if not m.waypoints or m.waypoint_tolerance <= 0:
        return shortest_path(scenario)
    discs = [(m.start.x, m.start.y, 0.0), *((w.x, w.y, m.waypoint_tolerance) for w in m.waypoints),
             (m.goal.x, m.goal.y, 0.0)]
    return path_through_discs(scenario, discs)[0]


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
