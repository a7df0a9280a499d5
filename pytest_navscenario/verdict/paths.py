"""Shortest collision-free paths for the robot's footprint, and exact planar distances.

Two jobs that share one small geometry kernel:

* ``shortest_path(scenario)``: the shortest path from the start through the waypoints (in
  order) to the goal that keeps the footprint clear of every obstacle. The yardstick of the
  path-efficiency and deviation metrics, and the search's validity check (``path_exists``).
* exact, vectorised distances between boxes, circles and "rounded boxes" (used for the
  clearance metric and ``min_obstacle_gap``): those are ``gaps.py``.

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
ends) + A*, vectorised with numpy; a node's edges are found when the search first reaches it (a
crowded world's A* reaches few of its nodes). Results are cached on the exact inputs (footprint,
start, waypoints, goal, obstacles): hashing those frozen dataclasses costs ~3 us where
``content_hash`` costs ~0.3 ms, and the answer does not depend on anything else.
"""
from __future__ import annotations

import functools
import heapq
import math
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Iterator, Sequence

import numpy as np

from ..scenario.model import BoxObstacle, CylinderObstacle, Footprint, Obstacle, Scenario
from .gaps import clear_gap_caches, is_outlined, path_obstacles, remember
from .gaps import footprint_core  # noqa: F401  (search/strategies.py imports it from here, as before)

INFLATION_TOLERANCE = 0.01   # m: how far polygonised round parts may bulge beyond the true shape
_TOL = 1e-9                  # m: touching counts as free (a path may graze a grown obstacle)


@dataclass(frozen=True, eq=False)
class ShortestPath:
    """A collision-free path for the footprint's centre: total ``length`` (m) and its
    vertices ``points`` ((k, 2) read-only array, start first, goal last)."""
    length: float
    points: np.ndarray


# --------------------------------------------------------------------------------------------
# Shortest path


def inflation_radius(footprint: Footprint) -> float:
    """How much obstacles grow for the path search: half the width of a box footprint (the
    robot drives lengthwise through gaps), the radius of a circle. See the module docstring."""
    return float(footprint.radius) if footprint.shape == "circle" else footprint.width / 2.0


def inflated_polygon(obs: Obstacle, r: float, tol: float = INFLATION_TOLERANCE) -> np.ndarray:
    """Counter-clockwise vertices ((m, 2) array) of a convex polygon containing ``obs`` grown
    by ``r``: exact on straight sides, round parts circumscribed within ``tol``."""
    grown = _grow((obs,), r, tol)
    return grown.verts[0, : grown.sizes[0]].copy()


@dataclass(frozen=True, eq=False)
class _Grown:
    """Grown obstacles as padded arrays: polygon j has ``sizes[j]`` vertices ``verts[j]``
    (padding repeats the last one), edge i of it is the half-plane normals[j, i] . p <= offsets[j, i],
    ``prev``/``after`` the neighbouring vertices, and a bounding circle (centre, radius)."""
    verts: np.ndarray
    prev: np.ndarray
    after: np.ndarray
    normals: np.ndarray
    offsets: np.ndarray
    sizes: np.ndarray
    centre: np.ndarray
    radius: np.ndarray

    @functools.cached_property
    def along(self) -> tuple[int, np.ndarray, np.ndarray, float]:
        """(axis, the polygons in the order of their centres along it, those centres' coordinates,
        the largest radius): the index of the broad phases among many polygons, along the axis
        the centres spread most on."""
        axis = 0 if np.ptp(self.centre[:, 0]) >= np.ptp(self.centre[:, 1]) else 1
        order = np.argsort(self.centre[:, axis], kind="stable")
        return axis, order, self.centre[order, axis], float(self.radius.max())


