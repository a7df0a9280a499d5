"""Keeping a seed from a bag small enough to search: neighbouring obstacles merged into simplified
polygons, and the obstacles split into the searchable ones near the driven path and a fixed
background (``search: {frozen: [...]}``) that the search does not move."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ...scenario.model import Obstacle, PolygonObstacle
from .obstacles import _r


@dataclass(frozen=True)
class SeedSize:
    merge_gap: float = 0.3        # m, obstacles closer than this become one polygon (the robot cannot pass)
    tolerance: float = 0.05       # m, a merged outline follows its parts within this (Douglas-Peucker)
    height_step: float = 0.1      # m, obstacles differing more in height are not merged (a low one stays low)
    near: float = 1.0             # m, obstacles this close to the driven path (beyond the footprint) are searchable
    max_searchable: int = 12      # the closest ones only: a search over more is slow to find anything
    map_reach: float = 3.0        # m, the bag's /map is kept this far around the driven path's bounding box


def _height(o: Obstacle) -> float:
    return float(getattr(o, "height", 1.0))


def _components(n: int, pairs) -> list[list[int]]:
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i
    for i, j in pairs:
        parent[root(i)] = root(j)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)
    return sorted(groups.values())


def merge_neighbours(obstacles: list[Obstacle], free_xy: np.ndarray | None,
                     s: SeedSize = SeedSize(), clearance: float = 0.0) -> tuple[list[Obstacle], int]:
    """Merge obstacles closer than ``s.merge_gap`` (and of about the same height) into one
    simplified polygon each. A group stays as it was when its outline would enclose a hole (walls
    around a room), fall apart, or come within ``clearance`` (the footprint) of a pose the robot
    drove through that its parts kept clear of. Returns the obstacles (polygons named
    ``outline1``, ...) and how many were merged away."""
    import shapely
    from shapely.geometry import Polygon

    from ...scenario.geometry import obstacle_polygon, polygon_problem

    if len(obstacles) < 2:
        return list(obstacles), 0
    polys = np.array([obstacle_polygon(o) for o in obstacles], dtype=object)
    tree = shapely.STRtree(polys)
    left, right = tree.query(polys, predicate="dwithin", distance=s.merge_gap)
    pairs = [(int(i), int(j)) for i, j in zip(left, right)
             if i < j and abs(_height(obstacles[i]) - _height(obstacles[j])) <= s.height_step]
    out: list[Obstacle] = []
    merged = 0
    free = shapely.points(free_xy) if free_xy is not None and len(free_xy) else None
    for group in _components(len(obstacles), pairs):
        members = [obstacles[i] for i in group]
        if len(group) > 1:
            half = s.merge_gap / 2
            u = shapely.unary_union([polys[i].buffer(half, join_style="mitre") for i in group])
            u = u.buffer(-half, join_style="mitre").simplify(s.tolerance, preserve_topology=True)
            ok = isinstance(u, Polygon) and not u.interiors and u.is_valid
            if ok and free is not None:
                before = min(float(shapely.distance(polys[i], free).min()) for i in group)
                ok = float(shapely.distance(u, free).min()) >= min(before, clearance) - 1e-3
            if ok:
                c = u.centroid
                pts = tuple((_r(x - c.x), _r(y - c.y)) for x, y in list(u.exterior.coords)[:-1])
                if polygon_problem(pts) is None:
                    out.append(PolygonObstacle(name="outline", x=_r(c.x), y=_r(c.y), points=pts,
                                               height=_r(max(_height(o) for o in members), 2)))
                    merged += len(group) - 1
                    continue
        out.extend(members)
    return _renumber(out), merged


def _renumber(obstacles: list[Obstacle]) -> list[Obstacle]:
    counts: dict[str, int] = {}
    named = []
    for o in obstacles:
        prefix = o.name.rstrip("0123456789")
        counts[prefix] = counts.get(prefix, 0) + 1
        named.append(dataclasses.replace(o, name=f"{prefix}{counts[prefix]}"))
    return named


def split_near_path(obstacles: list[Obstacle], path_xy: np.ndarray, radius: float,
                    s: SeedSize = SeedSize()) -> tuple[list[str], list[str]]:
    """The names of the searchable obstacles (within ``radius + s.near`` of the driven path, the
    ``s.max_searchable`` closest) and of the fixed background (the rest), in seed order."""
    import shapely
    from shapely.geometry import LineString, Point

    from ...scenario.geometry import obstacle_polygon

    if not obstacles:
        return [], []
    line = LineString(path_xy) if len(path_xy) > 1 else Point(path_xy[0])
    dist = shapely.distance(np.array([obstacle_polygon(o) for o in obstacles], dtype=object), line)
    near = [i for i in np.argsort(dist, kind="stable") if dist[i] <= radius + s.near][:s.max_searchable]
    keep = set(int(i) for i in near)
    return ([o.name for i, o in enumerate(obstacles) if i in keep],
            [o.name for i, o in enumerate(obstacles) if i not in keep])
