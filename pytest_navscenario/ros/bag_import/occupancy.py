"""An occupancy grid in log-odds, as a mapping package keeps one (gmapping, slam_toolbox, OctoMap):
every beam adds evidence of free space along its way and of an obstacle where it ended, so a cell
where a smeared return (or a person who walked on) landed once is cleared by the later beams that
pass through it.

Each cell holds ``log(p / (1 - p))``: a return adds ``HIT``, a beam through it adds ``FREE``, and the
sum is kept within ``[LOW, HIGH]`` after every batch of scans (a part of one for long beams) (so recent
evidence can still change an old verdict, as OctoMap's clamping does); within a batch a cell takes at
most one hit or one pass a scan (OctoMap updates a cell once per scan), so the many beams of a dense
lidar do not outvote the few that hit a wall. Beams are sampled every cell along their way, a cell
counted once per beam, and a cell where a beam of the same batch ended is not carved by the batch.

Walls the robot drove beside stay (issue 37): a beam meeting a surface at a shallow angle runs
within a few centimetres of it for a long way before its return, and a real lidar often gets no
echo at all from such a beam. So the inverse sensor model stops short of the return by
``DEPTH / sin(incidence)`` (the incidence from the neighbouring returns of the same scan, at most
``MAX_SHORT``), and a beam stops carving at the first cell that returns hit repeatedly
(``REPEATED`` scans) whose surface, as those returns saw it, the beam meets at less than ``GRAZE``:
the wall it grazed. A beam that saw nothing (``+inf`` or ``range_max``) carves up to the range it
could have seen, or up to such a wall.

The grid is dense over the driven path's bounding box grown by the laser's reach: memory follows
the area, not the length of the bag (4 bytes a cell: 100 m x 100 m at 5 cm is 16 MB).
"""
from __future__ import annotations

import math

import numpy as np

HIT = 0.85              # log-odds of a return (p = 0.7)
FREE = -0.4             # log-odds of a beam passing through (p = 0.4)
LOW, HIGH = -2.0, 3.5   # clamping (p = 0.12 .. 0.97)
MARGIN = 2              # cells before a return that its beam does not carve (at least)
DEPTH = 0.1             # m across a surface that a beam meeting it does not carve (pose and range error)
MAX_SHORT = 1.5         # m: a beam stops short of its return at most this much
REPEATED = 3            # scans that hit a cell for a grazing beam to stop there
CONSISTENT = 0.7        # share of a cell's hits whose surfaces agree in direction (resultant length)
GRAZE = math.radians(20.0)   # a beam meeting a surface at less than this from it grazes it
CHORD = 0.15            # m: the shortest chord between neighbouring returns that gives a surface's direction
ON_CHORD = 0.04         # m: a return farther than this from its chord lies across a jump
MAX_REACH = 20.0        # m: returns and free space farther than this are not used
CHUNK = 250_000         # beam samples handled at once (bounds the temporary memory: ~15 MB)


def reach_of(range_max: float) -> float:
    """How far along a beam the grid uses: the laser's range, at most MAX_REACH."""
    return float(min(range_max, MAX_REACH)) if math.isfinite(range_max) and range_max > 0 else MAX_REACH


