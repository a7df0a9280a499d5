"""Obstacles grown by the footprint (the configuration space the path search works in), and what
lies in them or crosses them.

Each obstacle is grown by the footprint's half WIDTH for a box footprint (radius for a circle) and
the robot centre is treated as a point. For a box robot this is the optimistic bound: the robot
can drive lengthwise through any gap wider than itself, which is how a legged robot passes a door;
turning in place near an obstacle may still need more room. Growing by the half diagonal instead
would declare doors the robot really fits through impassable.

The grown shapes are exact Minkowski sums (a box grows into a rounded box, a cylinder into a
bigger circle) whose round parts are replaced by *circumscribed* polygons: straight sides keep
the exact inflation, corners bulge out by at most ``INFLATION_TOLERANCE`` (1 cm). A path among
them is therefore never closer than the inflation radius to an obstacle, and at most ~1 cm longer
per corner it wraps than the true optimum. Gaps narrower than ``robot width + 2 x tolerance`` at
a rounded corner may be judged closed.

``inside`` and ``segments_free`` are vectorised with numpy; among many polygons their broad
phases meet only the polygons near each point or segment, a bounded number of pairs at a time.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Iterator, Sequence

import numpy as np

from ..scenario.model import BoxObstacle, CylinderObstacle, Footprint, Obstacle
from .gaps import is_outlined

INFLATION_TOLERANCE = 0.01   # m: how far polygonised round parts may bulge beyond the true shape
_TOL = 1e-9                  # m: touching counts as free (a path may graze a grown obstacle)


def inflation_radius(footprint: Footprint) -> float:
    """How much obstacles grow for the path search: half the width of a box footprint (the
    robot drives lengthwise through gaps), the radius of a circle. See the module docstring."""
    return float(footprint.radius) if footprint.shape == "circle" else footprint.width / 2.0


def inflated_polygon(obs: Obstacle, r: float, tol: float = INFLATION_TOLERANCE) -> np.ndarray:
    """Counter-clockwise vertices ((m, 2) array) of a convex polygon containing ``obs`` grown
    by ``r``: exact on straight sides, round parts circumscribed within ``tol``."""
    grown = grow((obs,), r, tol)
    return grown.verts[0, : grown.sizes[0]].copy()


@dataclass(frozen=True, eq=False)
class Grown:
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


def grow(obstacles: Sequence[Obstacle], r: float, tol: float = INFLATION_TOLERANCE) -> Grown:
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
    return Grown(
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
    ``tol``, like a box's): one convex polygon group each, as ``grow`` wants them."""
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


def inside(points: np.ndarray, g: Grown) -> np.ndarray:
    """(n, k): point i strictly inside grown polygon j."""
    proj = np.einsum("kmc,nc->nkm", g.normals, points)
    return (proj < g.offsets[None] - 1e-7).all(axis=2)


def buried(points: np.ndarray, owner: np.ndarray, g: Grown) -> np.ndarray:
    """(n,): point i strictly inside a grown polygon other than ``owner[i]`` (``inside``'s test,
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
        proj = nrm[..., 0] * points[ii, 0:1] + nrm[..., 1] * points[ii, 1:2]    # as inside's einsum
        out[ii[(proj < g.offsets[jj] - 1e-7).all(axis=1)]] = True
    return out


PAIRS_AT_ONCE = 1 << 20   # (item, polygon) pairs a broad phase holds at once: ~40 MB of arrays


def _pairs_within(items: np.ndarray, low: np.ndarray, high: np.ndarray, g: Grown
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


def segments_free(p: np.ndarray, q: np.ndarray, g: Grown) -> np.ndarray:
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


def _cut(p, q, d, seg2, g: Grown, e: np.ndarray, jj: np.ndarray, free: np.ndarray) -> None:
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


def _blocked(pp, qq, dd, seg2, g: Grown, jj) -> np.ndarray:
    """Separating-axis test of segments pp->qq against polygons jj: True where they cut the interior."""
    nrm, off, vv = g.normals[jj], g.offsets[jj], g.verts[jj]              # (c, m, ...)
    sep_poly = (((nrm[..., 0] * pp[:, 0:1] + nrm[..., 1] * pp[:, 1:2]) >= off - _TOL)
                & ((nrm[..., 0] * qq[:, 0:1] + nrm[..., 1] * qq[:, 1:2]) >= off - _TOL)).any(1)
    side = dd[:, 0:1] * (vv[..., 1] - pp[:, 1:2]) - dd[:, 1:2] * (vv[..., 0] - pp[:, 0:1])
    slack = _TOL * np.sqrt(seg2)[:, None]
    sep_line = (side >= -slack).all(1) | (side <= slack).all(1)
    return ~(sep_poly | sep_line)
