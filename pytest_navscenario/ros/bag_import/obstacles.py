"""Clustering the occupied cells and fitting obstacles: cylinders for round clusters, one box for
a compact block, else the cluster's outline as few simplified polygons (outline.py): a wall is one
thin polygon along it, not a fan of boxes."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ...scenario.model import BoxObstacle, CylinderObstacle, Obstacle, PolygonObstacle
from .outline import cell_outlines
from .projection import Grid


@dataclass
class Cluster:
    points: np.ndarray    # (k, 2) per-cell mean of the returns
    viewpoint: np.ndarray  # (2,) mean laser position that saw them
    height: float | None = None  # m, highest return above the ground (3D sensors), else None
    cells: np.ndarray | None = None   # (k, 2) the cells (column, row), for the outline
    views: np.ndarray | None = None   # (k, 2) where each cell was seen from (mean laser position)


def occupied_clusters(grid: Grid, *, min_hits: int = 2, link: float = 0.3, min_cells: int = 3,
                      occupied: np.ndarray | None = None) -> tuple[list[Cluster], int]:
    """Keep cells hit ``min_hits`` times (and, given ``occupied`` (k,) bool per cell of ``grid``,
    only those: the occupancy grid's verdict after free space was carved), group cells closer than
    ``link`` (sparse beams leave gaps along a far face; a robot does not fit through ``link`` anyway).

    Returns the clusters and the number of small clusters (< ``min_cells``) dropped as noise.
    """
    kept = grid.counts >= min_hits
    if occupied is not None:
        kept &= occupied
    means = grid.means[kept]
    cells = grid.cells[kept] if grid.keys is not None else None
    top = grid.top[kept] if grid.top is not None else None
    clusters, dropped = [], 0
    for members in _groups(means[:, :2], link):
        if len(members) < min_cells:
            dropped += 1
            continue
        m = means[members]
        height = float(np.nanmax(top[members])) if top is not None and np.isfinite(top[members]).any() else None
        clusters.append(Cluster(points=m[:, :2], viewpoint=m[:, 2:].mean(axis=0), height=height,
                                cells=None if cells is None else cells[members], views=m[:, 2:]))
    return clusters, dropped


def _groups(points: np.ndarray, radius: float) -> list[np.ndarray]:
    """Index arrays of the groups of points chained by neighbours closer than ``radius``."""
    if len(points) == 0:
        return []
    cells = np.floor(points / radius).astype(np.int64)
    buckets: dict[tuple[int, int], list[int]] = {}
    for i, (a, b) in enumerate(cells):
        buckets.setdefault((int(a), int(b)), []).append(i)
    label = -np.ones(len(points), dtype=np.int64)
    groups = []
    for seed in range(len(points)):
        if label[seed] >= 0:
            continue
        label[seed] = seed
        stack, members = [seed], []
        while stack:
            i = stack.pop()
            members.append(i)
            a, b = cells[i]
            for da in (-1, 0, 1):
                for db in (-1, 0, 1):
                    for j in buckets.get((int(a + da), int(b + db)), ()):
                        if label[j] < 0 and np.hypot(*(points[j] - points[i])) <= radius:
                            label[j] = seed
                            stack.append(j)
        groups.append(np.sort(np.array(members)))
    return groups


def fit_circle(points: np.ndarray) -> tuple[float, float, float, float]:
    """Least-squares (Kasa) circle: centre x, y, radius and the RMS radial residual."""
    a = np.c_[2.0 * points, np.ones(len(points))]
    b = (points ** 2).sum(axis=1)
    (cx, cy, c), *_ = np.linalg.lstsq(a, b, rcond=None)
    r = math.sqrt(max(c + cx * cx + cy * cy, 0.0))
    resid = np.hypot(points[:, 0] - cx, points[:, 1] - cy) - r
    return float(cx), float(cy), r, float(np.sqrt(np.mean(resid ** 2)))


@dataclass(frozen=True)
class FitSettings:
    res: float = 0.05             # m, grid cell
    max_radius: float = 0.6       # m, largest round obstacle fitted as a cylinder
    circle_rms: float = 0.025     # m, max RMS residual of a cylinder fit
    max_block: float = 2.5        # m, longest side of a cluster fitted as one solid box
    link: float = 0.3             # m, returns closer than this belong to one obstacle
    wall_depth: float = 0.15      # m, a wall's outline reaches this far behind its seen face


def _round(points: np.ndarray, s: FitSettings) -> tuple[float, float, float] | None:
    if len(points) < 5:
        return None
    cx, cy, r, rms = fit_circle(points)
    if not (0.02 <= r <= s.max_radius) or rms > max(s.circle_rms, 0.1 * r):
        return None
    # the returns must wrap around the centre, not be a nearly straight piece of wall
    cov = np.cov((points - points.mean(axis=0)).T)
    ev = np.linalg.eigvalsh(cov)
    if ev[0] < 0.05 * ev[1]:
        return None
    return cx, cy, r


def _r(v: float, nd: int = 3) -> float:
    return float(round(float(v), nd)) + 0.0


def _compact_box(points: np.ndarray, free_xy: np.ndarray | None, s: FitSettings) -> BoxObstacle | None:
    """One oriented box for a cluster that outlines a solid block seen from two or more sides:
    its minimum rotated rectangle is small, thick, hugged by the returns and holds no pose the
    robot drove through (so a corner of walls around the robot is not filled in)."""
    import shapely
    from shapely.geometry import MultiPoint

    if len(points) < 6:
        return None
    rect = MultiPoint(points).minimum_rotated_rectangle
    if rect.geom_type != "Polygon":
        return None
    xy = np.asarray(rect.exterior.coords)[:4]
    e1, e2 = xy[1] - xy[0], xy[2] - xy[1]
    a, b = float(np.hypot(*e1)), float(np.hypot(*e2))
    if min(a, b) < 3 * s.res or max(a, b) > s.max_block:
        return None
    if np.mean(shapely.distance(rect.exterior, shapely.points(points))) > s.res:
        return None
    if free_xy is not None and len(free_xy) and shapely.contains_xy(rect, free_xy[:, 0], free_xy[:, 1]).any():
        return None
    d = e1 if a >= b else e2
    yaw = (math.degrees(math.atan2(d[1], d[0])) + 90.0) % 180.0 - 90.0
    c = xy.mean(axis=0)
    return BoxObstacle(name="", x=_r(c[0]), y=_r(c[1]), length=_r(max(a, b)), width=_r(min(a, b)), yaw=_r(yaw, 2))


def fit_obstacles(clusters: list[Cluster], s: FitSettings = FitSettings(),
                  free_xy: np.ndarray | None = None, seen_free=None) -> list[Obstacle]:
    """Cylinders for round clusters, one box for a compact block, else the cluster's outline as
    simplified wall polygons. ``free_xy``: positions the robot drove through; ``seen_free(columns,
    rows)``: which cells the beams saw free (a wall's outline stays out of them)."""
    obstacles: list[Obstacle] = []
    for cl in sorted(clusters, key=lambda c: (round(float(c.points[:, 0].mean()), 3),
                                               round(float(c.points[:, 1].mean()), 3))):
        fitted = _fit_cluster(cl, s, free_xy, seen_free)
        if cl.height is not None:  # a 3D sensor saw how tall it is (a low obstacle keeps its height)
            fitted = [dataclasses.replace(o, height=_r(max(cl.height, 0.02), 2)) for o in fitted]
        obstacles.extend(fitted)
    kept = _drop_contained(obstacles)
    counts: dict[str, int] = {}
    named = []
    for o in kept:  # number each kind 1, 2, ... again after the drop
        prefix = o.name.rstrip("0123456789")
        counts[prefix] = counts.get(prefix, 0) + 1
        named.append(dataclasses.replace(o, name=f"{prefix}{counts[prefix]}"))
    return named


def _fit_cluster(cl: Cluster, s: FitSettings, free_xy: np.ndarray | None, seen_free=None) -> list[Obstacle]:
    """A cylinder, one compact box, or the cluster's outline as simplified polygons (numbered per
    cluster; the caller numbers them again)."""
    circle = _round(cl.points, s)
    if circle is not None:
        return [CylinderObstacle(name="pillar", x=_r(circle[0]), y=_r(circle[1]), radius=_r(circle[2]))]
    block = _compact_box(cl.points, free_xy, s)
    if block is not None:
        return [dataclasses.replace(block, name="box")]
    cells = cl.cells if cl.cells is not None else np.unique(np.floor(cl.points / s.res).astype(np.int64), axis=0)
    views = cl.views if cl.views is not None and cl.cells is not None else None
    return [_polygon("wall", poly) for poly in cell_outlines(cells, s.res, link=s.link, viewpoints=views,
                                                             depth=s.wall_depth, seen_free=seen_free,
                                                             points=cl.points if cl.cells is not None else None)]


def _polygon(name: str, poly) -> PolygonObstacle:
    """A polygon obstacle placed at the outline's centroid, its corners relative to it."""
    c = poly.centroid
    pts = tuple((_r(x - c.x), _r(y - c.y)) for x, y in list(poly.exterior.coords)[:-1])
    return PolygonObstacle(name=name, x=_r(c.x), y=_r(c.y), points=pts)


def _drop_contained(obstacles: list[Obstacle], share: float = 0.5) -> list[Obstacle]:
    """Leave out a piece that lies mostly (``share`` of its area or more) inside a larger obstacle: the
    stray returns at a block's corner otherwise become a sliver stuck to the block."""
    from ...scenario.geometry import obstacle_polygon

    polys = [obstacle_polygon(o) for o in obstacles]
    keep = []
    for i, (o, p) in enumerate(zip(obstacles, polys)):
        inside = any(j != i and q.area > p.area and p.intersection(q).area >= share * p.area
                     for j, q in enumerate(polys))
        if not inside:
            keep.append(o)
    return keep


