"""A lidar-built occupancy grid and a wavefront route on it, for escaping local minima.

A purely local planner (DWA, potential field) stalls where the straight line to the target
runs into a wall it cannot see around: a dead end, the outer wall of a bend. Like the global
planner of a navigation stack, :class:`LidarGrid` remembers every lidar return of the episode
in a world-frame grid (no map is given: unknown cells count as free), and :meth:`LidarGrid.plan`
computes, on request, the number of grid steps from every reachable cell to the target with the
obstacles inflated by the robot's half width plus a margin (breadth-first wavefront, 8-connected).
:meth:`LidarGrid.carrot` then follows that field downhill from the robot to a point ``lookahead``
metres along the route, which the local planner aims at instead of the target.

Cost: marking the returns is a few array operations per tick; a plan is about 0.6 ms for a
12 000-cell window (``_wavefront``: a step of the wave is a few big-integer operations on the
window's cells as bits), so the caller plans only when it is stuck; a carrot is about 15 us (a
walk over the flat field through a memoryview). The obstacles' inflation is separable (a row-wise pass,
then a column-wise one: the same cells as shifting by every offset of the disk, in far fewer
array passes). ``tests/subjects/test_route_grid.py`` checks the wavefront against a plain
breadth-first search.
"""
from __future__ import annotations

import functools
import math

import numpy as np

MAX_CELLS = 500          # grid side, cells, at most: the resolution grows for big worlds
_STEPS = ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1))


def _disk(radius: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(-radius, radius + 1) for j in range(-radius, radius + 1)
            if i * i + j * j <= radius * radius + radius]


@functools.lru_cache(maxsize=64)
def _inflation_disk(radius: int) -> tuple[tuple[tuple[int, int], ...], tuple[tuple[int, int], ...]]:
    """(the disk's cells, its rows) of a radius in cells: the same few radii every episode, so
    remembered (twice an episode at reset, ~0.1 ms: issue 35)."""
    disk = _disk(radius)
    return tuple(disk), tuple(_disk_rows(disk))


def _closest_reached(f: np.ndarray, ri: int, rj: int, r: int) -> tuple[int, int] | None:
    """(row, column) of the reached cell (``f >= 0``) nearest to (ri, rj), the first in row-major
    order on ties; None when none is. Looked for in a window of half side ``r`` around it, doubled
    until the nearest found lies within it (then no cell outside is as near, and the window's
    row-major order is the field's), else over the whole field: in a crowded world the robot is
    often in a gap too narrow for the route, and the whole field a tick cost 0.3 ms."""
    rows, cols = f.shape
    while True:
        a0, a1 = min(max(ri - r, 0), rows), min(max(ri + r + 1, 0), rows)
        b0, b1 = min(max(rj - r, 0), cols), min(max(rj + r + 1, 0), cols)
        whole = a0 == 0 and b0 == 0 and a1 == rows and b1 == cols
        reached = np.argwhere(f[a0:a1, b0:b1] >= 0)
        if len(reached):
            reached += (a0, b0)
            d2 = ((reached - (ri, rj)) ** 2).sum(axis=1)
            k = int(np.argmin(d2))
            if whole or int(d2[k]) <= r * r:
                return int(reached[k, 0]), int(reached[k, 1])
        elif whole:
            return None
        r *= 2


def _open_grid(i0: int, i1: int, j0: int, j1: int) -> tuple[np.ndarray, np.ndarray]:
    """``np.ogrid[i0:i1, j0:j1]`` (the same arrays) without its generic indexing machinery."""
    return np.arange(i0, i1)[:, None], np.arange(j0, j1)[None, :]


