"""The ground a 3D lidar saw, kept as terrain in the seed: ramps, steps, platforms and drop-offs
the obstacle band (clouds.py) would otherwise drop or mistake for obstacles.

Every cloud the band uses also goes into a ground map: its points in the world frame with the
robot's full pose (the odometry's height, roll and pitch, ``BagData.odom_up``; a planar odometry
leaves the robot level at z = 0, and says so), and per cell of ``res`` metres the lowest return,
averaged over the clouds that saw it. Then:

* the floor is the ground around the start (the seed's z = 0);
* ground seen from above (a cell whose returns span at most ``SURFACE`` in height: not a face of
  something) raised above the floor by more than ``TOLERANCE`` forms regions; a region the robot
  drove over, or that meets the floor gently somewhere along its edge (a ramp's foot), is terrain, kept as one heightfield over all such regions (a 16-bit PNG beside the seed);
  a raised block with steep sides all round that the robot never drove on is left to the
  obstacles (a crate and a loading dock look alike to a lidar: that is the guess);
* ground more than ``HOLE`` below the floor forms holes, each a pit (the rotated rectangle
  around it, the median depth seen);
* obstacles the band fitted over the kept raised regions (the slope of a ramp, a step's riser)
  are dropped: they were the ground.

Unseen cells within a region's outline take their seen neighbours' heights; the rest of the
heightfield's box is the floor. Every guess is in the notes.
"""
from __future__ import annotations

import io
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

TOLERANCE = 0.05      # m: ground this far from the floor is the floor (lidar noise, a rough floor)
HOLE = 0.10           # m below the floor: a hole
GENTLE = 0.08         # m: a region whose edge meets the floor within this somewhere can be driven onto
SURFACE = 0.10        # m: a cell whose returns span more than this in height is a face, not ground
START_RADIUS = 0.8    # m: the floor is the ground seen this close to the start


class GroundMap:
    """The lowest return per cell (world frame), averaged over the clouds that saw the cell, and
    the highest: a cell whose returns span little height is ground seen from above; one that
    spans much is a face (a wall, a crate's side, a step's riser)."""

    def __init__(self, res: float):
        self.res = float(res)
        self.sum: dict[tuple[int, int], float] = {}
        self.count: dict[tuple[int, int], int] = {}
        self.high: dict[tuple[int, int], float] = {}
        self.clouds = 0

    def add(self, world: np.ndarray) -> None:
        """One cloud's points (k, 3), world frame."""
        if not len(world):
            return
        ij = np.floor(world[:, :2] / self.res).astype(np.int64)
        key = ij[:, 0] * 2_000_003 + ij[:, 1]
        order = np.lexsort((world[:, 2], key))
        key, z, ij = key[order], world[order, 2], ij[order]
        first = np.r_[True, key[1:] != key[:-1]]          # sorted by cell, then height: its lowest
        last = np.r_[key[1:] != key[:-1], True]           # and its highest
        for (i, j), low, top in zip(ij[first].tolist(), z[first].tolist(), z[last].tolist()):
            cell = (i, j)
            self.sum[cell] = self.sum.get(cell, 0.0) + low
            self.count[cell] = self.count.get(cell, 0) + 1
            self.high[cell] = max(self.high.get(cell, -math.inf), top)
        self.clouds += 1

    def grid(self) -> tuple[np.ndarray, np.ndarray, float, float]:
        """(lowest heights (ny, nx), NaN unseen; the height the returns span in each cell; x, y of
        cell (0, 0)'s corner)."""
        if not self.sum:
            return np.full((0, 0), np.nan), np.full((0, 0), np.nan), 0.0, 0.0
        cells = np.array(list(self.sum), dtype=np.int64)
        i0, j0 = cells.min(axis=0)
        i1, j1 = cells.max(axis=0)
        out = np.full((j1 - j0 + 1, i1 - i0 + 1), np.nan)
        span = np.full(out.shape, np.nan)
        for (i, j), total in self.sum.items():
            low = total / self.count[(i, j)]
            out[j - j0, i - i0] = low
            span[j - j0, i - i0] = self.high[(i, j)] - low
        return out, span, i0 * self.res, j0 * self.res


