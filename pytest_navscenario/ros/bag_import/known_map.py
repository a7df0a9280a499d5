"""The bag's own map (``nav_msgs/OccupancyGrid`` on ``/map``) against what the sensors saw: the
obstacles that were not on the map that day are the likeliest cause of a failure, and are named.

When the map is in the seed's frame it is the seed's fixed background (``map_background``: its
occupied cells near the driven path, merged into polygons by the caller), and of what the sensors
saw only what the map does not have is kept: the search moves those.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...scenario.model import BoxObstacle, Obstacle


@dataclass
class KnownMap:
    """An occupancy grid: ``occupied`` (rows, cols) bool, cell size, origin (x, y, yaw) of cell (0, 0)."""
    frame: str
    topic: str
    occupied: np.ndarray
    resolution: float
    origin: tuple[float, float, float]


def from_message(msg, topic: str, threshold: int = 65) -> KnownMap:
    """A KnownMap from an OccupancyGrid message (cells >= ``threshold`` % are occupied)."""
    from .topics import yaw_of

    info = msg.info
    data = np.asarray(msg.data, dtype=np.int16).reshape(int(info.height), int(info.width))
    o = info.origin
    return KnownMap(frame=msg.header.frame_id.lstrip("/"), topic=topic, occupied=data >= threshold,
                    resolution=float(info.resolution), origin=(o.position.x, o.position.y, yaw_of(o.orientation)))


def on_map_share(m: KnownMap, obstacle: Obstacle, slack: int = 2) -> float:
    """The share of points on the obstacle's outline that lie within ``slack`` cells of an
    occupied map cell (the sensors see outlines; a wall's far side is rarely observed)."""
    from ...scenario.geometry import obstacle_polygon

    ring = obstacle_polygon(obstacle).exterior
    n = max(8, int(ring.length / (m.resolution / 2)))
    pts = np.array([ring.interpolate(i / n, normalized=True).coords[0] for i in range(n)])
    x0, y0, yaw = m.origin
    c, s = np.cos(-yaw), np.sin(-yaw)
    dx, dy = pts[:, 0] - x0, pts[:, 1] - y0
    col = np.floor((c * dx - s * dy) / m.resolution).astype(int)
    row = np.floor((s * dx + c * dy) / m.resolution).astype(int)
    h, w = m.occupied.shape
    hit = np.zeros(len(pts), bool)
    for dr in range(-slack, slack + 1):
        for dc in range(-slack, slack + 1):
            r, cc = row + dr, col + dc
            ok = (r >= 0) & (r < h) & (cc >= 0) & (cc < w)
            hit[ok] |= m.occupied[r[ok], cc[ok]]
    return float(hit.mean())


def not_on_map(m: KnownMap, obstacles: list[Obstacle], frame: str) -> tuple[list[Obstacle], str]:
    """The obstacles that the map does not have (less than half their outline on it), and a note."""
    if m.frame != frame:
        return [], (f"{m.topic} is in frame {m.frame!r} and the seed in {frame!r}: the obstacles are not "
                    f"compared with the map")
    new = [o for o in obstacles if on_map_share(m, o) < 0.5]
    h, w = m.occupied.shape
    head = f"{m.topic} ({w} x {h} cells of {m.resolution:g} m): "
    if not new:
        return [], head + f"all {len(obstacles)} obstacles are on the map"
    names = ", ".join(f"{o.name} at ({o.x:.2f}, {o.y:.2f})" for o in new[:12]) + (" ..." if len(new) > 12 else "")
    return new, (head + f"{len(new)} of {len(obstacles)} obstacles were not on the map that day (the likeliest "
                 f"cause of a failure): {names}")


def map_background(m: KnownMap, path_xy: np.ndarray, reach: float) -> list[BoxObstacle]:
    """Boxes (named ``map1``, ...) covering the map's occupied cells within ``reach`` of the driven
    path's bounding box: a building's map is far larger than what a seed needs."""
    import math

    from ..map_import import merge_rectangles

    x0, y0, yaw = m.origin
    c, s = math.cos(yaw), math.sin(yaw)
    lo, hi = path_xy.min(axis=0) - reach, path_xy.max(axis=0) + reach
    h, w = m.occupied.shape
    # the region's corners in cells: only that window of a large map is looked at
    corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [lo[0], hi[1]], [hi[0], hi[1]]]) - (x0, y0)
    cc = (c * corners[:, 0] + s * corners[:, 1]) / m.resolution
    rr = (-s * corners[:, 0] + c * corners[:, 1]) / m.resolution
    c0, c1 = max(int(np.floor(cc.min())), 0), min(int(np.ceil(cc.max())) + 1, w)
    r0, r1 = max(int(np.floor(rr.min())), 0), min(int(np.ceil(rr.max())) + 1, h)
    if not (c0 < c1 and r0 < r1):
        return []
    rows, cols = np.mgrid[r0:r1, c0:c1]
    lx, ly = (cols + 0.5) * m.resolution, (rows + 0.5) * m.resolution
    wx, wy = x0 + c * lx - s * ly, y0 + s * lx + c * ly
    window = m.occupied[r0:r1, c0:c1] & (wx >= lo[0]) & (wx <= hi[0]) & (wy >= lo[1]) & (wy <= hi[1])
    boxes = []
    for i, (r, col, nr, nc) in enumerate(((r + r0, col + c0, nr, nc) for r, col, nr, nc in merge_rectangles(window)), 1):
        bx, by = (col + nc / 2.0) * m.resolution, (r + nr / 2.0) * m.resolution   # row 0 at the origin
        boxes.append(BoxObstacle(name=f"map{i}", x=round(x0 + c * bx - s * by, 4) + 0.0,
                                 y=round(y0 + s * bx + c * by, 4) + 0.0, length=round(nc * m.resolution, 4),
                                 width=round(nr * m.resolution, 4), yaw=round(math.degrees(yaw), 3) + 0.0))
    return boxes
