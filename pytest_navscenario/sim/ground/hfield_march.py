"""The heightfield ray cast compiled: each ray walked over the grid in a loop of its own (numba).

Why: the vectorised cast (``hfield_rays``) pays numpy's call overhead a few hundred times a scan;
a 16 x 360 scan over a 256 x 256-cell field took 3.9 ms there. Here each ray, in one compiled loop:

1. is taken into the grid's frame and clipped to its box (the grid's footprint, from the base up to
   its highest sample), exactly as ``hfield_rays._clip`` does; a ray entering through a vertical
   side below the grid's edge, or through the base, hits there (``hfield_rays._wall_hits``);
2. walks the columns of ``BLOCK`` x ``BLOCK``-cell blocks along the axis it moves fastest along,
   skipping a column of blocks wherever the ray stays above the highest point of the (at most
   three) blocks it crosses there;
3. in the others, walks the columns of cells and intersects both of MuJoCo's triangles of each
   cell (split along the diagonal from (c, r) to (c + 1, r + 1)) whose highest corner the ray
   comes down to (a plane whose hit lies outside the column is not divided out); it ends with the
   first column that has a hit, or one column later where that hit lies within the triangle
   test's tolerance of the column's end (as ``hfield_rays._march`` tests two columns).

The triangle test is ``hfield_rays._march``'s expression, operation for operation (numba compiles
without fast-math: no reassociation, no fused multiply-add), so a hit is the same float64 as the
vectorised cast's where both pick the same triangle; the walk only decides which triangles are
tried (a superset of those the ray passes over, widened by ``SLOP``). ``tests/sim/test_hfield_march.py``
checks both casts and a brute force over every triangle give the same distances.

The kernel is compiled on first use (about 5 s) and cached on disk (numba's ``cache=True``; a new
process imports numba and loads it in about 0.5 s); the helpers are inlined into it (called, each
call counted the arrays' references: 25 % slower). ``available()`` is False where numba cannot be
imported, and ``hfield_rays`` then casts with numpy.
"""
from __future__ import annotations

import math

import numpy as np

BLOCK = 8          # cells a side of the coarse blocks a ray skips over
SLOP = 1e-9        # grid units / metres: how far a ray is widened when choosing cells to try
EPS = 1e-9         # grid units: a point this close to a triangle's edge counts as inside (as hfield_rays)

_KERNEL = None
_TRIED = False


def available() -> bool:
    """Whether the compiled cast can run here (numba importable); compiles it on the first call."""
    return _kernel() is not None


