"""Planar geometry with shapely: footprint and obstacle outlines. Shared by the safety layer,
the metrics and the search's validity check. Angles in radians unless a name says degrees."""
from __future__ import annotations

import functools
import math
from collections import OrderedDict

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


def obstacle_outline(obs: Obstacle) -> Polygon:
    """``obstacle_polygon``, remembered per obstacle (a frozen value: equal obstacles, equal
    outlines). The search checks and ranks hundreds of layouts in which most obstacles stand
    where they stood in the last one; building each outline again was most of that check."""
    try:
        return _remembered(obs, lambda: obstacle_polygon(obs))
    except TypeError:   # a field that does not hash: not remembered
        return obstacle_polygon(obs)


def footprint_outline(footprint: Footprint, x: float, y: float, yaw: float) -> Polygon:
    """``footprint_polygon``, remembered (the start and goal poses of a search's layouts)."""
    return _remembered((footprint, x, y, yaw), lambda: footprint_polygon(footprint, x, y, yaw))


def _remembered(key, make) -> Polygon:
    """The outline kept for ``key``, made and kept (the oldest of OUTLINES_KEPT dropped) if none."""
    hit = _OUTLINES.get(key)
    if hit is None:
        hit = _OUTLINES[key] = make()
        if len(_OUTLINES) > OUTLINES_KEPT:
            _OUTLINES.popitem(last=False)
    return hit


