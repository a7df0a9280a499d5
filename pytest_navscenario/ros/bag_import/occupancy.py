"""An occupancy grid in log-odds, as a mapping package keeps one (gmapping, slam_toolbox, OctoMap):
every beam adds evidence of free space along its way and of an obstacle where it ended, so a cell
where a smeared return (or a person who walked on) landed once is cleared by the later beams that
pass through it.

Each cell holds ``log(p / (1 - p))``: a return adds ``HIT``, a beam through it adds ``FREE``, and the
sum is kept within ``[LOW, HIGH]`` after every batch of scans (a part of one for long beams) (so recent evidence can still change
an old verdict, as OctoMap's clamping does). Beams are sampled every cell along their way, a
cell counted once per beam, up to ``MARGIN`` short of the return, and a cell where a beam of the
same batch ended is not carved by the batch (OctoMap's rule: a wall seen at a grazing angle is
crossed by the beams that end farther along it). A beam that saw nothing (``+inf`` or
``range_max``) carves up to the range it could have seen.

The grid is dense over the driven path's bounding box grown by the laser's reach: memory follows
the area, not the length of the bag (4 bytes a cell: 100 m x 100 m at 5 cm is 16 MB).
"""
from __future__ import annotations

import math

import numpy as np

HIT = 0.85              # log-odds of a return (p = 0.7)
FREE = -0.4             # log-odds of a beam passing through (p = 0.4)
LOW, HIGH = -2.0, 3.5   # clamping (p = 0.12 .. 0.97)
MARGIN = 2              # cells before a return that its beam does not carve
MAX_REACH = 20.0        # m: returns and free space farther than this are not used
CHUNK = 250_000         # beam samples handled at once (bounds the temporary memory: ~15 MB)


def reach_of(range_max: float) -> float:
    """How far along a beam the grid uses: the laser's range, at most MAX_REACH."""
    return float(min(range_max, MAX_REACH)) if math.isfinite(range_max) and range_max > 0 else MAX_REACH


class LogOdds:
    """A dense log-odds grid over ``lo``..``hi`` (x, y in metres) with cells of ``res`` metres."""

    def __init__(self, lo, hi, res: float):
        self.res = float(res)
        self.c0 = int(math.floor(lo[0] / res))
        self.r0 = int(math.floor(lo[1] / res))
        self.nx = int(math.floor(hi[0] / res)) - self.c0 + 1
        self.ny = int(math.floor(hi[1] / res)) - self.r0 + 1
        self.value = np.zeros((self.ny, self.nx), np.float32)

    def cells_of(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(column, row) grid indices of points (may fall outside the grid)."""
        return (np.floor(x / self.res).astype(np.int64) - self.c0,
                np.floor(y / self.res).astype(np.int64) - self.r0)

    def at_cells(self, cols: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """The log-odds of absolute cells (world column, row = floor(coordinate / res)); 0 outside."""
        c, r = cols - self.c0, rows - self.r0
        inside = (c >= 0) & (c < self.nx) & (r >= 0) & (r < self.ny)
        out = np.zeros(len(c), np.float32)
        out[inside] = self.value[r[inside], c[inside]]
        return out

    def add_rays(self, rays, reach: float) -> None:
        """Carve the free way of every beam of ``rays`` (projection.Rays) and mark its return."""
        res = self.res
        carve = np.where(rays.valid, rays.range - MARGIN * res, np.where(rays.none, reach, 0.0))
        carve = np.minimum(carve, reach)
        use = carve > 0.5 * res
        ox = np.asarray(rays.ox[use], np.float32)
        oy = np.asarray(rays.oy[use], np.float32)
        ang = rays.angle[use]
        dx, dy = np.cos(ang).astype(np.float32), np.sin(ang).astype(np.float32)
        steps = (carve[use] / res).astype(np.int64)
        hit = rays.valid & (rays.range <= reach)
        r = rays.range[hit].astype(float)
        a = rays.angle[hit]
        hx = rays.ox[hit] + r * np.cos(a)
        hy = rays.oy[hit] + r * np.sin(a)
        hc, hr = self.cells_of(hx, hy)
        bounds = np.cumsum(steps)
        start, first = 0, True
        while start < len(steps) or first:   # at most CHUNK samples at once, each chunk applied at once
            stop = int(np.searchsorted(bounds, (bounds[start - 1] if start else 0) + CHUNK, side="right"))
            stop = min(max(stop, start + 1), len(steps))
            c, rr = self._samples(ox[start:stop], oy[start:stop], dx[start:stop], dy[start:stop], steps[start:stop])
            self._apply(c, rr, hc, hr, count_hits=first)
            start, first = stop, False

    def _samples(self, ox, oy, dx, dy, steps) -> tuple[np.ndarray, np.ndarray]:
        """The cells each beam passes through (sampled once a cell length, each cell once per beam)."""
        total = int(steps.sum())
        if total == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        beam = np.repeat(np.arange(len(steps)), steps)
        k = np.arange(total) - np.repeat(np.cumsum(steps) - steps, steps)
        d = ((k + 0.5) * self.res).astype(np.float32)
        c, r = self.cells_of(ox[beam] + d * dx[beam], oy[beam] + d * dy[beam])
        fresh = np.ones(total, bool)
        fresh[1:] = (c[1:] != c[:-1]) | (r[1:] != r[:-1]) | (beam[1:] != beam[:-1])
        return c[fresh], r[fresh]

    def _apply(self, fc: np.ndarray, fr: np.ndarray, hc: np.ndarray, hr: np.ndarray, count_hits: bool = True) -> None:
        """Add the evidence (``fc``, ``fr``: cells beams passed; ``hc``, ``hr``: cells they ended in,
        counted when ``count_hits``, else only kept from being carved) in the window of the grid it
        touches, then clamp that window."""
        ok_f = (fc >= 0) & (fc < self.nx) & (fr >= 0) & (fr < self.ny)
        ok_h = (hc >= 0) & (hc < self.nx) & (hr >= 0) & (hr < self.ny)
        fc, fr, hc, hr = fc[ok_f], fr[ok_f], hc[ok_h], hr[ok_h]
        if not (len(fc) or (count_hits and len(hc))):
            return
        cols, rows = np.concatenate([fc, hc]), np.concatenate([fr, hr])
        c0, c1, r0, r1 = int(cols.min()), int(cols.max()) + 1, int(rows.min()), int(rows.max()) + 1
        w = c1 - c0
        size = w * (r1 - r0)
        hits = np.bincount((hr - r0) * w + (hc - c0), minlength=size).astype(np.float32)
        passes = np.bincount((fr - r0) * w + (fc - c0), minlength=size).astype(np.float32)
        # a cell that a beam of these scans ended in is not carved by the others (OctoMap's rule):
        # a wall seen at a grazing angle is crossed by the beams that end farther along it
        upd = np.where(hits > 0, HIT * hits if count_hits else 0.0, FREE * passes)
        win = self.value[r0:r1, c0:c1]
        win += upd.reshape(r1 - r0, w)
        np.clip(win, LOW, HIGH, out=win)