def block_tops(corner: np.ndarray) -> np.ndarray:
    """The highest point of each ``BLOCK`` x ``BLOCK`` block of cells (rows, cols of blocks), from
    the cells' highest corners ``corner`` (rows, cols of cells)."""
    ncr, ncc = corner.shape
    nr, nc = -(-ncr // BLOCK), -(-ncc // BLOCK)
    units = np.full((nr * BLOCK, nc * BLOCK), -np.inf)
    units[:ncr, :ncc] = corner
    return np.ascontiguousarray(units.reshape(nr, BLOCK, nc, BLOCK).max(axis=(1, 3)))


def cast(g, pnt: np.ndarray, dirs: np.ndarray, rmax: float, out: np.ndarray) -> None:
    """Lower ``out`` (n,) where a ray from ``pnt`` ((3,) or (n, 3)) along ``dirs`` (n, 3) meets the
    prepared grid ``g`` (``hfield_rays._Grid``) nearer, within ``rmax``."""
    pnts = np.asarray(pnt, dtype=np.float64)
    each = pnts.ndim == 2                      # one origin per ray, or one for all
    params = g.march_params
    if params is None:
        params = g.march_params = np.array([g.cx, g.cy, g.base, g.c, g.s, g.half_x, g.half_y, g.dx,
                                            g.dy, g.zmax, g.zmin, g.zlow])
    _kernel()(g.heights, g.cell_top, g.block_top, params, float(rmax),
              np.ascontiguousarray(pnts.reshape(-1, 3)), each, np.ascontiguousarray(dirs, dtype=np.float64), out)


def _kernel():
    global _KERNEL, _TRIED
    if not _TRIED:
        _TRIED = True
        try:
            import numba
        except ImportError:          # the numpy cast is used instead
            return None
        names = globals()            # helpers first: the compiled callers find them compiled
        for name in ("_slab", "_surface", "_span", "_inside", "_may_meet", "_column", "_walk", "_one"):
            # inlined: a call that passes arrays would count references (atomics) on each call
            names[name] = numba.njit(inline="always", error_model="numpy")(names[name])
        _KERNEL = numba.njit(cache=True, nogil=True, error_model="numpy")(_cast_all)
    return _KERNEL


def _cast_all(h, cell_top, block_top, params, rmax, pnts, each, dirs, out):   # pragma: no cover
    """Every ray: the nearest of its wall hit and triangle hits, lowering ``out`` (``pnts``: one
    origin a ray when ``each``, else one for all)."""
    cx, cy, base, c, s, half_x, half_y, dx, dy, zmax, zmin, zlow = (
        params[0], params[1], params[2], params[3], params[4], params[5], params[6], params[7],
        params[8], params[9], params[10], params[11])
    rows, cols = h.shape
    for i in range(dirs.shape[0]):
        o = i if each else 0
        z0 = pnts[o, 2] - base
        dz = dirs[i, 2]
        if z0 > zmax:                               # above the grid: only a ray coming down
            if not dz < 0:
                continue
            if not (zmax - z0) / dz <= min(out[i], rmax):
                continue
        px, py = pnts[o, 0] - cx, pnts[o, 1] - cy
        u0 = (c * px + s * py + half_x) / dx
        v0 = (-s * px + c * py + half_y) / dy
        du = (c * dirs[i, 0] + s * dirs[i, 1]) / dx
        dv = (-s * dirs[i, 0] + c * dirs[i, 1]) / dy
        t = _one(h, cell_top, block_top, rows, cols, u0, v0, z0, du, dv, dz, zmax, zmin, zlow, rmax, out[i])
        if t < out[i]:
            out[i] = t


def _slab(p, d, low, high):   # pragma: no cover - compiled
    """(near, far) of a ray against one slab, as ``hfield_rays._clip`` (parallel: in or out)."""
    if d == 0.0:
        if p >= low and p <= high:
            return -math.inf, math.inf
        return math.inf, -math.inf
    t1, t2 = (low - p) / d, (high - p) / d
    return min(t1, t2), max(t1, t2)


def _one(h, cell_top, block_top, rows, cols, u0, v0, z0, du, dv, dz, zmax, zmin, zlow, rmax, limit):  # pragma: no cover
    """One ray in grid units: its distance to the grid, or inf."""
    nu, fu = _slab(u0, du, 0.0, cols - 1.0)
    nv, fv = _slab(v0, dv, 0.0, rows - 1.0)
    nz, fz = _slab(z0, dz, zlow, zmax)
    lo, which = nu, 0                              # the first largest, as argmax
    if nv > lo:
        lo, which = nv, 1
    if nz > lo:
        lo, which = nz, 2
    ta = max(lo, 0.0)
    tb = min(min(min(fu, fv), fz), rmax)
    tb = min(tb, limit)
    if not ta <= tb:
        return math.inf
    if lo > 0.0:                                   # entered through a face of the box
        if which == 2 and not dz < 0:              # the base, from below
            return ta
        if which < 2:
            u = min(max(u0 + du * ta, 0.0), cols - 1.0)
            v = min(max(v0 + dv * ta, 0.0), rows - 1.0)
            if z0 + dz * ta < _surface(h, rows, cols, u, v):
                return ta
    # below the whole grid (going down) or above it (going up): nothing further can be met
    if dz < 0:
        t_floor = (zmin - z0) / dz
    elif dz > 0:
        t_floor = (zmax - z0) / dz
    else:
        t_floor = math.inf
    we = min(tb, t_floor)
    closed = dz < 0 and t_floor <= tb
    hit = _walk(h, cell_top, block_top, rows, cols, u0, v0, z0, du, dv, dz, ta, we)
    if closed and hit > we:      # searched to where it is under the ground: it met it there
        return we
    return hit if hit <= we else math.inf


def _surface(h, rows, cols, u, v):   # pragma: no cover - compiled
    """The grid's height at (u, v), on MuJoCo's triangles (``hfield_rays._surface``)."""
    c = min(max(math.floor(u), 0), cols - 2)
    r = min(max(math.floor(v), 0), rows - 2)
    fx, fy = u - c, v - r
    h00, h10, h01, h11 = h[r, c], h[r, c + 1], h[r + 1, c], h[r + 1, c + 1]
    if fx >= fy:
        return h00 + (h10 - h00) * fx + (h11 - h10) * fy
    return h00 + (h11 - h01) * fx + (h01 - h00) * fy


def _walk(h, cell_top, block_top, rows, cols, u0, v0, z0, du, dv, dz, ta, we):   # pragma: no cover
    """The nearest triangle hit in [ta, we] (inf if none): blocks, then cells, along the axis the
    ray moves fastest along (``sgn``: its direction there; ``x``: the mirrored coordinate along
    it, increasing with t)."""
    along_u = abs(du) >= abs(dv)
    if along_u:
        p0, dp, q0, dq, nf, no = u0, du, v0, dv, cols - 1, rows - 1
    else:
        p0, dp, q0, dq, nf, no = v0, dv, u0, du, rows - 1, cols - 1
    sgn = 1.0 if dp >= 0 else -1.0
    P, D = sgn * p0, sgn * dp
    iD = 1.0 / D if D > 1e-200 else 0.0
    xs, xe = P + D * ta, P + D * we
    # mirrored cell k covers x in [k, k + 1], the real cell sgn * k + (sgn - 1) / 2 (within 0..nf-1)
    if sgn > 0:
        kmin, kmax = 0, nf - 1
    else:
        kmin, kmax = -nf, -1
    k0 = min(max(int(math.floor(xs - SLOP)), kmin), kmax)
    k1 = min(max(int(math.floor(xe + SLOP)), kmin), kmax)
    nbo = block_top.shape[0] if along_u else block_top.shape[1]
    best = math.inf
    stop = k1
    kb = k0 // BLOCK
    while kb * BLOCK <= stop:
        ka, kz = max(kb * BLOCK, k0), min(kb * BLOCK + BLOCK - 1, stop)
        t_lo, t_hi = _span(P, D, iD, ta, we, ka, kz + 1)
        za, zb = z0 + dz * t_lo, z0 + dz * t_hi
        zlo = min(za, zb) - SLOP
        qa, qb = q0 + dq * t_lo, q0 + dq * t_hi
        ba = max(int(math.floor(min(qa, qb) - SLOP)) // BLOCK, 0)
        bz = min(int(math.floor(max(qa, qb) + SLOP)) // BLOCK, nbo - 1)
        jb = int(sgn) * kb + (int(sgn) - 1) // 2
        met = False
        for b in range(ba, bz + 1):
            top = block_top[b, jb] if along_u else block_top[jb, b]
            if zlo <= top:
                met = True
                break
        if met:
            for k in range(ka, kz + 1):
                if k > stop:
                    break
                t = _column(h, cell_top, rows, cols, u0, v0, z0, du, dv, dz, ta, we, P, D, iD, q0, dq,
                            int(sgn) * k + (int(sgn) - 1) // 2, no, k, along_u)
                if t < best:
                    best = t
                    # a hit in the next column lies past this column's end (to what the triangle
                    # test lets in): only a hit this close to the end makes it worth trying
                    if best < (k + 1 - P) / D - 4 * EPS / D - 1e-9 if D > 0.0 else True:
                        stop = k
                    elif stop > k + 1:
                        stop = k + 1           # one more column, then the nearest
        kb += 1
    return best


def _span(P, D, iD, ta, we, xa, xb):   # pragma: no cover - compiled
    """The t range of the ray within x in [xa, xb], clamped to [ta, we] (``iD``: 1 / D; a product
    is rounded differently from the quotient, which only widens or narrows the range by far less
    than SLOP: it chooses what is tried, never a hit's distance)."""
    if D > 1e-200:
        t_lo = max((xa - P) * iD, ta)
        t_hi = min((xb - P) * iD, we)
        if t_hi < t_lo:
            t_hi = t_lo
        return t_lo, t_hi
    return ta, we


def _column(h, cell_top, rows, cols, u0, v0, z0, du, dv, dz, ta, we, P, D, iD, q0, dq, j, no, k,
            along_u):   # pragma: no cover - compiled
    """The nearest triangle hit among the cells of column ``j`` (real index along the fast axis)
    that the ray may come down to."""
    t_lo, t_hi = _span(P, D, iD, ta, we, k, k + 1)
    zlo = min(z0 + dz * t_lo, z0 + dz * t_hi) - SLOP
    qa, qb = q0 + dq * t_lo, q0 + dq * t_hi
    ia = max(int(math.floor(min(qa, qb) - SLOP)), 0)
    iz = min(int(math.floor(max(qa, qb) + SLOP)), no - 1)
    best = math.inf
    lo, hi = ta - 1e-12, we + 1e-12
    # the column's stretch widened by what the triangle test lets in (EPS of a cell along the fast
    # axis) and more: a hit outside it is not one of this column's
    w = 4 * EPS / D + 1e-9 if D > 4 * EPS else math.inf
    wlo, whi = t_lo - w, t_hi + w
    for o in range(ia, iz + 1):
        if along_u:
            r, c = o, j
        else:
            r, c = j, o
        if zlo > cell_top[r, c]:
            continue
        h00, h10, h01, h11 = h[r, c], h[r, c + 1], h[r + 1, c], h[r + 1, c + 1]
        fx0, fy0 = u0 - c, v0 - r
        # the lower triangle (fx >= fy), then the upper one
        a1, a2 = h10 - h00, h11 - h10
        num, den = h00 + a1 * fx0 + a2 * fy0 - z0, dz - a1 * du - a2 * dv
        if _may_meet(num, den, wlo, whi):
            tt = num / den
            fx, fy = fx0 + du * tt, fy0 + dv * tt
            if _inside(fx, fy, tt, lo, hi) and fx >= fy - EPS and tt < best:
                best = tt
        a1, a2 = h11 - h01, h01 - h00
        num, den = h00 + a1 * fx0 + a2 * fy0 - z0, dz - a1 * du - a2 * dv
        if _may_meet(num, den, wlo, whi):
            tt = num / den
            fx, fy = fx0 + du * tt, fy0 + dv * tt
            if _inside(fx, fy, tt, lo, hi) and fy >= fx - EPS and tt < best:
                best = tt
    return best


def _may_meet(num, den, wlo, whi):   # pragma: no cover - compiled
    """Whether the plane's hit num / den can lie in [wlo, whi] (no division: most cells tried are
    missed). A ray nearly parallel to the plane is always tried (its hit is ill-conditioned)."""
    if den > 1e-6:
        return num >= wlo * den and num <= whi * den
    if den < -1e-6:
        return num <= wlo * den and num >= whi * den
    return True


def _inside(fx, fy, tt, lo, hi):   # pragma: no cover - compiled
    """Within the cell (to EPS) and the searched stretch."""
    return fx >= -EPS and fx <= 1 + EPS and fy >= -EPS and fy <= 1 + EPS and tt >= lo and tt <= hi