def _disk_rows(disk: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """The disk as rows: (row offset, half width w) for the column offsets -w..w of each row."""
    rows: dict[int, int] = {}
    for i, j in disk:
        rows[i] = max(rows.get(i, 0), abs(j))
    assert sorted(disk) == sorted((i, j) for i, w in rows.items() for j in range(-w, w + 1))
    return sorted(rows.items())


def _dilate(occ: np.ndarray, rows: list[tuple[int, int]]) -> np.ndarray:
    """``occ`` OR-ed with itself shifted by every offset of the disk given as ``rows``: first
    along each row by -w..w (one pass per distinct w), then by each row offset."""
    widths = sorted({w for _, w in rows})
    by_width = {}
    h = occ.copy()
    w_done = 0
    for w in widths:
        for k in range(w_done + 1, w + 1):
            _shift_or(h, occ, 0, k)
            _shift_or(h, occ, 0, -k)
        w_done = w
        by_width[w] = h.copy() if w != widths[-1] else h
    out = np.zeros_like(occ)
    for di, w in rows:
        _shift_or(out, by_width[w], di, 0)
    return out


def _shift_or(out: np.ndarray, src: np.ndarray, di: int, dj: int) -> None:
    """out |= src shifted by (di, dj) cells (no wrap-around)."""
    h, w = src.shape
    oi, si = (slice(di, h), slice(0, h - di)) if di >= 0 else (slice(0, h + di), slice(-di, h))
    oj, sj = (slice(dj, w), slice(0, w - dj)) if dj >= 0 else (slice(0, w + dj), slice(-dj, w))
    out[oi, oj] |= src[si, sj]


def _as_int(mask: np.ndarray) -> int:
    """A flat boolean mask as the bits of one Python int (bit k = cell k)."""
    return int.from_bytes(np.packbits(mask, bitorder="little").tobytes(), "little")


def _as_mask(bits: int, n: int) -> np.ndarray:
    """The first ``n`` bits of ``bits`` as a flat boolean mask (the inverse of ``_as_int``)."""
    raw = np.frombuffer(bits.to_bytes((n + 7) // 8, "little"), dtype=np.uint8)
    return np.unpackbits(raw, count=n, bitorder="little").view(bool)


def _wavefront(field: np.ndarray, open_: np.ndarray, seed: np.ndarray, near: np.ndarray, limit: int,
               ahead: int) -> tuple[int | None, np.ndarray]:
    """Breadth-first steps (8-connected) from ``seed`` through the ``open_`` cells into ``field``,
    until the steps run out (``limit``) or ``ahead`` steps after the wave first reaches a
    ``near`` cell. Returns (that last step, None if no near cell was reached; the field with a
    border of -1, flattened).

    The grid gets a border of one closed cell and is flattened into the bits of a Python int
    (bit k = cell k), so that a step is a handful of big-integer operations of a few hundred
    machine words each, far cheaper than as many numpy calls: the frontier's 3 x 3 dilation is
    shifts by +-1 (along the rows) and +-(width + 2) (across them); a border cell is never open,
    so nothing wraps from one row into the next. Each step's new cells are OR-ed into the bit
    planes of the step number, which become the field once, at the end."""
    h, w = field.shape
    stride = w + 2
    n = (h + 2) * stride

    def padded(a: np.ndarray, fill) -> np.ndarray:
        out = np.full((h + 2, stride), fill, dtype=a.dtype)
        out[1:-1, 1:-1] = a
        return out.reshape(-1)

    open_start = _as_int(padded(open_, False))
    free, front, near_bits = open_start, _as_int(padded(seed, False)), _as_int(padded(near, False))
    planes: list[int] = []              # planes[b]: the cells whose step has bit b set
    reached_near = bool(front & near_bits)
    step, extra = 0, None
    alive = front != 0
    while alive and step < limit:
        step += 1
        rows = front | (front << 1) | (front >> 1)
        grow = (rows | (rows << stride) | (rows >> stride)) & free
        free ^= grow                                          # grow is within free: free &= ~grow
        s, b = step, 0
        while s:
            if s & 1:
                if b >= len(planes):
                    planes.extend([0] * (b + 1 - len(planes)))
                planes[b] |= grow
            s >>= 1
            b += 1
        if extra is None and (reached_near or grow & near_bits):
            extra = step + ahead
        if extra is not None and step >= extra:
            break
        alive = grow != 0
        front = grow
    field_p = padded(field, -1)
    grown = _as_mask(open_start ^ free, n)
    if grown.any():
        steps = np.zeros(n, dtype=np.int32)
        for b, plane in enumerate(planes):
            steps[_as_mask(plane, n)] += 1 << b
        field_p[grown] = steps[grown]
    field[...] = field_p.reshape(h + 2, stride)[1:-1, 1:-1]
    return extra, field_p


class LidarGrid:
    """Occupied cells seen by the lidar over one episode, in a fixed world-frame grid that
    covers ``points`` (start, waypoints, goal) plus ``border`` metres."""

    def __init__(self, points: np.ndarray, border: float, inflation: float = 0.3, res: float = 0.1):
        lo = points.min(axis=0) - border
        hi = points.max(axis=0) + border
        self.res = res = max(res, float((hi - lo).max()) / MAX_CELLS)
        self.origin = lo
        self.shape = (int(math.ceil((hi[1] - lo[1]) / res)) + 1,
                      int(math.ceil((hi[0] - lo[0]) / res)) + 1)      # rows = y, columns = x
        self.occupied = np.zeros(self.shape, dtype=bool)
        self._rot = np.zeros((2, 3))
        self.set_inflation(inflation)
        self.field: np.ndarray | None = None    # steps to the target, -1 = not reached
        self._flat = np.empty(0, dtype=np.int32)  # the field with a border of -1, flattened
        self._near = r = int(0.6 / res) + 1     # cells: the robot's surroundings (plan) and carrot's window
        self._near_cost = np.hypot(*_open_grid(-r, r + 1, -r, r + 1)) * 0.5
        self.box = (0, 0)                        # (row, column) of field[0, 0] in the grid

    def set_inflation(self, inflation: float) -> None:
        """Cells within ``inflation`` metres of a return are not on a route."""
        self.inflate, self._inflate_rows = _inflation_disk(max(1, int(round(inflation / self.res))))

    def cell(self, x: float, y: float) -> tuple[int, int]:
        return (int((y - self.origin[1]) / self.res + 0.5), int((x - self.origin[0]) / self.res + 0.5))

    def mark(self, x: float, y: float, c: float, s: float, points: np.ndarray) -> None:
        """Record lidar returns ``points`` (2, n), robot frame, seen from pose (x, y) with
        heading cos ``c``, sin ``s``. Returns beyond the grid are not recorded."""
        k = 1.0 / self.res
        rot = self._rot
        rot[0, 0], rot[0, 1], rot[1, 0], rot[1, 1] = c * k, -s * k, s * k, c * k
        rot[0, 2] = (x - self.origin[0]) * k + 0.5
        rot[1, 2] = (y - self.origin[1]) * k + 0.5
        q = (rot[:, :2] @ points + rot[:, 2:]).astype(np.intp)        # (column, row) per point
        u = q.view(np.uintp)                     # a negative index is huge unsigned: one test a side
        ok = (u[0] < self.shape[1]) & (u[1] < self.shape[0])
        self.occupied[q[1, ok], q[0, ok]] = True

    def plan(self, robot: tuple[float, float], target: tuple[float, float], reach: float,
             border: float = 4.0) -> bool:
        """Wavefront from every free cell within ``reach`` of ``target`` over a window around
        robot and target. False when the robot's surroundings are not reached."""
        res = self.res
        ri, rj = self.cell(*robot)
        ti, tj = self.cell(*target)
        b = int(min(border / res, sum(self.shape)))
        i0, i1 = max(min(ri, ti) - b, 0), min(max(ri, ti) + b + 1, self.shape[0])
        j0, j1 = max(min(rj, tj) - b, 0), min(max(rj, tj) + b + 1, self.shape[1])
        if i0 >= i1 or j0 >= j1:
            self.field = None
            return False
        free = ~_dilate(self.occupied[i0:i1, j0:j1], self._inflate_rows)
        ii, jj = _open_grid(i0, i1, j0, j1)
        k = max(int(reach / res), 0)
        seed = ((ii - ti) ** 2 + (jj - tj) ** 2 <= k * k) & free
        if not seed.any():                   # the target is boxed in: aim at its cell anyway
            seed = (ii - ti) ** 2 + (jj - tj) ** 2 <= k * k
        field = np.full(free.shape, -1, dtype=np.int32)
        field[seed] = 0
        near = ((ii - ri) ** 2 + (jj - rj) ** 2 <= self._near ** 2)
        extra, self._flat = _wavefront(field, free & ~seed, seed, near, 4 * (free.shape[0] + free.shape[1]),
                                       int(1.5 / res))
        self.field, self.box = field, (i0, j0)
        return extra is not None

    def carrot(self, robot: tuple[float, float], lookahead: float) -> tuple[float, float] | None:
        """The point ``lookahead`` metres along the route from the robot, world frame (None
        when no route reaches the robot's surroundings)."""
        f = self.field
        if f is None:
            return None
        res = self.res
        ri, rj = self.cell(*robot)
        ri, rj = ri - self.box[0], rj - self.box[1]
        r = self._near
        a0, a1 = max(ri - r, 0), min(ri + r + 1, f.shape[0])
        b0, b1 = max(rj - r, 0), min(rj + r + 1, f.shape[1])
        win = f[a0:a1, b0:b1]
        unreached = win < 0
        if a0 < a1 and b0 < b1 and not unreached.all():
            sub = win.astype(float)
            # prefer close cells at the same distance: half the distance in cells (a table)
            sub += self._near_cost[a0 - ri + r:a1 - ri + r, b0 - rj + r:b1 - rj + r]
            sub[unreached] = np.inf
            flat = int(np.argmin(sub))
            ci, cj = a0 + flat // sub.shape[1], b0 + flat % sub.shape[1]
        else:
            # the robot is in a gap too narrow for the route: head for the closest route cell
            closest = _closest_reached(f, ri, rj, 4 * r)
            if closest is None:
                return None
            ci, cj = closest
            return (self.origin[0] + (cj + self.box[1]) * res, self.origin[1] + (ci + self.box[0]) * res)
        # downhill on the field with its border of -1 (no bounds checks), read through a
        # memoryview: a Python int per cell read, much cheaper than f[i, j], and no copy; the
        # first lower neighbour in _STEPS order
        at = memoryview(self._flat)
        stride = f.shape[1] + 2
        k = (ci + 1) * stride + cj + 1
        deltas = [di * stride + dj for di, dj in _STEPS]
        for _ in range(max(int(lookahead / res), 1)):
            here = at[k]
            if here <= 0:
                break
            for d in deltas:
                if 0 <= at[k + d] < here:
                    k += d
                    break
            else:
                break
        ci, cj = k // stride - 1, k % stride - 1
        return (self.origin[0] + (cj + self.box[1]) * res, self.origin[1] + (ci + self.box[0]) * res)
