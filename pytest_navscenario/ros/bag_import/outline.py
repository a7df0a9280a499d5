"""Walls as walls: the outline of a group of occupied cells as few simplified polygons.

The cells are closed over gaps narrower than ``link`` (sparse beams leave gaps along a far wall; a
robot does not fit through them anyway), outlined by marching squares (contourpy, the contouring
library matplotlib draws with) and simplified (shapely, Douglas-Peucker within ``tolerance``), so a
wall seen along a corridor is one thin polygon that follows it, not a fan of slivers. A group that
closes into a ring around where the robot drove (the walls of a room) is cut across each hole:
a scenario polygon has no holes.
"""
from __future__ import annotations

import math

import numpy as np


def _shift_any(mask: np.ndarray, h: int, axis: int, combine) -> np.ndarray:
    """``combine`` (or / and) of ``mask`` shifted by -h..h along ``axis`` (a square element, separably)."""
    out = mask.copy()
    n = mask.shape[axis]
    for d in range(1, h + 1):
        for sign in (1, -1):
            src = [slice(None)] * 2
            dst = [slice(None)] * 2
            if sign > 0:
                src[axis], dst[axis] = slice(0, n - d), slice(d, n)
            else:
                src[axis], dst[axis] = slice(d, n), slice(0, n - d)
            part = out[tuple(dst)]
            shifted = mask[tuple(src)]
            if combine is np.logical_and:   # outside the mask counts as empty
                part &= shifted
            else:
                part |= shifted
        if combine is np.logical_and:
            edge = [slice(None)] * 2
            edge[axis] = slice(0, min(h, n))
            out[tuple(edge)] = False
            edge[axis] = slice(max(n - h, 0), n)
            out[tuple(edge)] = False
    return out


def close_cells(mask: np.ndarray, h: int) -> np.ndarray:
    """Morphological closing of ``mask`` by a (2h+1)-cell square: gaps up to 2h cells filled."""
    if h <= 0:
        return mask
    grown = _shift_any(_shift_any(mask, h, 0, np.logical_or), h, 1, np.logical_or)
    return _shift_any(_shift_any(grown, h, 0, np.logical_and), h, 1, np.logical_and)


def cell_outlines(cells: np.ndarray, res: float, link: float = 0.3, tolerance: float | None = None,
                  viewpoints: np.ndarray | None = None, depth: float = 0.15, seen_free=None,
                  points: np.ndarray | None = None) -> list:
    """Simplified shapely polygons (without holes) outlining the cells ``cells`` ((k, 2) column,
    row; cell (c, r) spans [c res, (c + 1) res] x [r res, (r + 1) res]).

    With ``points`` ((k, 2) the mean return in each cell) the outline is drawn on a grid twice as
    fine, through the returns themselves (a wall's face where it was seen, not up to a cell in
    front of it). A lidar sees only the near face of a wall: with ``viewpoints`` ((k, 2) where each
    cell was seen from), every cell is extended ``depth`` metres away from its viewpoint, so the
    outline is a wall of some thickness whose near face lies where the returns were (not a needle
    that simplifying would cut through); ``seen_free(columns, rows)`` (bool per cell of ``res``)
    keeps the extension out of space the beams saw free."""
    import contourpy
    import shapely
    from shapely.geometry import Polygon

    if not len(cells):
        return []
    tolerance = 0.75 * res if tolerance is None else tolerance
    if points is not None:      # on a grid twice as fine, from the returns
        fine = res / 2
        cells = np.floor(points / fine).astype(np.int64)
        coarse = seen_free
        seen_free = None if coarse is None else (lambda c, r: coarse(c // 2, r // 2))
        res = fine
    if viewpoints is not None and depth > 0:
        cells = _extended(cells, viewpoints, res, depth, seen_free)
    h = max(int(math.ceil(link / (2 * res))), 0)
    pad = h + 2
    lo = cells.min(axis=0) - pad
    shape = cells.max(axis=0) - lo + pad + 1
    mask = np.zeros((shape[1], shape[0]), bool)
    mask[cells[:, 1] - lo[1], cells[:, 0] - lo[0]] = True
    z = close_cells(mask, h).astype(np.float64)
    x = (lo[0] + np.arange(shape[0]) + 0.5) * res
    y = (lo[1] + np.arange(shape[1]) + 0.5) * res
    gen = contourpy.contour_generator(x, y, z, name="serial", fill_type="OuterOffset")
    pts, offsets = gen.filled(0.5, 2.0)
    polys = []
    for ring_pts, off in zip(pts, offsets):
        rings = [ring_pts[a:b] for a, b in zip(off[:-1], off[1:])]
        poly = shapely.make_valid(Polygon(rings[0], rings[1:]))
        polys.extend(_polygons(poly))
    out = []
    for poly in polys:
        simple = poly.simplify(tolerance, preserve_topology=True)
        for piece in _without_holes(simple):
            piece = piece.simplify(tolerance * 0.5, preserve_topology=True)
            if piece.is_valid and piece.area > 4 * res * res:
                out.append(piece)
    return out


def _extended(cells: np.ndarray, viewpoints: np.ndarray, res: float, depth: float, seen_free) -> np.ndarray:
    """The cells plus, for each, the cells up to ``depth`` behind it as seen from its viewpoint
    (sampled every half cell), except those ``seen_free``."""
    centre = (cells + 0.5) * res
    if len(viewpoints) != len(cells):
        raise ValueError("one viewpoint per cell")
    away = centre - viewpoints
    norm = np.hypot(away[:, 0], away[:, 1])
    away = away / np.where(norm > 0, norm, 1.0)[:, None]
    steps = np.arange(1, int(math.ceil(depth / (0.5 * res))) + 1) * (0.5 * res)
    pts = centre[:, None, :] + steps[None, :, None] * away[:, None, :]
    extra = np.floor(pts.reshape(-1, 2) / res).astype(np.int64)
    if seen_free is not None and len(extra):
        extra = extra[~seen_free(extra[:, 0], extra[:, 1])]
    return np.unique(np.concatenate([cells, extra]), axis=0)


def _polygons(geom) -> list:
    """The polygons of a (multi)polygon or collection."""
    if geom.geom_type == "Polygon":
        return [geom] if not geom.is_empty else []
    return [p for g in getattr(geom, "geoms", []) for p in _polygons(g)]


def _without_holes(poly) -> list:
    """``poly`` cut across each of its holes (through the hole, parallel to the polygon's longer
    side) into pieces that have none."""
    from shapely.geometry import LineString
    from shapely.ops import split

    if not poly.interiors:
        return [poly]
    hole = poly.interiors[0]
    cx, cy = hole.centroid.x, hole.centroid.y
    x0, y0, x1, y1 = poly.bounds
    if x1 - x0 >= y1 - y0:     # cut across the longer extent: a vertical line
        line = LineString([(cx, y0 - 1), (cx, y1 + 1)])
    else:
        line = LineString([(x0 - 1, cy), (x1 + 1, cy)])
    pieces = [p for g in split(poly, line).geoms for p in _polygons(g)]
    if len(pieces) < 2:        # the line missed (a degenerate hole): drop the hole instead
        from shapely.geometry import Polygon
        return _without_holes(Polygon(poly.exterior, poly.interiors[1:]))
    return [q for p in pieces for q in _without_holes(p)]