@dataclass
class TerrainGuess:
    elements: list = field(default_factory=list)          # Heightfield and Pit elements
    files: dict[str, bytes] = field(default_factory=dict)  # beside the seed
    raised: Any = None                                     # shapely geometry of the kept raised regions
    floor: float = 0.0                                     # the floor's height in the world frame
    notes: list[str] = field(default_factory=list)


def terrain_from_ground(gmap: GroundMap, start: tuple[float, float], path_xy: np.ndarray,
                        name: str = "ground") -> TerrainGuess:
    """The terrain in the ground map (see the module docstring): the floor, the raised regions the
    robot drove on or can drive onto as one heightfield, the holes beside the path as pits."""
    import shapely

    out = TerrainGuess()
    heights, span, x0, y0 = gmap.grid()
    res = gmap.res
    if not heights.size or not np.isfinite(heights).any():
        return out
    ny, nx = heights.shape
    cx = x0 + (np.arange(nx) + 0.5) * res
    cy = y0 + (np.arange(ny) + 0.5) * res
    gx, gy = np.meshgrid(cx, cy)
    seen = np.isfinite(heights)
    out.floor = _floor(out, gmap, heights, seen, gx, gy, start)
    cells = _Cells(heights - out.floor, span, seen, gx, gy, x0, y0, res)
    path = shapely.LineString(path_xy) if len(path_xy) >= 2 else shapely.Point(start)
    kept = _raised_regions(out, cells, path)
    if kept:
        _add_heightfield(out, cells, kept, name)
    _add_pits(out, cells, path, name)
    return out


@dataclass
class _Cells:
    """The ground map's grid against the floor: heights above it (``rel``, NaN where unseen), the
    returns' height spans, which cells were seen, the cells' centres, the grid's corner and cell size."""
    rel: np.ndarray
    span: np.ndarray
    seen: np.ndarray
    gx: np.ndarray
    gy: np.ndarray
    x0: float
    y0: float
    res: float

    def regions(self, mask: np.ndarray) -> list:
        """The connected regions of the cells in ``mask``, of 4 cells or more, as shapely polygons."""
        import shapely
        from shapely.geometry import box

        x0, y0, res = self.x0, self.y0, self.res
        cells = [box(x0 + i * res, y0 + j * res, x0 + (i + 1) * res, y0 + (j + 1) * res)
                 for j, i in zip(*np.nonzero(mask))]
        if not cells:
            return []
        merged = shapely.union_all(cells)
        return [g for g in getattr(merged, "geoms", [merged]) if g.area >= 4 * res * res]


def _floor(out: TerrainGuess, gmap: GroundMap, heights: np.ndarray, seen: np.ndarray, gx: np.ndarray,
           gy: np.ndarray, start: tuple[float, float]) -> float:
    """The floor's height in the world frame: the ground around the start, else the height seen most often."""
    near = seen & (np.hypot(gx - start[0], gy - start[1]) <= START_RADIUS)
    floor = float(np.median(heights[near])) if near.sum() >= 5 else _mode(heights[seen])
    out.notes.append(f"ground: {int(seen.sum())} cells of {gmap.res:g} m seen by {gmap.clouds} cloud(s); the floor "
                     f"(z = 0 in the seed) is the ground "
                     + ("around the start" if near.sum() >= 5 else "seen most often")
                     + f", z={floor:.2f} m in the world frame")
    return floor


def _raised_regions(out: TerrainGuess, cells: _Cells, path: Any) -> list:
    """The raised regions seen from above that the robot drove on or can drive onto (an edge meets
    the floor gently somewhere); the others (steep all round: crates, docks) are left to the obstacles."""
    kept, dropped = [], 0
    for region in cells.regions(cells.seen & (cells.rel > TOLERANCE) & (cells.span <= SURFACE)):
        gentle = bool(np.any(_edge_steps(region, cells.rel, cells.gx, cells.gy, cells.res) <= GENTLE))
        if path.intersects(region) or gentle:
            kept.append(region)
        else:
            dropped += 1
    if dropped:
        out.notes.append(f"ground: {dropped} raised region(s) with steep sides all round that the robot never drove "
                         f"on are left to the obstacles (a crate and a dock look alike to a lidar)")
    return kept


