"""The reduced visibility graph among grown obstacles (``grown.py``), and the searches over it:
nodes are the stops and the polygon vertices not buried in another polygon; an edge joins two
nodes tangent to their polygons (both of a vertex's neighbours on one side of it) along a segment
clear of every polygon. A node's edges are found when a search first reaches it (a crowded
world's A* reaches few of its nodes); a small graph is built whole.
"""
from __future__ import annotations

import heapq
import math
from typing import Sequence

import numpy as np

from .grown import Grown, buried, segments_free


def graph(stops: np.ndarray, g: Grown, whole: bool = False) -> tuple[np.ndarray, "Adjacency"]:
    """The reduced visibility graph: nodes (``stops`` first, in order, then the polygon vertices
    not buried inside another polygon) and each node's (neighbour, distance) list, ascending by
    neighbour (``Adjacency``: built a node at a time as a search reaches it, or ``whole``)."""
    k, mmax = g.offsets.shape
    valid = np.arange(mmax)[None, :] < g.sizes[:, None]
    owner = np.broadcast_to(np.arange(k)[:, None], valid.shape)[valid]
    allv = g.verts[valid]
    keep = ~buried(allv, owner, g)
    nodes = np.concatenate([stops, allv[keep]])
    prev = np.concatenate([stops, g.prev[valid][keep]])
    after = np.concatenate([stops, g.after[valid][keep]])
    return nodes, Adjacency(nodes, prev, after, g, whole or len(nodes) <= WHOLE_NODES)


WHOLE_NODES = 160   # a graph of at most this many nodes is built whole (see Adjacency)


class Adjacency:
    """The reduced visibility graph's edges: ``adj[u]`` is node u's (neighbour, distance) list,
    ascending by neighbour. An edge must be tangent to its polygon at each end (both of that
    vertex's neighbours on one side of it) and clear of every grown polygon.

    Built a node at a time, when a path search first asks for a node's edges: A* towards a
    goal looks at few of a crowded world's nodes (BARN world 0: 8 of 540), and the pairs it
    never reached were most of the cost. ``whole``: every pair in one vectorised pass, for a
    search that reaches most nodes (the Dijkstra through waypoint discs: 3-4x cheaper so).
    Either way a node's list is the same, bit for bit: the same tests on the same pairs (each
    segment from its lower-numbered end), so a search over it takes the same steps."""

    def __init__(self, nodes: np.ndarray, prev: np.ndarray, after: np.ndarray, g: Grown,
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
        free = segments_free(self.nodes[i], self.nodes[j], self.g)
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
            ok = segments_free(self.nodes[low], self.nodes[high], self.g)
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


def astar(adj: Sequence[list[tuple[int, float]]], nodes: np.ndarray, src: int, dst: int) -> list[int] | None:
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


def layered_dijkstra(nodes: np.ndarray, adj: Sequence[list[tuple[int, float]]], which: np.ndarray,
                     n_discs: int) -> tuple[list[int] | None, int]:
    """Dijkstra over (node, next disc to touch): at a candidate of that disc the state moves on
    to the next disc at no cost. Starts at node 0 (disc 0 touched). (the hop sequence or None,
    the number of discs reached in order)."""
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
            return points[::-1], n_discs
        for v, w in adj[u]:
            nd = du + w
            if nd < cost.get((v, layer), math.inf):
                cost[(v, layer)], back[(v, layer)] = nd, (u, layer)
                heapq.heappush(heap, (nd, v, layer))
    return None, best_layer
