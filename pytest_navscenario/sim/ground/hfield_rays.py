"""Ray casting over height grids: the lidars' own cast against heightfields, vectorised in numpy.

Why not ``mj_multiRay``: MuJoCo tests every triangle under a ray's bounding rectangle, which costs
9, 20, 57 and 240 ms for a 16 x 360 scan against heightfields of 32, 64, 128 and 256 cells a side
(measured, MuJoCo 4.0). Here a ray only does work where it can meet the ground:

1. it is clipped to the grid's box (its footprint, from the base below its lowest point up to its
   highest sample): a ray that never enters the box (above the highest point, beside the patch)
   costs a few arithmetic operations in a vector of all rays;
2. from where it enters the box it is followed column by column (cells along the axis it moves
   fastest along: it crosses at most two cells of each column), cells whose highest corner lies
   below the ray across the column are skipped, and the ray is intersected with both triangles of
   the cells in the first ``TESTED`` columns that are not (MuJoCo's triangles: each cell split
   along its diagonal from (c, r) to (c + 1, r + 1)); the nearest intersection is the hit;
3. a ray with none goes on in further rounds from where it was left: each round first walks the
   grid's blocks (``BLOCK`` cells a side) to skip every block whose highest point lies below the
   ray all the way across it, then follows the ray from the first block it may touch as in 2. Going
   down, a search ends early where the ray is lower than all of the block it is in, or than the
   whole grid: it has met the ground by then.

Most rays meet the ground in the first round (1-3 columns after they enter the box, measured on
rough ground); the rounds are there for long shallow rays over hilly fields.
The vertical walls of the box below its edge (MuJoCo's heightfield is solid down to its base) are
hits too. Every walk is exact (cells entered through their edges, in grid units, the entering cell of
each crossing), not sampled: the distances equal ``mj_multiRay``'s to floating point, apart from
MuJoCo keeping the grid in float32 (``tests/sim/test_hfield_rays.py`` states the tolerance).
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from . import hfield_march
from .heightfield import PlacedGrid, hfield_size

LEVELS = (16, 4)      # coarser views of the grid, in cells a side (used where the grid is 2x larger)
STEPS = 8             # columns of units a round follows a ray over, at each level
TESTED = 2            # columns of cells whose triangles a round intersects, from the first candidate
WIDEN = 2             # later rounds follow rays over up to 2**WIDEN times STEPS columns (the long ones)
FINISH = 48           # with this few rays left after a round, they are followed to their end at once
LONG = 4              # a ray's stretch must span this many units of a coarse level for it to walk them
PAD = 2               # units of border around each level's grid
MAX_ROUNDS = 100_000  # a ray advances at least one column a round: never reached
EPS = 1e-9            # grid units: a point this close to a triangle's edge counts as inside


class _Grid:
    """What the cast needs of one placed grid, computed once: heights in the geom's frame, cell and
    block maxima, the box."""

    def __init__(self, placed: PlacedGrid):
        grid = placed.grid
        h = np.ascontiguousarray(grid.heights, dtype=np.float64)
        self.rows, self.cols = h.shape
        self.flat = h.ravel()
        self.dx, self.dy = grid.cell
        size, _ = hfield_size(grid, placed.z)
        self.half_x, self.half_y = size[0], size[1]
        self.cx, self.cy, self.base = placed.x, placed.y, placed.z   # heights are above base
        self.c, self.s = math.cos(placed.yaw), math.sin(placed.yaw)
        self.zmax, self.zmin = float(h.max()), float(h.min())
        self.zlow = self.zmin - size[3]                       # the bottom of the solid base
        corner = np.maximum(np.maximum(h[:-1, :-1], h[:-1, 1:]), np.maximum(h[1:, :-1], h[1:, 1:]))
        self.ncr, self.ncc = self.rows - 1, self.cols - 1     # cells
        # the highest point of each cell, and of each LEVELS x LEVELS block of cells, with a border
        # of units that are never met (it catches rounding at the edges), flat
        self.levels = {size: _Level(corner, size) for size in (1,) + LEVELS
                       if size == 1 or max(self.ncr, self.ncc) >= 4 * size}
        # the compiled cast's view: heights (rows, cols), each cell's and block's highest point
        self.heights, self.cell_top = h, np.ascontiguousarray(corner)
        self.block_top = hfield_march.block_tops(corner)
        self.march_params = None        # its constants, made on its first cast


class _Level:
    """The grid seen in units of ``size`` x ``size`` cells: each unit's highest point, flat, with a
    border of ``PAD`` units that are never met all round (a ray's crossing of the grid's edge, to
    rounding, indexes the border, never another row)."""

    def __init__(self, corner: np.ndarray, size: int):
        ncr, ncc = corner.shape
        self.size = size
        self.nr, self.nc = -(-ncr // size), -(-ncc // size)
        units = np.full((self.nr * size, self.nc * size), -np.inf)
        units[:ncr, :ncc] = corner
        units = units.reshape(self.nr, size, self.nc, size).max(axis=(1, 3))
        pad = np.full((self.nr + 2 * PAD, self.nc + 2 * PAD), -np.inf)
        pad[PAD:-PAD, PAD:-PAD] = units
        self.top = pad.ravel().astype(np.float32)    # float32: half the memory the gathers touch
        self.top[self.top > -np.inf] = np.nextafter(self.top[self.top > -np.inf], np.float32(np.inf))
        self.width = self.nc + 2 * PAD


_GRIDS: dict[int, tuple[PlacedGrid, _Grid]] = {}


_MALLOC_TUNED = False


def _keep_freed_memory() -> None:
    """Have glibc keep freed memory for reuse (once per process). A cast makes a few dozen
    temporary arrays of 100-700 KB; by default glibc maps each of those afresh and returns it on
    free, so every scan page-faults them in again: raising its mmap and trim thresholds to 64 MB
    took a 16 x 360 scan over rough ground from 3.1 to 2.0 ms (median, CPU time, measured). The
    cost is memory kept by the process for its next arrays. Elsewhere than glibc: nothing."""
    global _MALLOC_TUNED
    if _MALLOC_TUNED:
        return
    _MALLOC_TUNED = True
    try:
        import ctypes
        import ctypes.util

        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return
    M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
    mallopt(M_MMAP_THRESHOLD, 64 << 20)
    mallopt(M_TRIM_THRESHOLD, 128 << 20)


def _prepared(placed: PlacedGrid) -> _Grid:
    _keep_freed_memory()
    hit = _GRIDS.get(id(placed))
    if hit is not None and hit[0] is placed:
        return hit[1]
    if len(_GRIDS) > 64:
        _GRIDS.clear()
    prepared = _Grid(placed)
    _GRIDS[id(placed)] = (placed, prepared)
    return prepared


def cast_grids(grids: Sequence[PlacedGrid], pnt: np.ndarray, dirs: np.ndarray, rmax: float,
               out: np.ndarray | None = None, within: np.ndarray | None = None) -> np.ndarray:
    """Distances (n,) along the unit ``dirs`` (n, 3) from ``pnt`` ((3,) or (n, 3), world frame) to
    the nearest of the ``grids``' surfaces, sides and bases within ``rmax``; ``np.inf`` where a ray
    meets none. ``within`` (n,): look no further than this along each ray (what it met already:
    a ray that hit the floor before reaching a patch costs nothing here). ``out`` (n,) is filled
    and returned when given."""
    n = len(dirs)
    if out is None:
        out = np.empty(n)
    if within is None:
        out.fill(np.inf)
    else:                         # out holds each ray's limit; a ray meeting nothing keeps inf
        np.copyto(out, within)
    compiled = hfield_march.available()
    for placed in grids:
        if compiled:
            hfield_march.cast(_prepared(placed), pnt, dirs, rmax, out)
        else:
            _cast_one(_prepared(placed), pnt, dirs, rmax, out)
    return out


# rows of the per-ray state matrix (one fancy index filters every quantity at once)
U0, V0, Z0, DU, DV, DZ, TA, TB, IDX, MT, MP, MD, MQ, ME, MS, MA = range(16)


def _cast_one(g: _Grid, pnt: np.ndarray, dirs: np.ndarray, rmax: float, out: np.ndarray) -> None:
    """Lower ``out`` where a ray meets grid ``g`` nearer. Rays that start above the grid's highest
    point and do not come down to it within rmax (or what they met already) are left out first,
    in two array operations: a level 2D lidar riding the grid casts few rays that can reach it
    (each ray's answer is the same either way: ``_clip`` would drop them)."""
    pnt = np.asarray(pnt, dtype=float)
    z0 = pnt[..., 2] - g.base
    dz = dirs[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_top = np.where(dz < 0, (g.zmax - z0) / dz, np.inf)
    reach = (z0 <= g.zmax) | (t_top <= np.minimum(out, rmax))
    if not reach.all():
        if not reach.any():
            return
        sub = out[reach]
        _cast_rays(g, pnt[reach] if pnt.ndim == 2 else pnt, dirs[reach], rmax, sub)
        out[reach] = sub
        return
    _cast_rays(g, pnt, dirs, rmax, out)


def _cast_rays(g: _Grid, pnt: np.ndarray, dirs: np.ndarray, rmax: float, out: np.ndarray) -> None:
    """``_cast_one`` for rays that may reach the grid."""
    n = len(dirs)
    st = np.empty((16, n))
    # into the grid's frame, in grid units (u along columns, v along rows), z in metres above base
    px, py = pnt[..., 0] - g.cx, pnt[..., 1] - g.cy
    st[U0] = (g.c * px + g.s * py + g.half_x) / g.dx
    st[V0] = (-g.s * px + g.c * py + g.half_y) / g.dy
    st[Z0] = pnt[..., 2] - g.base
    st[DU] = (g.c * dirs[:, 0] + g.s * dirs[:, 1]) / g.dx
    st[DV] = (-g.s * dirs[:, 0] + g.c * dirs[:, 1]) / g.dy
    st[DZ] = dirs[:, 2]
    st[IDX] = np.arange(n)
    # 1. the box: u in [0, cols - 1], v in [0, rows - 1], z in [zlow, zmax]
    with np.errstate(divide="ignore", invalid="ignore"):
        side = _clip(st, g, rmax)
    np.minimum(st[TB], out, out=st[TB])          # a ray that met something before gives up there
    keep = st[TA] <= st[TB]
    if not keep.any():
        return
    st, side = st[:, keep], side[keep]
    # a ray entering through a vertical side below the edge, or through the base, hits there
    wall = _wall_hits(g, st, side)
    if wall.any():
        at = st[IDX, wall].astype(np.intp)
        out[at] = np.minimum(out[at], st[TA, wall])
        st = st[:, ~wall]
    # the march's frame: p along the axis the ray moves fastest along, mirrored to move forwards
    along_u = np.abs(st[DU]) >= np.abs(st[DV])
    st[MS] = np.where(np.where(along_u, st[DU], st[DV]) >= 0, 1.0, -1.0)
    st[MP] = np.where(along_u, st[U0], st[V0]) * st[MS]
    st[MD] = np.where(along_u, st[DU], st[DV]) * st[MS]
    st[MA] = along_u
    st[MT] = np.where(np.where(along_u, st[DV], st[DU]) >= 0, 1.0, -1.0)
    st[MQ] = np.where(along_u, st[V0], st[U0]) * st[MT]
    st[ME] = np.where(along_u, st[DV], st[DU]) * st[MT]
    for rounds in range(MAX_ROUNDS):
        if not st.shape[1]:
            return
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if rounds and st.shape[1] <= FINISH:     # the few long rays left: all of them at once
                hit, reached, we, closed = _finish(g, st)
            else:
                hit, reached, we, closed = _round(g, st, STEPS << min(rounds, WIDEN))
        # a ray searched up to where it must be under the ground met it there (to rounding)
        np.copyto(hit, we, where=closed & (reached >= we) & (hit > we))
        found = hit <= we
        if found.any():
            at = st[IDX, found].astype(np.intp)
            out[at] = np.minimum(out[at], hit[found])
        more = ~found & (reached < we)
        st = st[:, more]
        st[TA] = reached[more]
    raise RuntimeError("hfield ray cast did not finish")    # each round advances every ray a column


def _round(g: _Grid, st: np.ndarray, steps: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One round of the search for every ray left, from TA: (the hit, inf if none; the t up to
    which it searched; the end of its search, TB or sooner where it must be under the ground;
    whether it ended so). Coarse to fine: at each level, the first of ``steps`` columns of units
    the ray may pass under (none: the ray goes on from the last column next round; a ray whose
    stretch is shorter than two units of a level skips it), then the cells."""
    ta, tb, z0, dz = st[TA], st[TB], st[Z0], st[DZ]
    going_down = dz < 0
    # below the whole grid (going down) or above it (going up): nothing further can be met
    t_floor = np.where(going_down, (g.zmin - z0) / dz, np.where(dz > 0, (g.zmax - z0) / dz, np.inf))
    we = np.minimum(tb, t_floor)
    closed = going_down & (t_floor <= tb)
    n = len(ta)
    hit = np.full(n, np.inf)
    reached = we.copy()
    ws = ta
    active = np.arange(n)
    cells = (we - ta) * st[MD]                  # each ray's stretch, in cells along its fast axis
    for size in LEVELS:
        level = g.levels.get(size)
        if level is None:
            continue
        long = np.flatnonzero(cells[active] >= LONG * size)
        if not len(long):
            continue
        pick = active[long]
        tl, cand, _ = _dense(g, level, st[:, pick], ws[long], we[pick], steps)
        column = cand[0] | cand[1]
        first = column.argmax(axis=1)
        rows = np.arange(len(pick))
        has = column[rows, first]
        reached[pick[~has]] = tl[~has, -1]
        ws = ws.copy()
        ws[long[has]] = tl[rows[has], first[has]]
        keep = np.ones(len(active), dtype=bool)
        keep[long[~has]] = False
        active, ws = active[keep], ws[keep]
        if not len(active):
            return hit, reached, we, closed
    hit[active], reached[active] = _march(g, st[:, active], ws, we[active], steps)
    return hit, reached, we, closed


def _finish(g: _Grid, st: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``_round`` for a few rays: each followed cell by cell over all of what is left of its
    stretch, every candidate cell's triangles intersected (no coarse levels, no further round)."""
    ta, tb, z0, dz = st[TA], st[TB], st[Z0], st[DZ]
    going_down = dz < 0
    t_floor = np.where(going_down, (g.zmin - z0) / dz, np.where(dz > 0, (g.zmax - z0) / dz, np.inf))
    we = np.minimum(tb, t_floor)
    closed = going_down & (t_floor <= tb)
    cells = int(np.ceil(np.max((we - ta) * st[MD]))) + 2
    steps = int(min(max(cells, 1), len(_ARANGE) - 2))
    hit, reached = _march(g, st, ta, we, steps, tested=steps)
    return hit, reached, we, closed


def _clip(st: np.ndarray, g: _Grid, rmax: float) -> np.ndarray:
    """Set TA, TB to where each ray enters the box and leaves it (or reaches rmax); returns the face
    it entered through: 0 a u side, 1 a v side, 2 the top, 3 the bottom, -1 it starts inside. The
    three slabs at once ((3, n) arrays: a few numpy calls for every ray of a scan)."""
    p, d = st[[U0, V0, Z0]], st[[DU, DV, DZ]]
    low = np.array([[0.0], [0.0], [g.zlow]])
    high = np.array([[g.cols - 1.0], [g.rows - 1.0], [g.zmax]])
    t1, t2 = (low - p) / d, (high - p) / d
    near, far = np.minimum(t1, t2), np.maximum(t1, t2)
    parallel = d == 0
    if parallel.any():          # parallel to a slab: inside it for all t, or never
        inside = (p >= low) & (p <= high)
        near = np.where(parallel, np.where(inside, -np.inf, np.inf), near)
        far = np.where(parallel, np.where(inside, np.inf, -np.inf), far)
    which = near.argmax(axis=0)
    lo = near[which, np.arange(p.shape[1])]
    side = np.where(lo > 0.0, np.where(which == 2, np.where(st[DZ] < 0, 2, 3), which), -1).astype(np.int8)
    st[TA] = np.maximum(lo, 0.0)
    st[TB] = np.minimum(far.min(axis=0), rmax)
    return side


def _wall_hits(g: _Grid, st: np.ndarray, side: np.ndarray) -> np.ndarray:
    """Rays that enter the box through a vertical side below the grid's edge there (or through its
    base's bottom): they hit at the entry."""
    out = side == 3
    sides = (side == 0) | (side == 1)
    if not sides.any():
        return out
    ta = st[TA]
    u = np.clip(st[U0] + st[DU] * ta, 0.0, g.cols - 1.0)
    v = np.clip(st[V0] + st[DV] * ta, 0.0, g.rows - 1.0)
    return out | (sides & (st[Z0] + st[DZ] * ta < _surface(g, u, v)))


def _surface(g: _Grid, u, v) -> np.ndarray:
    """Heights of the grid at grid points (u, v), on MuJoCo's triangles."""
    c = np.clip(np.floor(u), 0, g.cols - 2).astype(np.intp)
    r = np.clip(np.floor(v), 0, g.rows - 2).astype(np.intp)
    fx, fy = u - c, v - r
    i = r * g.cols + c
    h = g.flat
    h00, h10, h01, h11 = h[i], h[i + 1], h[i + g.cols], h[i + g.cols + 1]
    return np.where(fx >= fy, h00 + (h10 - h00) * fx + (h11 - h10) * fy,
                    h00 + (h11 - h01) * fx + (h01 - h00) * fy)


def _dense(g: _Grid, level: _Level, st: np.ndarray, ws: np.ndarray, we: np.ndarray, steps: int):
    """The ray over ``steps`` columns of ``level``'s units from ws (columns across the axis it moves
    fastest along; both axes mirrored so that it moves forwards along them): (t at the column
    boundaries (n, steps + 1), within [ws, we]; which of the at most two units it crosses in each
    column it may pass under, (2, n, steps); those units' padded indices). In a column the ray
    moves at most one unit along the other axis, so it crosses at most two units there. Columns
    past we repeat the unit at we: harmless, the ray is there."""
    L = float(level.size)
    z0, dz, P, D, Q, E = st[Z0], st[DZ], st[MP] / L, st[MD] / L, st[MQ] / L, st[ME] / L
    sp, sq = st[MS], st[MT]
    ar = _ARANGE[:steps + 1]
    k0 = np.floor(P + D * ws + EPS)       # a ray a hair before a column's boundary starts past it
    step = 1.0 / np.maximum(D, 1e-300)                           # t per column (huge: vertical)
    tl = ((k0 - P) * step)[:, None] + step[:, None] * ar         # t at the column boundaries
    np.minimum(tl, we[:, None], out=tl)
    np.maximum(tl, ws[:, None], out=tl)
    z = z0[:, None] + dz[:, None] * tl
    zlo = np.minimum(z[:, :-1], z[:, 1:])
    q = Q[:, None] + E[:, None] * tl                             # increasing along each row
    # the span is at most one unit: shrunk by EPS, a column ending on a corner that rounding put a
    # hair past it counts the units it really crosses, not the corner's neighbours
    lo_other = np.floor(q[:, :-1] + EPS)
    hi_other = np.floor(q[:, 1:] - EPS)
    # padded flat index = (mirrored index m -> sign * m + (sign - 1) / 2, + PAD) times the axis's
    # stride, summed over the two axes; the column's part is a line in k
    W = level.width
    au = st[MA] > 0
    a_stride, b_stride = np.where(au, 1.0, W), np.where(au, W, 1.0)
    # the column (unmirrored), kept within the border: columns past the stretch's end repeat its
    # last unit in t (tl is clamped) and must not index another row
    col = (sp * k0 + (sp - 1.0) * 0.5)[:, None] + sp[:, None] * ar[:steps]
    np.minimum(col, np.where(au, level.nc, level.nr)[:, None], out=col)
    np.maximum(col, -1.0, out=col)
    a_part = a_stride[:, None] * (col + PAD) + (b_stride * ((sq - 1.0) * 0.5 + PAD))[:, None]
    b_mul = (b_stride * sq)[:, None]
    units = np.empty((2,) + lo_other.shape, dtype=np.intp)
    np.add(a_part, b_mul * lo_other, out=units[0], casting="unsafe")
    np.add(a_part, b_mul * hi_other, out=units[1], casting="unsafe")
    cand = zlo <= level.top[units]                               # (2, n, steps)
    cand[1] &= hi_other != lo_other                              # the same unit twice: once
    return tl, cand, units


def _march(g: _Grid, st: np.ndarray, ws: np.ndarray, we: np.ndarray, steps: int = STEPS,
           tested: int = TESTED) -> tuple[np.ndarray, np.ndarray]:
    """Per ray, (the nearest t in [ws, we] where it meets a triangle, inf if none; the t up to
    which it was searched): over STEPS columns of cells from ws, both triangles of the cells it may
    pass under in the first TESTED columns that have any (a hit in an earlier column is always
    nearer); the rest is left to the next round."""
    n = len(ws)
    tl, cand, cells = _dense(g, g.levels[1], st, ws, we, steps)
    column = cand[0] | cand[1]
    first = column.argmax(axis=1)                                # the first column it may touch
    rows = np.arange(n)
    has = column[rows, first]
    hit = np.full(n, np.inf)
    if not has.any():
        return hit, tl[:, -1]
    pick = np.minimum(first[:, None] + _ARANGE[:tested].astype(np.intp), steps - 1)[None]
    sel = np.take_along_axis(cand, pick, axis=2)                 # (2, n, TESTED)
    sel[:, :, 1:] &= pick[:, :, 1:] > pick[:, :, :-1]            # not the last column twice
    which = np.flatnonzero(sel)
    ray = (which // tested) % n
    r, c = np.divmod(np.take_along_axis(cells, pick, axis=2).ravel()[which], g.levels[1].width)
    r -= PAD
    c -= PAD
    i = r * g.cols + c
    h = g.flat
    h00, h10, h01, h11 = h[i], h[i + 1], h[i + g.cols], h[i + g.cols + 1]
    fx0, fy0 = st[U0, ray] - c, st[V0, ray] - r                 # the ray's origin in the cell's units
    ddu, ddv, ddz, zz0 = st[DU, ray], st[DV, ray], st[DZ, ray], st[Z0, ray]
    lo, hi = ws[ray] - 1e-12, we[ray] + 1e-12
    best = np.full(len(which), np.inf)
    for a1, a2, lower in ((h10 - h00, h11 - h10, True), (h11 - h01, h01 - h00, False)):
        tt = (h00 + a1 * fx0 + a2 * fy0 - zz0) / (ddz - a1 * ddu - a2 * ddv)
        fx, fy = fx0 + ddu * tt, fy0 + ddv * tt
        ok = (fx >= -EPS) & (fx <= 1 + EPS) & (fy >= -EPS) & (fy <= 1 + EPS) & (tt >= lo) & (tt <= hi)
        ok &= (fx >= fy - EPS) if lower else (fy >= fx - EPS)
        np.copyto(best, tt, where=ok & (tt < best))
    met = np.full(sel.shape, np.inf)
    met.ravel()[which] = best
    hit = met.min(axis=(0, 2))
    # searched up to the end of the tested columns (all of them where none was a candidate)
    end = np.where(has, np.minimum(first + tested, steps), steps)
    step = 1.0 / np.maximum(st[MD], 1e-300)
    return hit, np.maximum(tl[rows, end], ws + EPS * step)      # at least a hair further each round


_ARANGE = np.arange(4100.0)        # columns: more than a 1024-sample grid's diagonal