def _add_heightfield(out: TerrainGuess, cells: _Cells, kept: list, name: str) -> None:
    """The kept raised regions as one heightfield (its PNG in ``out.files``), unseen cells inside
    them filled from their seen neighbours, the rest of its box the floor."""
    import shapely

    from ...scenario.terrain import Heightfield

    rel, gx, gy, x0, y0, res = cells.rel, cells.gx, cells.gy, cells.x0, cells.y0, cells.res
    ny, nx = rel.shape
    out.raised = shapely.union_all(kept)
    bx0, by0, bx1, by1 = out.raised.bounds
    bx0, by0, bx1, by1 = bx0 - res, by0 - res, bx1 + res, by1 + res
    i0, i1 = int(round((bx0 - x0) / res)), int(round((bx1 - x0) / res))
    j0, j1 = int(round((by0 - y0) / res)), int(round((by1 - y0) / res))
    sub = np.zeros((j1 - j0, i1 - i0))
    si0, sj0 = max(i0, 0), max(j0, 0)
    si1, sj1 = min(i1, nx), min(j1, ny)
    window = rel[sj0:sj1, si0:si1]
    wx, wy = gx[sj0:sj1, si0:si1], gy[sj0:sj1, si0:si1]
    mask = shapely.contains_xy(out.raised.buffer(res * 0.01), wx, wy)
    # the regions' outlines filled: cells in them the lidar did not see (the far part of a
    # dock's top) take their seen neighbours' heights
    outline = shapely.union_all([shapely.Polygon(r.exterior) for r in kept]).buffer(res * 0.01)
    filled = _fill(np.where(mask, window, np.nan), shapely.contains_xy(outline, wx, wy))
    sub[sj0 - j0:sj1 - j0, si0 - i0:si1 - i0] = np.clip(np.nan_to_num(filled, nan=0.0), 0, None)
    top = float(sub.max())
    file = f"terrain/{name}.png"
    out.files[file] = _png16(sub, top)
    rows, cols = sub.shape
    out.elements.append(Heightfield(name=name, x=_r((bx0 + bx1) / 2), y=_r((by0 + by1) / 2), file=file,
                                    length=_r((cols - 1) * res), width=_r((rows - 1) * res),
                                    min_height=0.0, max_height=_r(top)))
    # the heightfield's samples are the cells' centres: its extent is one cell less each way
    out.notes.append(f"ground: {len(kept)} raised region(s) the robot drove on or can drive onto (up to "
                     f"{top:.2f} m above the floor) -> heightfield '{name}' ({file}, {cols} x {rows} samples of "
                     f"{res:g} m); unseen cells within the regions take their neighbours' heights, the "
                     f"rest of its box is the floor")


def _add_pits(out: TerrainGuess, cells: _Cells, path: Any, name: str) -> None:
    """Each hole seen below the floor, off the driven path, as a pit (its rotated rectangle, its
    bottom the lowest tenth seen in it)."""
    import shapely

    from ...scenario.terrain import Pit

    rel, seen, res = cells.rel, cells.seen, cells.res
    for k, region in enumerate(cells.regions(seen & (rel < -HOLE))):
        rect = region.minimum_rotated_rectangle
        corners = np.asarray(rect.exterior.coords)[:4]
        e1, e2 = corners[1] - corners[0], corners[2] - corners[1]
        length, width = float(np.hypot(*e1)), float(np.hypot(*e2))
        yaw = math.degrees(math.atan2(e1[1], e1[0]))
        inside = shapely.contains_xy(region, cells.gx, cells.gy) & seen
        # its bottom: the lowest tenth of what was seen in it (the rest is its walls)
        depth = float(-np.percentile(rel[inside], 10)) if inside.any() else HOLE
        centre = rect.centroid
        if path.intersects(region.buffer(-res)):
            out.notes.append(f"ground: a hole at ({centre.x:.1f}, {centre.y:.1f}) lies on the driven path: the robot "
                             f"drove through it, so it is not a hole (left out; check the odometry's height)")
            continue
        pit = Pit(name=f"{name}-hole{k + 1}", x=_r(centre.x), y=_r(centre.y), length=_r(length), width=_r(width),
                  depth=_r(depth), yaw=_r(yaw, 2))
        out.elements.append(pit)
        out.notes.append(f"ground: a hole {length:.1f} x {width:.1f} m, {depth:.2f} m deep (the lowest tenth seen) -> "
                         f"pit '{pit.name}': the part the lidar saw into (an edge hides the ground right behind it), "
                         f"as its rotated rectangle")