OUTLINES_KEPT = 4096
_OUTLINES: OrderedDict = OrderedDict()


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
    (Hertel-Mehlhorn; at most four times the optimal number of parts; near-linear in corners:
    1000 corners in ~0.1 s, see ``_merge_while_convex``). MuJoCo collides each part as its own
    convex geom, the path search grows each part."""
    poly = shapely.geometry.polygon.orient(Polygon(points), 1.0)
    if poly.convex_hull.area - poly.area <= 1e-9 * max(poly.area, 1.0):
        return (_ccw(poly),)
    triangles = [shapely.geometry.polygon.orient(t, 1.0)
                 for t in shapely.constrained_delaunay_triangles(poly).geoms]
    return tuple(_ccw(p) for p in _merge_while_convex(triangles))


class _Part:
    """A convex part while triangles are merged: ``key`` orders the parts (its lowest triangle
    index), ``root`` is its triangle in the union-find, ``edges`` the diagonals it shares with each
    neighbouring part, ``good`` the neighbours whose union with it is convex, ``angle`` its
    interior angle at each corner and ``short`` the shortest triangle side there."""

    __slots__ = ("key", "root", "poly", "edges", "good", "alive", "angle", "short", "straight")

    def __init__(self, key: int, poly: Polygon, ring: list[tuple[float, float]]):
        self.key, self.root, self.poly, self.alive, self.straight = key, key, poly, True, False
        self.edges: dict[_Part, list[tuple]] = {}
        self.good: set[_Part] = set()
        self.angle: dict[tuple[float, float], float] = {}
        self.short: dict[tuple[float, float], float] = {}
        for i in range(3):
            (px, py), (vx, vy), (nx, ny) = ring[i - 1], ring[i], ring[(i + 1) % 3]
            ax, ay, bx, by = px - vx, py - vy, nx - vx, ny - vy
            self.angle[ring[i]] = math.atan2(abs(ax * by - ay * bx), ax * bx + ay * by)
            self.short[ring[i]] = min(math.hypot(ax, ay), math.hypot(bx, by))


_STRAIGHT = 1e-9      # rad: angles closer than this to 180 degrees are left to the exact test
_FLAT = 1e-9          # m^2: a union whose convex hull exceeds it by at most this counts as convex


def _convex_union(a: _Part, b: _Part, quick: bool) -> bool:
    """True if the union of two neighbouring convex parts is one convex polygon (its convex hull
    larger by at most 1e-9 m^2). ``quick``: first from the angles at the two ends of the shared
    edge (the union is convex iff neither sum exceeds 180 degrees; a larger sum leaves a notch of
    at least half the product of the sides' lengths times the sine of the excess); the union's
    hull, as before, where the angles cannot tell."""
    if quick:
        count: dict[tuple[float, float], int] = {}
        for side in a.edges[b]:
            for c in side:
                count[c] = count.get(c, 0) + 1
        ends = [c for c, n in count.items() if n == 1]
        verdict: bool | None = True if len(ends) == 2 else None
        for v in ends if verdict else ():
            excess = a.angle[v] + b.angle[v] - math.pi
            if excess > _STRAIGHT and 0.5 * a.short[v] * b.short[v] * math.sin(excess) > 2 * _FLAT:
                return False
            if excess > -_STRAIGHT:
                verdict = None
        if verdict is not None:
            return verdict
    first, second = (a, b) if a.key < b.key else (b, a)
    union = first.poly.union(second.poly)
    return union.geom_type == "Polygon" and union.convex_hull.area - union.area <= _FLAT


def _corners(poly: Polygon) -> set[tuple[float, float]]:
    return set(map(tuple, shapely.get_coordinates(poly).tolist()))


def _merge_while_convex(triangles: list[Polygon]) -> list[Polygon]:
    """Hertel-Mehlhorn merging of a triangulation: merge the first pair of neighbouring parts (in
    the order of their lowest triangle index, then the other's) whose union is convex, until none
    is left. The same parts, bit for bit, as re-scanning every pair after each merge (the former
    way: cubic in corners, 170 s for a 1000-corner star), in O(n log n) steps:

    - whether two convex neighbours make a convex union depends only on their angles at the ends
      of their shared edge, and a merge changes angles only at the ends of the diagonal it removes
      (or drops a corner that became straight), so after a merge only the neighbours touching
      those corners are tested again; every other pair keeps its answer;
    - the convex pairs wait in a heap keyed by (lower key, higher key), the former scan's order;
    - a merged part keeps the record of the part with more neighbours (small-to-large), so moving
      neighbour lists costs O(n log n) in all.
    """
    return _Merging(triangles).run()


class _Merging:
    """One run of ``_merge_while_convex``: the parts (one per triangle at first), a union-find from
    triangles to the part that holds them, each diagonal's corners, and the heap of convex pairs."""

    def __init__(self, triangles: list[Polygon]) -> None:
        rings = [list(map(tuple, shapely.get_coordinates(t)[:3].tolist())) for t in triangles]
        self.parts = [_Part(k, t, ring) for k, (t, ring) in enumerate(zip(triangles, rings))]
        self.owner = list(range(len(self.parts)))     # union-find over triangles
        # the quick test's float error stays far below 1e-9 m^2 on obstacles up to 100 m across
        x0, y0, x1, y1 = shapely.total_bounds(triangles)
        self.quick = max(x1 - x0, y1 - y0) <= 100.0
        self.corners = self._link(rings)
        self.heap: list[tuple[int, int, int, int]] = []   # (lower key, higher key, root, root) of convex pairs

    def _link(self, rings: list[list[tuple]]) -> dict[tuple, list[tuple[int, int]]]:
        """Make the triangles sharing a diagonal neighbours; corner -> triangle pairs of its diagonals."""
        parts = self.parts
        sides: dict[tuple, list[int]] = {}
        for k, ring in enumerate(rings):
            for i in range(3):
                u, v = ring[i], ring[(i + 1) % 3]
                sides.setdefault((u, v) if u < v else (v, u), []).append(k)
        corners: dict[tuple, list[tuple[int, int]]] = {}
        for side, owners in sides.items():
            if len(owners) != 2 or math.dist(*side) <= 1e-12:
                continue
            i, j = owners
            parts[i].edges.setdefault(parts[j], []).append(side)
            parts[j].edges.setdefault(parts[i], []).append(side)
            corners.setdefault(side[0], []).append((i, j))
            corners.setdefault(side[1], []).append((i, j))
        return corners

    def part_of(self, t: int) -> _Part:
        owner = self.owner
        root = t
        while owner[root] != root:
            root = owner[root]
        while owner[t] != root:
            owner[t], t = root, owner[t]
        return self.parts[root]

    def push(self, a: _Part, b: _Part) -> None:
        import heapq

        lo, hi = (a, b) if a.key < b.key else (b, a)
        heapq.heappush(self.heap, (lo.key, hi.key, lo.root, hi.root))

    def note(self, a: _Part, b: _Part, convex: bool) -> None:
        if convex:
            a.good.add(b)
            b.good.add(a)
            self.push(a, b)
        else:
            a.good.discard(b)
            b.good.discard(a)

    def run(self) -> list[Polygon]:
        """Merge the first convex pair left until none is: the parts in the order of their keys."""
        import heapq

        parts, heap = self.parts, self.heap
        for p in parts:
            for q in p.edges:
                if p.key < q.key:
                    self.note(p, q, _convex_union(p, q, self.quick))
        while heap:
            lo_key, hi_key, lo_root, hi_root = heapq.heappop(heap)
            a, b = parts[lo_root], parts[hi_root]
            if not (a.alive and b.alive and a.key == lo_key and b.key == hi_key and b in a.good):
                continue                                # stale: merged away since, or no longer convex
            self._merge(a, b, lo_key)
        return [p.poly for p in sorted((p for p in parts if p.alive), key=lambda p: p.key)]

    def _merge(self, a: _Part, b: _Part, lo_key: int) -> None:
        """Merge ``b`` into ``a`` (or the other way: the one with more neighbours stays), then test
        again the pairs whose angles changed."""
        shared = a.edges[b]
        changed = {c for side in shared for c in side}
        union = a.poly.union(b.poly)
        straight = a.straight or b.straight or len(shared) > 1 or \
            any(abs(a.angle[c] + b.angle[c] - math.pi) <= _STRAIGHT for c in changed)
        if straight:     # drop corners that became straight (simplify keeps some of them: remember)
            union = union.simplify(0.0)
        merged = shapely.geometry.polygon.orient(union, 1.0)
        if shapely.get_num_coordinates(merged) != shapely.get_num_coordinates(a.poly) + \
                shapely.get_num_coordinates(b.poly) - 2 * len(shared) - 1:   # not a plain splice:
            changed |= (_corners(a.poly) | _corners(b.poly)) - _corners(merged)   # check every corner
        keep, gone = (a, b) if len(a.edges) >= len(b.edges) else (b, a)
        self._absorb(keep, gone)
        rekeyed = keep.key != lo_key
        keep.key, keep.poly, keep.straight = lo_key, merged, straight
        self._retest(keep, changed)
        if rekeyed:                                 # its pairs' places in the heap moved
            for q in keep.good:
                self.push(keep, q)

    def _absorb(self, keep: _Part, gone: _Part) -> None:
        """``gone``'s neighbours, convex pairs and corner angles move over to ``keep``."""
        gone.alive = False
        self.owner[gone.root] = keep.root
        del keep.edges[gone]
        keep.good.discard(gone)
        for q, sides_q in gone.edges.items():       # the absorbed part's neighbours move over
            if q is keep:
                continue
            del q.edges[gone]
            q.edges.setdefault(keep, []).extend(sides_q)
            keep.edges.setdefault(q, []).extend(sides_q)
            if q in gone.good:
                q.good.discard(gone)
                self.note(keep, q, True)            # kept unless one of its corners changed (_retest)
        if len(gone.angle) > len(keep.angle):      # small into large
            keep.angle, gone.angle, keep.short, gone.short = gone.angle, keep.angle, gone.short, keep.short
        for c, angle in gone.angle.items():
            keep.angle[c] = keep.angle.get(c, 0.0) + angle
            keep.short[c] = min(keep.short.get(c, math.inf), gone.short[c])
        gone.edges, gone.good, gone.angle, gone.short = {}, set(), {}, {}

    def _retest(self, keep: _Part, changed: set) -> None:
        """Test again ``keep``'s pairs with the neighbours that touch a corner whose angle changed."""
        retest = set()
        for c in changed:
            for i, j in self.corners.get(c, ()):
                p, q = self.part_of(i), self.part_of(j)
                if p is keep and q is not keep:
                    retest.add(q)
                elif q is keep and p is not keep:
                    retest.add(p)
        for q in retest:
            self.note(keep, q, _convex_union(keep, q, self.quick))


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
