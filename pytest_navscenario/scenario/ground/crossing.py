"""What a body can cross, as one rule over a ground profile: the legged body's capability model
(sim/bodies/legged.py) walks it every tick, and the traversable grid (scenario/ground/traversable.py)
applies it between neighbouring cells, so the simulation and the feasibility check agree.

A *profile* is the ground's height at evenly spaced points along a line (``spacing`` metres
apart), walked from a *level* (the height the body's foot, or centre, stands at now):

* ground that changes by at most ``spacing * tan(max_slope)`` per sample is walked on (a slope
  within the body's limit);
* a steeper stretch (a step's face, a kerb, a slope steeper than ``max_slope``) is taken in one
  go: rising by at most ``max_step`` it is climbed; rising more it is a *barrier* ("step", or
  "slope" when the stretch is wider than FOOT);
* a steeper stretch down by at most ``max_step`` is stepped down; deeper, it is a drop edge: when
  ground within ``max_step`` of the level comes back within ``max_gap`` (a trench, a gap between
  two platforms) the body strides over it (its support is the straight line across); else it is a
  "drop" barrier: a body that goes on falls.

Distances are exact to the spacing (SPACING, 2 cm, in the simulation). No MuJoCo, no I/O.

A profile sees the slope along its line only. *Steep ground* (``steep_ground``) is the slope in
every direction: ground steeper than ``max_slope`` whose height spans more than ``max_step`` (a
steep ramp's whole surface, a steep patch of a height grid). The path search makes it a wall
(scenario/ground/traversable.py) and the legged body does not walk onto it from level ground, whichever way
it comes (``walk``'s ``steep``): across a bank or up it diagonally, where the rise along its way is
within ``max_slope``, as well as straight up.
"""
from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..bodies.record import Capability

SPACING = 0.02    # m between the samples of a profile (a threshold of 5 cm is seen)
FOOT = 0.1        # m: a steep stretch narrower than this is a step's face, wider a slope (words only)
EPS = 1e-9


@dataclass(frozen=True)
class Barrier:
    """Where a profile stops the body: ``index`` is the last sample it stands on before it;
    ``kind`` "step" or "slope" (a rise it cannot climb: it is stopped), "steep" (onto steep ground
    the line itself rises within max_slope on: it is stopped) or "drop" (a drop deeper
    than max_step with no ground back within max_gap: it falls if it goes on); ``height`` the rise
    or the depth (m), ``width`` the steep stretch's or the gap's width (inf: no far side seen)."""
    kind: str
    index: int
    height: float
    width: float


def walk(h: Sequence[float], spacing: float, level: float, cap: Capability,
         steep: Sequence[bool] | None = None) -> tuple[list[float], Barrier | None]:
    """Walk the profile ``h`` (heights at 0, spacing, 2 spacing ...) from ``level`` at its first
    sample: (the support height at each sample up to the first barrier, NaN beyond; the barrier or
    None). The support is the ground, or the straight line across a gap it strides over.
    ``steep`` (per sample: on steep ground, ``steep_ground``): walkable ground along the line that
    leads from level ground onto steep ground is a "steep" barrier (height 0, width 0)."""
    n = len(h)
    tol = spacing * math.tan(math.radians(min(cap.max_slope, 89.9))) + EPS
    step = cap.max_step + EPS
    reach = int(math.floor(cap.max_gap / spacing + EPS)) + 1   # samples from a drop edge to the far side
    support = [math.nan] * n
    support[0] = cur = float(level)
    k = 0
    while k < n - 1:
        nxt = h[k + 1]
        if abs(nxt - cur) <= tol:               # walkable ground
            if steep is not None and steep[k + 1] and not steep[k]:
                return support, Barrier("steep", k, 0.0, 0.0)
            k += 1
            support[k] = cur = nxt
            continue
        j = k + 1
        if nxt > cur:                          # a steep rise: climbed in one go if low enough
            while j + 1 < n and h[j + 1] - h[j] > tol:
                j += 1
            rise = h[j] - cur
            if rise > step:
                width = (j - k - 1) * spacing
                return support, Barrier("slope" if width > FOOT else "step", k, rise, width)
        else:                                  # a steep drop: stepped down if shallow enough
            while j + 1 < n and h[j + 1] - h[j] < -tol:
                j += 1
            if cur - h[j] > step:
                far = next((i for i in range(j, min(n, k + reach + 1)) if h[i] >= cur - step), None)
                if far is None:
                    seen = h[k + 1:min(n, k + reach + 1)]
                    return support, Barrier("drop", k, cur - min(seen), math.inf)
                if h[far] - cur > step:        # the far side is a wall: it cannot get up there
                    return support, Barrier("step", k, h[far] - cur, (far - k - 1) * spacing)
                for i in range(k + 1, far):    # strides over: supported on the line across
                    support[i] = cur + (h[far] - cur) * (i - k) / (far - k)
                support[far] = cur = h[far]
                k = far
                continue
        for i in range(k + 1, j + 1):
            support[i] = h[i]
        cur = h[j]
        k = j
    return support, None


def look_ahead(cap: Capability, move: float, spacing: float = SPACING) -> int:
    """Samples a profile needs to decide a move of ``move`` metres: the move, the widest gap and
    two samples more (so a far side within max_gap is seen)."""
    return int(math.ceil((move + cap.max_gap) / spacing)) + 3


# ---------------------------------------------------------------- steep ground, in every direction