class LogOdds:
    """A dense log-odds grid over ``lo``..``hi`` (x, y in metres) with cells of ``res`` metres, and
    for every cell how many scans hit it and the orientation of the surface they saw there."""

    def __init__(self, lo, hi, res: float):
        self.res = float(res)
        self.c0 = int(math.floor(lo[0] / res))
        self.r0 = int(math.floor(lo[1] / res))
        self.nx = int(math.floor(hi[0] / res)) - self.c0 + 1
        self.ny = int(math.floor(hi[1] / res)) - self.r0 + 1
        self.value = np.zeros((self.ny, self.nx), np.float32)
        self.hits = np.zeros((self.ny, self.nx), np.float32)       # scans that hit each cell
        # the surface's direction at each cell, as a doubled angle (a line has no sign): sums of
        # cos 2a, sin 2a over the hits whose scan showed the surface
        self.c2 = np.zeros((self.ny, self.nx), np.float32)
        self.s2 = np.zeros((self.ny, self.nx), np.float32)

    def cells_of(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(column, row) grid indices of points (may fall outside the grid)."""
        return (np.floor(x / self.res).astype(np.int64) - self.c0,
                np.floor(y / self.res).astype(np.int64) - self.r0)

    def at_cells(self, cols: np.ndarray, rows: np.ndarray, layer: np.ndarray | None = None) -> np.ndarray:
        """The log-odds (or another ``layer``) of absolute cells (world column, row = floor(coordinate
        / res)); 0 outside."""
        c, r = cols - self.c0, rows - self.r0
        inside = (c >= 0) & (c < self.nx) & (r >= 0) & (r < self.ny)
        out = np.zeros(len(c), np.float32)
        out[inside] = (self.value if layer is None else layer)[r[inside], c[inside]]
        return out

    def add_rays(self, rays, reach: float) -> None:
        """Carve the free way of every beam of ``rays`` (projection.Rays) and mark its return."""
        res = self.res
        surface = surface_angles(rays)
        hit = rays.valid & (rays.range <= reach)
        r = rays.range[hit].astype(float)
        a = rays.angle[hit]
        hc, hr = self.cells_of(rays.ox[hit] + r * np.cos(a), rays.oy[hit] + r * np.sin(a))
        scans = rays.range.shape[0]
        self._note_surfaces(hc, hr, surface[hit], scans)
        short = np.clip(DEPTH / np.maximum(np.abs(np.sin(rays.angle - surface)), 1e-3), MARGIN * res, MAX_SHORT)
        short = np.where(np.isfinite(surface), short, MARGIN * res)
        carve = np.where(rays.valid, rays.range - short, np.where(rays.none, reach, 0.0))
        carve = np.minimum(carve, reach)
        use = carve > 0.5 * res
        ox = np.asarray(rays.ox[use], np.float32)
        oy = np.asarray(rays.oy[use], np.float32)
        ang = rays.angle[use]
        dx, dy = np.cos(ang).astype(np.float32), np.sin(ang).astype(np.float32)
        steps = (carve[use] / res).astype(np.int64)
        bounds = np.cumsum(steps)
        start, first = 0, True
        while start < len(steps) or first:   # at most CHUNK samples at once, each chunk applied at once
            stop = int(np.searchsorted(bounds, (bounds[start - 1] if start else 0) + CHUNK, side="right"))
            stop = min(max(stop, start + 1), len(steps))
            c, rr, beam = self._samples(ox[start:stop], oy[start:stop], dx[start:stop], dy[start:stop],
                                        steps[start:stop])
            keep = self._before_grazed_wall(c, rr, beam, ang[start:stop])
            self._apply(c[keep], rr[keep], hc, hr, scans, count_hits=first)
            start, first = stop, False

    def _note_surfaces(self, hc, hr, surface, scans: int) -> None:
        """Count the scans that hit each cell (at most one a scan) and add the surface's direction."""
        ok = (hc >= 0) & (hc < self.nx) & (hr >= 0) & (hr < self.ny)
        hc, hr, surface = hc[ok], hr[ok], surface[ok]
        if not len(hc):
            return
        flat = hr * self.nx + hc
        size = self.nx * self.ny
        counts = np.bincount(flat, minlength=size)
        cells = np.nonzero(counts)[0]
        scans_hit = np.minimum(counts[cells], scans)
        self.hits.reshape(-1)[cells] += scans_hit
        seen = np.isfinite(surface)
        if seen.any():      # the mean direction of the batch's hits, weighted as the scans that hit
            weight = scans_hit / counts[cells]
            c2 = np.bincount(flat[seen], weights=np.cos(2 * surface[seen]), minlength=size)
            s2 = np.bincount(flat[seen], weights=np.sin(2 * surface[seen]), minlength=size)
            self.c2.reshape(-1)[cells] += c2[cells] * weight
            self.s2.reshape(-1)[cells] += s2[cells] * weight

    def _before_grazed_wall(self, c, r, beam, angle) -> np.ndarray:
        """Which samples a beam carves: those before the first cell that returns hit in ``REPEATED``
        scans or more whose surface (a consistent direction) the beam meets at less than ``GRAZE``."""
        keep = np.ones(len(c), bool)
        if not len(c):
            return keep
        inside = (c >= 0) & (c < self.nx) & (r >= 0) & (r < self.ny)
        flat = np.where(inside, r * self.nx + c, 0)
        hits = self.hits.reshape(-1)[flat]
        wall = np.flatnonzero(inside & (hits >= REPEATED))
        if not len(wall):
            return keep
        at = flat[wall]
        c2, s2 = self.c2.reshape(-1)[at], self.s2.reshape(-1)[at]
        surface = 0.5 * np.arctan2(s2, c2)
        graze = (np.hypot(c2, s2) >= CONSISTENT * hits[wall]) & \
            (np.abs(np.sin(angle[beam[wall]] - surface)) < math.sin(GRAZE))
        if not graze.any():
            return keep
        # carved up to (not through) the first grazed wall cell of each beam: samples are in beam order
        stop = np.full(int(beam[-1]) + 1, len(c))
        np.minimum.at(stop, beam[wall[graze]], wall[graze])
        return np.arange(len(c)) < stop[beam]

    def _samples(self, ox, oy, dx, dy, steps) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The cells each beam passes through (sampled once a cell length, each cell once per beam),
        and the beam each belongs to (in order)."""
        total = int(steps.sum())
        if total == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64)
        beam = np.repeat(np.arange(len(steps)), steps)
        k = np.arange(total) - np.repeat(np.cumsum(steps) - steps, steps)
        d = ((k + 0.5) * self.res).astype(np.float32)
        c, r = self.cells_of(ox[beam] + d * dx[beam], oy[beam] + d * dy[beam])
        fresh = np.ones(total, bool)
        fresh[1:] = (c[1:] != c[:-1]) | (r[1:] != r[:-1]) | (beam[1:] != beam[:-1])
        return c[fresh], r[fresh], beam[fresh]

    def _apply(self, fc: np.ndarray, fr: np.ndarray, hc: np.ndarray, hr: np.ndarray, scans: int,
               count_hits: bool = True) -> None:
        """Add the evidence (``fc``, ``fr``: cells beams passed; ``hc``, ``hr``: cells they ended in,
        counted when ``count_hits``, else only kept from being carved; each at most once for each of
        the ``scans``) in the window of the grid it touches, then clamp that window."""
        ok_f = (fc >= 0) & (fc < self.nx) & (fr >= 0) & (fr < self.ny)
        ok_h = (hc >= 0) & (hc < self.nx) & (hr >= 0) & (hr < self.ny)
        fc, fr, hc, hr = fc[ok_f], fr[ok_f], hc[ok_h], hr[ok_h]
        if not (len(fc) or (count_hits and len(hc))):
            return
        cols, rows = np.concatenate([fc, hc]), np.concatenate([fr, hr])
        c0, c1, r0, r1 = int(cols.min()), int(cols.max()) + 1, int(rows.min()), int(rows.max()) + 1
        w = c1 - c0
        size = w * (r1 - r0)
        hits = np.minimum(np.bincount((hr - r0) * w + (hc - c0), minlength=size), scans).astype(np.float32)
        passes = np.minimum(np.bincount((fr - r0) * w + (fc - c0), minlength=size), scans).astype(np.float32)
        # a cell that a beam of these scans ended in is not carved by the others (OctoMap's rule):
        # a wall seen at a grazing angle is crossed by the beams that end farther along it
        upd = np.where(hits > 0, HIT * hits if count_hits else 0.0, FREE * passes)
        win = self.value[r0:r1, c0:c1]
        win += upd.reshape(r1 - r0, w)
        np.clip(win, LOW, HIGH, out=win)


def surface_angles(rays) -> np.ndarray:
    """(scans, beams) the direction (rad) of the surface at each return: the chord between the
    returns ``k`` beams either side of it in the same scan, for the smallest ``k`` (of 1, 2, 4, ...)
    whose chord is at least ``CHORD`` long (so range noise does not turn it) with the return on it
    within ``ON_CHORD`` (not across a jump); NaN where none is."""
    rng = np.where(rays.valid, rays.range, np.nan).astype(float)
    px = rays.ox + rng * np.cos(rays.angle)
    py = rays.oy + rng * np.sin(rays.angle)
    out = np.full(rng.shape, np.nan)
    n = rng.shape[1]
    k = 1
    while k < min(n // 2, 33):
        ax, ay = px[:, :-2 * k], py[:, :-2 * k]           # beam i - k
        bx, by = px[:, 2 * k:], py[:, 2 * k:]             # beam i + k
        mx, my = px[:, k:-k], py[:, k:-k]
        ex, ey = bx - ax, by - ay
        with np.errstate(invalid="ignore", divide="ignore"):
            length = np.hypot(ex, ey)
            off = np.abs(ex * (my - ay) - ey * (mx - ax)) / length
            ok = (length >= CHORD) & (off <= ON_CHORD)
        mid = out[:, k:-k]
        todo = ok & np.isnan(mid)
        mid[todo] = np.arctan2(ey[todo], ex[todo])
        k *= 2
    return out