@functools.lru_cache(maxsize=64)
def _box_corners(r: float, tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(corner signs, arc offsets, edge normals) of a box grown by ``r``, its corners' quarter
    arcs circumscribed within ``tol``: the same for every box at one ``r`` (a search grows boxes
    by the same few radii thousands of times). Read-only arrays."""
    q = 1 if r <= 0 else int(np.clip(math.ceil((math.pi / 2) / (2 * math.acos(r / (r + tol)))), 1, 8))
    step = (math.pi / 2) / q
    i = np.arange(4 * q)
    corner = np.array([(1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0)])[i // q]    # (m, 2)
    vang = -math.pi / 2 + (i + 0.5) * step
    nang = -math.pi / 2 + (i + 1) * step
    arc = (max(r, 0.0) / math.cos(step / 2)) * np.column_stack([np.cos(vang), np.sin(vang)])
    lnorm = np.column_stack([np.cos(nang), np.sin(nang)])
    for a in (corner, arc, lnorm):
        a.flags.writeable = False
    return corner, arc, lnorm


@functools.lru_cache(maxsize=64)
def _circle_directions(n: int) -> tuple[np.ndarray, np.ndarray]:
    """(vertex directions, edge normals) of a circle drawn as ``n`` circumscribed edges. Read-only."""
    j = np.arange(n)
    vdir = np.column_stack([np.cos((j + 0.5) * 2 * math.pi / n), np.sin((j + 0.5) * 2 * math.pi / n)])
    ndir = np.column_stack([np.cos((j + 1.0) * 2 * math.pi / n), np.sin((j + 1.0) * 2 * math.pi / n)])
    vdir.flags.writeable = ndir.flags.writeable = False
    return vdir, ndir


def _grow(obstacles: Sequence[Obstacle], r: float, tol: float = INFLATION_TOLERANCE) -> _Grown:
    groups = []  # (verts (g, m, 2), normals (g, m, 2), offsets (g, m), centre (g, 2), radius (g,))
    boxes = [o for o in obstacles if isinstance(o, BoxObstacle)]
    if boxes:
        corner, arc, lnorm = _box_corners(r, tol)
        b = np.array([(o.x, o.y, o.length / 2, o.width / 2, math.radians(o.yaw)) for o in boxes])
        local = corner[None] * b[:, None, 2:4] + arc[None]                               # (g, m, 2)
        c, s_ = np.cos(b[:, 4])[:, None], np.sin(b[:, 4])[:, None]
        verts = np.stack([b[:, 0:1] + c * local[..., 0] - s_ * local[..., 1],
                          b[:, 1:2] + s_ * local[..., 0] + c * local[..., 1]], axis=-1)
        normals = np.stack([c * lnorm[:, 0] - s_ * lnorm[:, 1], s_ * lnorm[:, 0] + c * lnorm[:, 1]], axis=-1)
        offsets = (normals * verts).sum(-1)
        radius = np.sqrt((local ** 2).sum(-1)).max(1)
        groups.append((verts, normals, offsets, b[:, :2], radius))
    for o in obstacles:
        if is_outlined(o):
            groups.extend(_grow_outline(o, r, tol))
    cyls = [o for o in obstacles if isinstance(o, CylinderObstacle)]
    by_count: dict[int, list[CylinderObstacle]] = {}
    for o in cyls:
        big = o.radius + r
        n = int(np.clip(math.ceil(math.pi / math.acos(big / (big + tol))), 8, 64))
        by_count.setdefault(n, []).append(o)
    for n, group in by_count.items():
        cb = np.array([(o.x, o.y, o.radius + r) for o in group])
        vdir, ndir = _circle_directions(n)
        rad = cb[:, 2] / math.cos(math.pi / n)
        verts = cb[:, None, :2] + rad[:, None, None] * vdir[None]
        normals = np.broadcast_to(ndir, (len(group), n, 2))
        offsets = (normals * cb[:, None, :2]).sum(-1) + cb[:, 2:3]
        groups.append((verts, normals, offsets, cb[:, :2], rad))
    mmax = max(g[0].shape[1] for g in groups)

    def pad(a: np.ndarray) -> np.ndarray:
        extra = mmax - a.shape[1]
        return a if extra == 0 else np.concatenate([a, np.repeat(a[:, -1:], extra, axis=1)], axis=1)

    verts = np.concatenate([pad(g[0]) for g in groups])
    return _Grown(
        verts=verts,
        prev=np.concatenate([pad(np.roll(g[0], 1, axis=1)) for g in groups]),
        after=np.concatenate([pad(np.roll(g[0], -1, axis=1)) for g in groups]),
        normals=np.concatenate([pad(g[1]) for g in groups]),
        offsets=np.concatenate([pad(g[2]) for g in groups]),
        sizes=np.concatenate([np.full(len(g[0]), g[0].shape[1]) for g in groups]),
        centre=np.concatenate([g[3] for g in groups]),
        radius=np.concatenate([g[4] for g in groups]),
    )


def _grow_outline(obs: Obstacle, r: float, tol: float) -> list[tuple]:
    """Each convex part of a polygon or mesh grown by ``r`` (its corners' arcs circumscribed within
    ``tol``, like a box's): one convex polygon group each, as ``_grow`` wants them."""
    from ..scenario.geometry import convex_parts

    out = []
    for part in convex_parts(obs):
        edges = np.roll(part, -1, axis=0) - part
        lengths = np.hypot(edges[:, 0], edges[:, 1])
        keep = lengths > 1e-12
        part, edges, lengths = part[keep], edges[keep], lengths[keep]
        normals = np.column_stack([edges[:, 1], -edges[:, 0]]) / lengths[:, None]   # outward (CCW)
        verts, norms = [], []
        for i in range(len(part)):
            n_in, n_out = normals[i - 1], normals[i]       # the edges before and after vertex i
            a0, a1 = math.atan2(n_in[1], n_in[0]), math.atan2(n_out[1], n_out[0])
            turn = (a1 - a0) % (2 * math.pi)
            q = 1 if r <= 0 else int(np.clip(math.ceil(turn / (2 * math.acos(r / (r + tol)))), 1, 16))
            step = turn / q
            for k in range(q):     # the arc around the vertex, circumscribed: vertices at r / cos(step / 2)
                ang = a0 + (k + 0.5) * step
                verts.append(part[i] + (max(r, 0.0) / math.cos(step / 2)) * np.array([math.cos(ang), math.sin(ang)]))
                nang = a0 + (k + 1) * step
                norms.append((math.cos(nang), math.sin(nang)))
        verts = np.array(verts)
        norms = np.array(norms)
        offsets = (norms * verts).sum(-1)
        centre = part.mean(axis=0)
        radius = float(np.hypot(*(verts - centre).T).max())
        out.append((verts[None], norms[None], offsets[None], centre[None], np.array([radius])))
    return out


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
            grown = _grow(obstacles, r + margin)
            at_stop = _inside(stops, grown).any(axis=0)
            if at_stop.any():
                keep, grown = tuple(o for o, out in zip(obstacles, at_stop) if not out), None
        if _plan(stops, keep, r + margin, grown) is not None:   # grown: the same obstacles, not again
            return float(margin)
    return 0.0


def clear_caches() -> None:
    """Forget cached paths, gaps and shapes (for benchmarks measuring the uncached cost)."""
    _PATH_CACHE.clear()
    clear_gap_caches()


def _plan(stops: np.ndarray, obstacles: Sequence[Obstacle], r: float, grown: _Grown | None = None
          ) -> ShortestPath | None:
    """Shortest path through ``stops`` among ``obstacles`` grown by ``r`` (``grown``: already so)."""
    if not obstacles:
        return _make_path(stops)
    g = grown if grown is not None else _grow(obstacles, r)
    if _inside(stops, g).any():
        return None
    if _segments_free(stops[:-1], stops[1:], g).all():    # nothing in the way: straight legs
        return _make_path(stops)
    nodes, adj = _graph(stops, g)
    route = [0]
    for leg in range(len(stops) - 1):
        hops = _astar(adj, nodes, leg, leg + 1)
        if hops is None:
            return None
        route.extend(hops[1:])
    return _make_path(nodes[route])


def _inside(points: np.ndarray, g: _Grown) -> np.ndarray:
    """(n, k): point i strictly inside grown polygon j."""
    proj = np.einsum("kmc,nc->nkm", g.normals, points)
    return (proj < g.offsets[None] - 1e-7).all(axis=2)


def _buried(points: np.ndarray, owner: np.ndarray, g: _Grown) -> np.ndarray:
    """(n,): point i strictly inside a grown polygon other than ``owner[i]`` (``_inside``'s test,
    the same arithmetic), tried only against the polygons whose bounding circle holds it (found
    by ``_pairs_within``). Every vertex against every polygon was most of a crowded world's path
    search (BARN world 0: 3300 vertices x 209 polygons x 16 edges a graph)."""
    axis, _, _, reach = g.along
    reach += 1e-6
    out = np.zeros(len(points), dtype=bool)
    for ii, jj in _pairs_within(np.arange(len(points)), points[:, axis] - reach, points[:, axis] + reach, g):
        dx, dy = points[ii, 0] - g.centre[jj, 0], points[ii, 1] - g.centre[jj, 1]
        near = (dx * dx + dy * dy <= (g.radius[jj] + 1e-6) ** 2) & (jj != owner[ii])
        ii, jj = ii[near], jj[near]
        nrm = g.normals[jj]                                                     # (c, m, 2)
        proj = nrm[..., 0] * points[ii, 0:1] + nrm[..., 1] * points[ii, 1:2]    # as _inside's einsum
        out[ii[(proj < g.offsets[jj] - 1e-7).all(axis=1)]] = True
    return out


PAIRS_AT_ONCE = 1 << 20   # (item, polygon) pairs a broad phase holds at once: ~40 MB of arrays


def _pairs_within(items: np.ndarray, low: np.ndarray, high: np.ndarray, g: _Grown
                  ) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """(item, polygon) index pairs: each of ``items`` with the polygons whose centre lies in its
    [low, high] along ``g.along``'s axis (found in the sorted centres), at most PAIRS_AT_ONCE pairs
    a chunk (an item with more alone), so a crowded world's broad phase stays in bounded memory."""
    _, order, along, _ = g.along
    lo = np.searchsorted(along, low, side="left")
    counts = np.searchsorted(along, high, side="right") - lo
    ends = np.cumsum(counts)
    start = 0
    while start < len(counts):
        before = int(ends[start - 1]) if start else 0
        stop = max(start + 1, int(np.searchsorted(ends, before + PAIRS_AT_ONCE, side="right")))
        c = counts[start:stop]
        yield (np.repeat(items[start:stop], c),
               order[np.repeat(lo[start:stop] - np.cumsum(c) + c, c) + np.arange(int(c.sum()))])
        start = stop


def _graph(stops: np.ndarray, g: _Grown, whole: bool = False) -> tuple[np.ndarray, "_Adjacency"]:
    """The reduced visibility graph: nodes (``stops`` first, in order, then the polygon vertices
    not buried inside another polygon) and each node's (neighbour, distance) list, ascending by
    neighbour (``_Adjacency``: built a node at a time as a search reaches it, or ``whole``)."""
    k, mmax = g.offsets.shape
    valid = np.arange(mmax)[None, :] < g.sizes[:, None]
    owner = np.broadcast_to(np.arange(k)[:, None], valid.shape)[valid]
    allv = g.verts[valid]
    keep = ~_buried(allv, owner, g)
    nodes = np.concatenate([stops, allv[keep]])
    prev = np.concatenate([stops, g.prev[valid][keep]])
    after = np.concatenate([stops, g.after[valid][keep]])
    return nodes, _Adjacency(nodes, prev, after, g, whole or len(nodes) <= WHOLE_NODES)


WHOLE_NODES = 160   # a graph of at most this many nodes is built whole (see _Adjacency)


class _Adjacency:
    """The reduced visibility graph's edges: ``adj[u]`` is node u's (neighbour, distance) list,
    ascending by neighbour. An edge must be tangent to its polygon at each end (both of that
    vertex's neighbours on one side of it) and clear of every grown polygon.

    Built a node at a time, when a path search first asks for a node's edges: A* towards a
    goal looks at few of a crowded world's nodes (BARN world 0: 8 of 540), and the pairs it
    never reached were most of the cost. ``whole``: every pair in one vectorised pass, for a
    search that reaches most nodes (the Dijkstra through waypoint discs: 3-4x cheaper so).
    Either way a node's list is the same, bit for bit: the same tests on the same pairs (each
    segment from its lower-numbered end), so a search over it takes the same steps."""

    def __init__(self, nodes: np.ndarray, prev: np.ndarray, after: np.ndarray, g: _Grown,
                 whole: bool = False):
        self.nodes, self.g = nodes, g
        x, y = nodes[:, 0], nodes[:, 1]
        ea, eb = prev - nodes, after - nodes
        self.x, self.y, self.ea, self.eb = x, y, ea, eb
        self.ca = x * ea[:, 1] - y * ea[:, 0]         # each node's own term of its side tests
        self.cb = x * eb[:, 1] - y * eb[:, 0]
        self.scale = np.sqrt((ea * ea).sum(1) * (eb * eb).sum(1))
        n = len(nodes)
        self.rows: list[list[tuple[int, float]] | None] = [None] * n
        self.reached = np.zeros(n, dtype=bool)                     # nodes whose edges are found
        self.lookup: dict[int, dict[int, float]] = {}              # such a node: neighbour -> length
        if whole:
            self._build_whole()

    def __len__(self) -> int:
        return len(self.rows)

    def __getitem__(self, u: int) -> list[tuple[int, float]]:
        row = self.rows[u]
        if row is None:
            row = self.rows[u] = self._row(u)
        return row

    def _build_whole(self) -> None:
        x, y, ea, eb = self.x, self.y, self.ea, self.eb
        fa = x[None, :] * ea[:, 1:2] - y[None, :] * ea[:, 0:1] - self.ca[:, None]
        fb = x[None, :] * eb[:, 1:2] - y[None, :] * eb[:, 0:1] - self.cb[:, None]
        d2 = (x[None, :] - x[:, None]) ** 2 + (y[None, :] - y[:, None]) ** 2
        tangent = fa * fb >= -1e-12 * self.scale[:, None] * d2
        i, j = np.nonzero(np.triu(tangent & tangent.T, 1))
        free = _segments_free(self.nodes[i], self.nodes[j], self.g)
        i, j = i[free], j[free]
        length = np.sqrt(d2[i, j])
        rows: list[list[tuple[int, float]]] = [[] for _ in range(len(self.nodes))]
        for a, b, w in zip(i.tolist(), j.tolist(), length.tolist()):
            rows[a].append((b, w))
            rows[b].append((a, w))
        self.rows = rows

    def _row(self, u: int) -> list[tuple[int, float]]:
        """Node u's edges: the same element-wise tests as ``_build_whole``'s row and column u."""
        x, y, ea, eb = self.x, self.y, self.ea, self.eb
        # tangent at u towards every j (row u) and at every j towards u (column u)
        d2_row = (x - x[u]) ** 2 + (y - y[u]) ** 2          # d2[u, j]
        d2_col = (x[u] - x) ** 2 + (y[u] - y) ** 2          # d2[j, u]
        at_u = ((x * ea[u, 1] - y * ea[u, 0] - self.ca[u]) * (x * eb[u, 1] - y * eb[u, 0] - self.cb[u])
                >= -1e-12 * self.scale[u] * d2_row)
        at_j = ((x[u] * ea[:, 1] - y[u] * ea[:, 0] - self.ca) * (x[u] * eb[:, 1] - y[u] * eb[:, 0] - self.cb)
                >= -1e-12 * self.scale * d2_col)
        mutual = at_u & at_j
        mutual[u] = False
        cand = np.flatnonzero(mutual)
        seen = self.reached[cand]       # a pair with a node reached before was tested then: its
        fresh = cand[~seen]             # row lists the pair if it is free
        found: dict[int, float] = {}
        if len(fresh):
            low, high = np.minimum(fresh, u), np.maximum(fresh, u)
            ok = _segments_free(self.nodes[low], self.nodes[high], self.g)
            dx, dy = x[high] - x[low], y[high] - y[low]
            length = np.sqrt(dx ** 2 + dy ** 2)                 # d2[low, high], as the whole build
            found = dict(zip(fresh[ok].tolist(), length[ok].tolist()))
        lookup = self.lookup
        row = []
        for j, before in zip(cand.tolist(), seen.tolist()):
            w = lookup[j].get(u) if before else found.get(j)
            if w is not None:
                row.append((j, w))
        self.reached[u] = True
        lookup[u] = dict(row)
        return row


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
        g = _grow(obstacles, r)
        ok = ~_inside(pts, g).any(axis=1)
        pts, which = pts[ok], which[ok]
        if not len(pts) or which[0] != 0:
            return None, 0
        nodes, adj = _graph(pts, g, whole=True)     # its Dijkstra reaches most nodes
    else:
        nodes = pts
        dist = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
        adj = [[(j, float(dist[i, j])) for j in range(len(pts)) if j != i] for i in range(len(pts))]
    return _layered_dijkstra(nodes, adj, which, len(discs))


def _layered_dijkstra(nodes: np.ndarray, adj: Sequence[list[tuple[int, float]]], which: np.ndarray,
                      n_discs: int) -> tuple[ShortestPath | None, int]:
    """Dijkstra over (node, next disc to touch): at a candidate of that disc the state moves on
    to the next disc at no cost. Starts at node 0 (disc 0 touched)."""
    disc_of = which.tolist() + [-1] * (len(nodes) - len(which))
    start = (0, 1)
    cost = {start: 0.0}
    back: dict[tuple[int, int], tuple[int, int]] = {}
    heap = [(0.0, 0, 1)]
    best_layer = 1
    while heap:
        du, u, layer = heapq.heappop(heap)
        if du > cost.get((u, layer), math.inf):
            continue
        if disc_of[u] == layer:      # touching the disc this state is heading for
            nxt = (u, layer + 1)
            if du < cost.get(nxt, math.inf):
                cost[nxt], back[nxt] = du, (u, layer)
                heapq.heappush(heap, (du, u, layer + 1))
            continue
        best_layer = max(best_layer, layer)
        if layer == n_discs:
            points = [u]
            state = (u, layer)
            while state in back:
                state = back[state]
                if state[0] != points[-1]:
                    points.append(state[0])
            return _make_path(nodes[points[::-1]]), n_discs
        for v, w in adj[u]:
            nd = du + w
            if nd < cost.get((v, layer), math.inf):
                cost[(v, layer)], back[(v, layer)] = nd, (u, layer)
                heapq.heappush(heap, (nd, v, layer))
    return None, best_layer


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


def _segments_free(p: np.ndarray, q: np.ndarray, g: _Grown) -> np.ndarray:
    """For each segment p->q: does it stay out of the interior of every grown polygon?
    Broad phase on bounding circles, then the separating-axis test (polygon edge normals and
    the segment's own normal): first against the circle each segment cuts deepest (which
    blocks most blocked segments), then the survivors against all their candidates.

    Few pairs: every segment against every circle at once. Many (a crowded world): each segment
    first against the polygons near its two ends, then, still free, against those whose centre
    lies within the largest radius of its extent along ``g.along``'s axis (``_pairs_within``,
    bounded chunks). The same tests on every pair that can be blocked, so the same answer."""
    d = q - p
    seg2 = np.maximum((d * d).sum(1), 1e-300)
    free = np.ones(len(p), dtype=bool)
    if len(p) * len(g.radius) <= DENSE_PAIRS:
        rx = g.centre[None, :, 0] - p[:, 0:1]                              # (e, k)
        ry = g.centre[None, :, 1] - p[:, 1:2]
        t = np.clip((rx * d[:, 0:1] + ry * d[:, 1:2]) / seg2[:, None], 0.0, 1.0)
        gx, gy = rx - t * d[:, 0:1], ry - t * d[:, 1:2]
        depth = (g.radius[None, :] - 1e-7) ** 2 - (gx * gx + gy * gy)     # > 0: may be blocked
        if len(p) > 64 and g.radius.size > 1:
            first = np.argmax(depth, axis=1)
            e = np.nonzero(depth[np.arange(len(p)), first] > 0)[0]
            free[e[_blocked(p[e], q[e], d[e], seg2[e], g, first[e])]] = False
            depth[~free] = -1.0
        e, jj = np.nonzero(depth > 0)
        if len(e):
            free[e[_blocked(p[e], q[e], d[e], seg2[e], g, jj)]] = False
        return free
    axis, _, _, reach = g.along
    # first the polygons near each end (a blocked segment is mostly blocked by the obstacle beside
    # the vertex it leaves), then what is still free against every polygon near its extent
    every = np.arange(len(p))
    for end in (p, q):
        for e, jj in _pairs_within(every, end[:, axis] - NEAR_ENDS * reach, end[:, axis] + NEAR_ENDS * reach, g):
            _cut(p, q, d, seg2, g, e, jj, free)
    live = np.flatnonzero(free)
    for e, jj in _pairs_within(live, np.minimum(p[live, axis], q[live, axis]) - reach,
                               np.maximum(p[live, axis], q[live, axis]) + reach, g):
        _cut(p, q, d, seg2, g, e, jj, free)
    return free


NEAR_ENDS = 2.0   # largest radii either side of a segment's end within which it is tried first


DENSE_PAIRS = 1 << 16   # segment-polygon pairs up to which every segment meets every polygon at once


def _cut(p, q, d, seg2, g: _Grown, e: np.ndarray, jj: np.ndarray, free: np.ndarray) -> None:
    """Mark in ``free`` the segments ``e`` that cut the interior of polygon ``jj`` (pairs)."""
    rx = g.centre[jj, 0] - p[e, 0]
    ry = g.centre[jj, 1] - p[e, 1]
    t = np.clip((rx * d[e, 0] + ry * d[e, 1]) / seg2[e], 0.0, 1.0)
    gx, gy = rx - t * d[e, 0], ry - t * d[e, 1]
    depth = (g.radius[jj] - 1e-7) ** 2 - (gx * gx + gy * gy)               # > 0: may be blocked
    near = depth > 0
    e, jj, depth = e[near], jj[near], depth[near]
    if len(e) > 64:
        deepest = np.lexsort((-depth, e))                                    # each segment's first
        first = deepest[np.concatenate([[True], e[deepest][1:] != e[deepest][:-1]])]
        free[e[first][_blocked(p[e[first]], q[e[first]], d[e[first]], seg2[e[first]], g, jj[first])]] = False
        tried = np.zeros(len(e), dtype=bool)
        tried[first] = True
        rest = free[e] & ~tried
        e, jj = e[rest], jj[rest]
    if len(e):
        free[e[_blocked(p[e], q[e], d[e], seg2[e], g, jj)]] = False


def _blocked(pp, qq, dd, seg2, g: _Grown, jj) -> np.ndarray:
    """Separating-axis test of segments pp->qq against polygons jj: True where they cut the interior."""
    nrm, off, vv = g.normals[jj], g.offsets[jj], g.verts[jj]              # (c, m, ...)
    sep_poly = (((nrm[..., 0] * pp[:, 0:1] + nrm[..., 1] * pp[:, 1:2]) >= off - _TOL)
                & ((nrm[..., 0] * qq[:, 0:1] + nrm[..., 1] * qq[:, 1:2]) >= off - _TOL)).any(1)
    side = dd[:, 0:1] * (vv[..., 1] - pp[:, 1:2]) - dd[:, 1:2] * (vv[..., 0] - pp[:, 0:1])
    slack = _TOL * np.sqrt(seg2)[:, None]
    sep_line = (side >= -slack).all(1) | (side <= slack).all(1)
    return ~(sep_poly | sep_line)


def _astar(adj: Sequence[list[tuple[int, float]]], nodes: np.ndarray, src: int, dst: int) -> list[int] | None:
    """Shortest hop sequence src -> dst (A* with the straight-line distance, which is exact
    Dijkstra order for this consistent heuristic), or None if dst is unreachable."""
    gx, gy = float(nodes[dst, 0]), float(nodes[dst, 1])
    xs, ys = nodes[:, 0].tolist(), nodes[:, 1].tolist()
    cost = {src: 0.0}
    back: dict[int, int] = {}
    heap = [(math.hypot(xs[src] - gx, ys[src] - gy), 0.0, src)]
    done = set()
    while heap:
        _, du, u = heapq.heappop(heap)
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
            if nd < cost.get(v, math.inf):
                cost[v] = nd
                back[v] = u
                heapq.heappush(heap, (nd + math.hypot(xs[v] - gx, ys[v] - gy), nd, v))
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