def steep_piece(rise: float, run: float, cap: Capability) -> bool:
    """A ramp's surface (rising ``rise`` over ``run``) is steep ground for ``cap``."""
    return abs(rise) > cap.max_step and math.degrees(math.atan2(abs(rise), run)) > cap.max_slope


def steep_cells(h: np.ndarray, dx: float, dy: float, cap: Capability) -> np.ndarray:
    """Cells of a height grid (rows along y, ``dx`` by ``dy`` apart) on steep ground: connected
    (8 neighbours) cells whose slope (the gradient's size) passes max_slope, in patches whose
    heights span more than max_step."""
    gx = np.gradient(h, dx, axis=1) if h.shape[1] > 1 else np.zeros_like(h)
    gy = np.gradient(h, dy, axis=0) if h.shape[0] > 1 else np.zeros_like(h)
    steep = np.hypot(gx, gy) > math.tan(math.radians(min(cap.max_slope, 89.9)))
    if not steep.any():
        return steep
    roots = _label(steep)[steep]                # each steep cell's component (its smallest flat index)
    high = np.full(h.size, -np.inf)
    low = np.full(h.size, np.inf)
    np.maximum.at(high, roots, h[steep])
    np.minimum.at(low, roots, h[steep])
    out = np.zeros(h.shape, dtype=bool)
    out[steep] = (high - low)[roots] > cap.max_step
    return out


def _label(mask: np.ndarray) -> np.ndarray:
    """Connected components (8-neighbours) of ``mask``: each cell's label is the smallest flat
    index in its component (-1 outside). Union by hooking each edge's larger root under its
    smaller one, then pointer jumping to the roots, until no edge joins two roots: a few rounds
    of O(cells) numpy work whatever the components' shapes (propagating minima cell by cell took
    as many rounds as a component is long: minutes for a winding one on a 1024^2 grid)."""
    rows, cols = mask.shape
    index = np.arange(mask.size).reshape(mask.shape)
    a_parts, b_parts = [], []
    for (dy, dx) in ((0, 1), (1, 0), (1, 1), (1, -1)):      # each neighbour pair once
        ys, ye = 0, rows - dy
        xs, xe = max(0, -dx), cols - max(0, dx)
        both = mask[ys:ye, xs:xe] & mask[ys + dy:ye + dy, xs + dx:xe + dx]
        a_parts.append(index[ys:ye, xs:xe][both])
        b_parts.append(index[ys + dy:ye + dy, xs + dx:xe + dx][both])
    a, b = np.concatenate(a_parts), np.concatenate(b_parts)
    parent = index.ravel().copy()
    while a.size:
        pa, pb = parent[a], parent[b]
        keep = pa != pb
        a, b, pa, pb = a[keep], b[keep], pa[keep], pb[keep]
        if not a.size:
            break
        np.minimum.at(parent, np.maximum(pa, pb), np.minimum(pa, pb))
        while True:                                  # every cell straight to its root
            up = parent[parent]
            if np.array_equal(up, parent):
                break
            parent = up
    return np.where(mask, parent.reshape(mask.shape), -1)


def steep_areas(scenario, cap: Capability) -> tuple:
    """The scenario's steep ground for ``cap``: (element index, piece or None, steep cell mask or
    None) for each steep ramp piece and each height grid with steep cells. Cached per terrain,
    folder and capability (the legged body asks every tick)."""
    key = (scenario.terrain, getattr(scenario, "source", None), cap)
    try:
        return _STEEP[key]
    except KeyError:
        pass
    from . import surface as ground
    from .heightmap import height_grid

    out = []
    for piece in ground.pieces(scenario.terrain):
        if steep_piece(piece.top1 - piece.top0, piece.u1 - piece.u0, cap):
            out.append((piece.element, piece, None))
    for i in ground.grid_elements(scenario.terrain):
        grid = height_grid(scenario.terrain[i], scenario)
        cells = steep_cells(np.asarray(grid.heights, dtype=float), grid.cell[0], grid.cell[1], cap)
        if cells.any():
            out.append((i, None, cells))
    if len(_STEEP) >= 256:
        _STEEP.popitem(last=False)
    _STEEP[key] = out = tuple(out)
    return out


_STEEP: OrderedDict = OrderedDict()


def steep_ground(scenario, cap: Capability, px, py) -> np.ndarray:
    """Per world point (arrays of one shape): on steep ground for ``cap`` (see ``steep_areas``)."""
    px, py = np.asarray(px, dtype=float), np.asarray(py, dtype=float)
    out = np.zeros(np.broadcast(px, py).shape, dtype=bool)
    areas = steep_areas(scenario, cap) if scenario.terrain else ()
    if not areas:
        return out
    from . import surface as ground
    from .heightmap import height_grid

    for i, piece, cells in areas:
        el = scenario.terrain[i]
        u, v = ground.to_local(el, px, py)
        if piece is not None:
            out |= (u >= piece.u0) & (u <= piece.u1) & (np.abs(v) <= el.width / 2)
            continue
        grid = height_grid(el, scenario)
        rows, cols = cells.shape
        col = np.rint((u + el.length / 2) / grid.cell[0]).astype(int)
        row = np.rint((v + el.width / 2) / grid.cell[1]).astype(int)
        inside = (col >= 0) & (col < cols) & (row >= 0) & (row < rows)
        out |= inside & cells[np.clip(row, 0, rows - 1), np.clip(col, 0, cols - 1)]
    return out