def _edge_steps(region: Any, rel: np.ndarray, gx: np.ndarray, gy: np.ndarray, res: float) -> np.ndarray:
    """The heights of the region's cells that touch its edge: a ramp's foot is low, a crate's edge
    is its full height."""
    import shapely

    rim = region.difference(region.buffer(-res * 1.01))
    inside = shapely.contains_xy(rim, gx, gy) & np.isfinite(rel)
    return rel[inside] if inside.any() else np.array([np.inf])


def _fill(values: np.ndarray, inside: np.ndarray, rounds: int = 200) -> np.ndarray:
    """``values`` with its NaN cells where ``inside`` filled from their filled 4-neighbours (their
    mean), ring by ring inwards."""
    out = values.copy()
    for _ in range(rounds):
        todo = np.isnan(out) & inside
        if not todo.any():
            break
        pad = np.pad(out, 1, constant_values=np.nan)
        near = np.stack([pad[:-2, 1:-1], pad[2:, 1:-1], pad[1:-1, :-2], pad[1:-1, 2:]])
        count = np.isfinite(near).sum(axis=0)
        mean = np.nansum(near, axis=0) / np.maximum(count, 1)
        grow = todo & (count > 0)
        if not grow.any():
            break
        out[grow] = mean[grow]
    return out


def _mode(values: np.ndarray) -> float:
    """The most common height (2 cm bins)."""
    lo = np.floor(values.min() / 0.02)
    counts = np.bincount((np.floor(values / 0.02) - lo).astype(np.int64))
    k = int(np.argmax(counts))
    band = values[(values >= (lo + k) * 0.02) & (values < (lo + k + 1) * 0.02)]
    return float(np.median(band))


def _png16(heights: np.ndarray, top: float) -> bytes:
    """A 16-bit greyscale PNG of ``heights`` (0 black, ``top`` white), its first row the +y edge."""
    from PIL import Image

    scaled = np.zeros_like(heights) if top <= 0 else heights / top
    img = np.round(np.clip(scaled, 0.0, 1.0) * 65535).astype(np.uint16)[::-1]
    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    return buf.getvalue()


def drop_ground_obstacles(obstacles: list, raised: Any, notes: list[str]) -> list:
    """The obstacles not explained by the kept raised ground: one mostly (half its area or more)
    over it was the ground seen in the band (a ramp's slope, a step's riser)."""
    if raised is None:
        return obstacles
    from ...scenario.geometry import obstacle_polygon

    keep, gone = [], []
    near = raised.buffer(0.25)          # a riser's outline lies on the region's edge, half outside
    for obs in obstacles:
        poly = obstacle_polygon(obs)
        if poly.area > 0 and poly.intersection(near).area >= 0.5 * poly.area:
            gone.append(obs.name)
        else:
            keep.append(obs)
    if gone:
        notes.append(f"ground: {len(gone)} obstacle(s) over the kept raised ground were that ground seen in the "
                     f"obstacle band, dropped: {', '.join(gone[:8])}{' ...' if len(gone) > 8 else ''}")
    return keep


def _r(v: float, nd: int = 3) -> float:
    return float(round(float(v), nd)) + 0.0
