"""What the robot's body cannot cross on the scenario's terrain, as obstacles for the path search.

The rule is the legged body's (``scenario/ground/crossing.py``), with the body's ``Capability``
(``scenario.bodies.body_capability``: a legged body's declared limits, a wheeled body's estimated ones):

* a *face* (where the ground jumps: a step's riser, a platform's edge, a pit's wall, a ramp's
  side) higher than ``max_step`` is a wall, both ways (up it cannot climb, down it would fall),
  unless it is the wall of a gap no wider than ``max_gap`` (ground within ``max_step`` of the
  upper side comes back within ``max_gap``: a trench it strides over);
* a slope steeper than ``max_slope`` rising more than ``max_step`` in all (a steep ramp) is a
  wall over its whole surface;
* a pit is enclosed by its walls: a hole.

Ramps, steps, platforms and pits are exact (their faces are found along their edges, 5 cm apart,
from ``scenario.ground.surface``'s heights on either side); rough ground and height files are checked on
their grid (a cell where the ground jumps by more than ``max_step`` to a neighbour, steeper than
``max_slope`` over the cell, and connected
cells steeper than ``max_slope`` whose heights span more than ``max_step``).

``barriers(scenario)`` gives them as thin ``BoxObstacle``s named after the element and what it is
("platform 'kerb' (0.30 m step)"): ``verdict/paths.py`` grows them by the footprint like any
obstacle, so the shortest path goes round a step the body cannot climb and up a ramp it can, and
the feasibility check says "no planner can pass this" when the terrain closes every way; the
clearance metric (``verdict/gaps.py``) and the collision safety layer (``sim/safety.py``, a face
from its low side) keep clear of them. A body
that declares no limits (an MJCF robot) gets no barriers. Cached per terrain and body.
"""
from __future__ import annotations

import math
import warnings
from collections import OrderedDict
from dataclasses import replace

import numpy as np

from ..bodies import body_capability
from ..model import BoxObstacle, Scenario
from . import surface as ground
from .crossing import Capability, steep_cells, steep_piece

EDGE_SPACING = 0.05     # m between the points along an element's edge where faces are measured
PROBE = 0.01            # m either side of an edge where the two heights are read
WALL = 0.02             # m: the thickness of a face's barrier box
LONG_EDGE = 1000.0      # m: a longer edge is probed every EDGE_SPACING only near other elements
# The most barriers the path search is given: its visibility graph among 400 thin boxes in a
# weaving layout took ~3.6-6 s and ~1.1 GB, and since the graph gets a node's edges as the search
# reaches it takes 0.8 s and 55 MB (benchmarks/bench_limits.py); beyond, the terrain is left out of
# the path search and the feasibility check, with a TerrainTooFineWarning.
MAX_BARRIERS = 400


class TerrainTooFineWarning(UserWarning):
    """The terrain has more stretches the body cannot cross than the path search plans among in
    bounded time (``MAX_BARRIERS``): the shortest path and the feasibility check ignore it."""
CACHE_SIZE = 256


def barriers(scenario: Scenario, capability: Capability | None = None) -> tuple[BoxObstacle, ...]:
    """The terrain the body cannot cross, as thin boxes (see the module docstring); () without
    terrain or for a body without limits. ``capability`` overrides the body's (for the lenient
    confirmation of ``feasibility``)."""
    if not scenario.terrain:
        return ()
    cap = capability if capability is not None else body_capability(scenario)
    if cap is None:
        return ()
    key = (scenario.terrain, cap)
    try:
        out = _CACHE[key]
        _CACHE.move_to_end(key)
        return out
    except KeyError:
        pass
    out = _piece_barriers(scenario, cap, MAX_BARRIERS)
    if len(out) <= MAX_BARRIERS:
        out += _grid_barriers(scenario, cap, MAX_BARRIERS - len(out))
    if len(out) > MAX_BARRIERS:      # the path search could not plan among them in bounded time
        warnings.warn(TerrainTooFineWarning(
            f"scenario {scenario.name or scenario.source}: its terrain has more than {MAX_BARRIERS} stretches the "
            f"body cannot cross, more than the path search plans among in bounded time: the shortest path and "
            f"the feasibility check ignore the terrain for this scenario (as for a body without declared "
            f"limits); fewer, larger terrain elements or smoother ground keep them"), stacklevel=2)
        out = []
    out = tuple(out)
    _CACHE[key] = out
    if len(_CACHE) > CACHE_SIZE:
        _CACHE.popitem(last=False)
    return out


_CACHE: OrderedDict = OrderedDict()
LOW_SIDE_PROBE = 0.05   # m beyond a face's barrier box where the heights on its two sides are read


def walls_from_below(scenario: Scenario) -> tuple[tuple[BoxObstacle, tuple[float, float, float, float]], ...]:
    """The faces among ``barriers`` (not the steep areas), each with (ux, uy, mid, top): the unit
    vector across it to its lower side, the height halfway up it and its top's: from ground below
    ``mid`` on its lower side it rises as a wall, from above it is an edge to go over (the collision
    safety layer halts only for the former, and only where its scan plane meets it:
    ``sim/safety.py``). () without faces."""
    faces = [b for b in barriers(scenario) if b.width == WALL]
    if not faces:
        return ()
    yaw = np.radians([b.yaw for b in faces])
    nx, ny = -np.sin(yaw), np.cos(yaw)               # across the face (its box's width axis)
    cx, cy = np.array([b.x for b in faces]), np.array([b.y for b in faces])
    reach = WALL / 2 + LOW_SIDE_PROBE
    plus = ground.ground_height(scenario, cx + nx * reach, cy + ny * reach)
    minus = ground.ground_height(scenario, cx - nx * reach, cy - ny * reach)
    sign = np.where(plus < minus, 1.0, -1.0)
    mid, top = (plus + minus) / 2, np.maximum(plus, minus)
    return tuple((b, (float(sign[k] * nx[k]), float(sign[k] * ny[k]), float(mid[k]), float(top[k])))
                 for k, b in enumerate(faces))


def _name(scenario: Scenario, element: int, what: str) -> str:
    return f"{ground.describe_element(scenario.terrain[element])} ({what})"


def _piece_barriers(scenario: Scenario, cap: Capability, budget: int) -> list[BoxObstacle]:
    """Steep ramps, and the faces along every piece's four edges, element by element: an element's
    edge points are probed against the elements near it only (``_near``), so the cost grows with
    the elements, not with their square, and an edge longer than ``LONG_EDGE`` is probed every
    ``EDGE_SPACING`` only where another element comes near it (``_edge_bounds``), so a 10^6 m
    platform costs what a 1000 m one does (it took 23.5 GB)."""
    out: list[BoxObstacle] = []
    terrain = scenario.terrain
    reach = PROBE + (cap.max_gap + 0.04 if cap.max_gap > 0 else 0.0) + 1e-6
    boxes = np.array([np.concatenate([ground.outline(el).min(0), ground.outline(el).max(0)]) for el in terrain])
    mine: dict[int, list] = {}
    for piece in ground.pieces(terrain):
        el = terrain[piece.element]
        x, y, c, s = ground.frame(el)
        rise = piece.top1 - piece.top0
        run = piece.u1 - piece.u0
        if steep_piece(rise, run, cap):
            um = (piece.u0 + piece.u1) / 2
            out.append(BoxObstacle(_name(scenario, piece.element, f"{math.degrees(math.atan2(abs(rise), run)):.0f} "
                                                                   f"deg slope"),
                                   x + c * um, y + s * um, run, el.width, yaw=el.yaw, height=1.0))
        mine.setdefault(piece.element, []).append(piece)
    for element, its in mine.items():
        if len(out) > budget:      # over the path search's budget: the caller drops them all
            break
        near = _near(boxes, element, reach)
        out += _element_faces(scenario, cap, element, its, near, boxes, reach)
    return out


def _near(boxes: np.ndarray, element: int, reach: float) -> np.ndarray:
    """Indices of the elements whose bounding boxes come within ``reach`` of ``element``'s."""
    lo, hi = boxes[element, :2] - reach, boxes[element, 2:] + reach
    return np.flatnonzero((boxes[:, 0] <= hi[0]) & (boxes[:, 2] >= lo[0]) & (boxes[:, 1] <= hi[1])
                          & (boxes[:, 3] >= lo[1]))


def _edge_bounds(a_world: np.ndarray, b_world: np.ndarray, length: float, others: np.ndarray) -> np.ndarray:
    """The bounds (0..1 along the edge) of the stretches an edge is probed in, one point each: every
    EDGE_SPACING for an edge up to LONG_EDGE (as always); a longer one in LONG_EDGE / EDGE_SPACING
    stretches plus every EDGE_SPACING where another element's box (``others``) comes near it."""
    n = max(2, int(math.ceil(length / EDGE_SPACING)) + 1)
    if length <= LONG_EDGE:
        return np.arange(n + 1) / n
    parts = [np.linspace(0.0, 1.0, int(LONG_EDGE / EDGE_SPACING) + 1)]
    d = b_world - a_world
    for box in others:
        t0, t1 = 0.0, 1.0
        for k in range(2):                      # clip the edge to the box (Liang-Barsky)
            if abs(d[k]) < 1e-15:
                if not box[k] <= a_world[k] <= box[k + 2]:
                    t0, t1 = 1.0, 0.0
                continue
            ta, tb = (box[k] - a_world[k]) / d[k], (box[k + 2] - a_world[k]) / d[k]
            t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
        if t1 >= t0:
            step = EDGE_SPACING / length
            parts.append(np.arange(max(0.0, t0 - step), min(1.0, t1 + step), step))
    return np.unique(np.clip(np.concatenate(parts + [np.array([0.0, 1.0])]), 0.0, 1.0))


def _element_faces(scenario: Scenario, cap: Capability, element: int, its: list, near: np.ndarray,
                   boxes: np.ndarray, reach: float) -> list[BoxObstacle]:
    """The faces along the edges of ``element``'s pieces, its points probed on a terrain of the
    elements ``near`` it (the ground at a point is the elements covering it, so that is exact)."""
    el = scenario.terrain[element]
    local = replace(scenario, terrain=tuple(scenario.terrain[i] for i in near))
    others = boxes[near[near != element]] + np.array([-reach, -reach, reach, reach])
    x, y, c, s = ground.frame(el)
    edges, points, normals, count = [], [], [], 0
    for piece in its:
        hw = el.width / 2
        corners = [(piece.u0, -hw), (piece.u1, -hw), (piece.u1, hw), (piece.u0, hw)]
        for k in range(4):        # counter-clockwise round the piece: the outside is on the right
            a, b = corners[k], corners[(k + 1) % 4]
            length = math.hypot(b[0] - a[0], b[1] - a[1])
            aw = np.array([x + c * a[0] - s * a[1], y + s * a[0] + c * a[1]])
            bw = np.array([x + c * b[0] - s * b[1], y + s * b[0] + c * b[1]])
            bounds = _edge_bounds(aw, bw, length, others)
            t = (bounds[:-1] + bounds[1:]) / 2
            lu, lv = a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t
            dx, dy = (b[0] - a[0]) / length, (b[1] - a[1]) / length
            edges.append((a, b, bounds, count))
            count += len(t)
            points.append(np.column_stack([x + c * lu - s * lv, y + s * lu + c * lv]))
            normals.append(np.tile((c * dy + s * dx, s * dy - c * dx), (len(t), 1)))
    p, nrm = np.concatenate(points), np.concatenate(normals)
    inside = ground.ground_height(local, p[:, 0] - nrm[:, 0] * PROBE, p[:, 1] - nrm[:, 1] * PROBE)
    outside = ground.ground_height(local, p[:, 0] + nrm[:, 0] * PROBE, p[:, 1] + nrm[:, 1] * PROBE)
    jump = outside - inside
    wall = np.abs(jump) > cap.max_step + 1e-9
    out: list[BoxObstacle] = []
    if not wall.any():
        return out
    if cap.max_gap > 0:
        at = np.flatnonzero(wall)
        wall[at] = ~_bridged(local, cap, p[at], nrm[at], inside[at], outside[at])
    for a, b, bounds, first in edges:
        n = len(bounds) - 1
        here = wall[first:first + n]
        if not here.any():
            continue
        length = math.hypot(b[0] - a[0], b[1] - a[1])
        dx, dy = (b[0] - a[0]) / length, (b[1] - a[1]) / length
        runs = np.flatnonzero(np.diff(np.concatenate([[0], here.astype(int), [0]])))
        for start, stop in zip(runs[::2], runs[1::2]):
            t0, t1 = bounds[start], bounds[stop]
            mid = (t0 + t1) / 2
            mu, mv = a[0] + (b[0] - a[0]) * mid, a[1] + (b[1] - a[1]) * mid
            height = float(np.abs(jump[first + start:first + stop]).max())
            out.append(BoxObstacle(_name(scenario, element, f"{height:.2f} m step"),
                                   x + c * mu - s * mv, y + s * mu + c * mv, (t1 - t0) * length, WALL,
                                   yaw=math.degrees(math.atan2(s * dx + c * dy, c * dx - s * dy)), height=1.0))
    return out


def _bridged(scenario, cap, p, nrm, inside, outside) -> np.ndarray:
    """Per edge point: the face is a wall of a gap no wider than max_gap (from the upper side,
    ground within max_step of it comes back within max_gap across the lower side)."""
    high = np.maximum(inside, outside)
    toward = np.where(outside < inside, 1.0, -1.0)[:, None]    # across the lower side
    k = (PROBE + np.arange(1, int(math.ceil(cap.max_gap / 0.02)) + 1) * 0.02)[None]
    qx = p[:, 0:1] + toward * nrm[:, 0:1] * k
    qy = p[:, 1:2] + toward * nrm[:, 1:2] * k
    back = ground.ground_height(scenario, qx, qy) >= high[:, None] - cap.max_step - 1e-9
    return back.any(axis=1)


def _grid_barriers(scenario: Scenario, cap: Capability, budget: int) -> list[BoxObstacle]:
    """Rough ground and height files: barrier cells on the element's own grid, as boxes (a run
    of cells along a row is one box); it stops once there are more than ``budget``."""
    out = []
    from .heightmap import height_grid

    for i in ground.grid_elements(scenario.terrain):
        el = scenario.terrain[i]
        grid = height_grid(el, scenario)
        heights = np.asarray(grid.heights, dtype=float)
        dx, dy = grid.cell
        blocked = _blocked_cells(heights, dx, dy, cap)
        if not blocked.any():
            continue
        x, y, c, s = ground.frame(el)
        open_runs: dict[tuple[int, int], int] = {}     # (start, stop) of a run -> its first row
        for r in range(blocked.shape[0] + 1):
            runs = set()
            if r < blocked.shape[0]:
                edges = np.flatnonzero(np.diff(np.concatenate([[0], blocked[r].astype(int), [0]])))
                runs = set(zip(edges[::2].tolist(), edges[1::2].tolist()))
            for run in [k for k in open_runs if k not in runs]:   # a run that stops: one box, its rows
                out.append(_cells_box(scenario, i, el, (x, y, c, s), run, open_runs.pop(run), r, dx, dy))
            for run in runs:
                open_runs.setdefault(run, r)
            if len(out) > budget:
                return out
    return out


def _cells_box(scenario: Scenario, i: int, el, pose, run: tuple[int, int], r0: int, r1: int,
               dx: float, dy: float) -> BoxObstacle:
    """The box over grid cells ``run`` (columns start..stop) of rows r0..r1 (r1 excluded): the
    same run in consecutive rows is one box (a wall along the grid, a blob's core)."""
    x, y, c, s = pose
    start, stop = run
    u0, u1 = -el.length / 2 + (start - 0.5) * dx, -el.length / 2 + (stop - 0.5) * dx
    v0, v1 = -el.width / 2 + (r0 - 0.5) * dy, -el.width / 2 + (r1 - 0.5) * dy
    um, vm = (u0 + u1) / 2, (v0 + v1) / 2
    return BoxObstacle(_name(scenario, i, "ground it cannot cross"), x + c * um - s * vm, y + s * um + c * vm,
                       max(u1 - u0, WALL), max(v1 - v0, WALL), yaw=el.yaw, height=1.0)


def _blocked_cells(h: np.ndarray, dx: float, dy: float, cap: Capability) -> np.ndarray:
    """Cells of a height grid the body cannot cross: a jump of more than max_step to a neighbour
    that is also steeper than max_slope over the cell (on a coarse grid a rise between samples is
    a slope: issue 36), or steep ground (``crossing.steep_cells``: a connected patch steeper than max_slope whose
    heights span more than max_step)."""
    blocked = np.zeros(h.shape, dtype=bool)
    steep = math.tan(math.radians(min(cap.max_slope, 89.9)))
    rise_x, rise_y = np.abs(np.diff(h, axis=1)), np.abs(np.diff(h, axis=0))
    # A jump is a face only where it is steeper than the body climbs: MuJoCo's heightfield is a
    # surface of triangles between the samples, so a rise over a coarse grid's cell is a slope.
    jx = (rise_x > cap.max_step) & (rise_x > steep * dx)
    jy = (rise_y > cap.max_step) & (rise_y > steep * dy)
    blocked[:, 1:] |= jx
    blocked[:, :-1] |= jx
    blocked[1:, :] |= jy
    blocked[:-1, :] |= jy
    return blocked | steep_cells(h, dx, dy, cap)


def lenient(cap: Capability) -> Capability:
    """A more capable body than ``cap`` (half as much again, 5 degrees steeper): what
    ``feasibility`` confirms an impassable verdict with, so an estimate's error never makes a
    passable scenario a setup error."""
    return replace(cap, max_step=cap.max_step * 1.5, max_slope=min(cap.max_slope + 5.0, 89.0),
                   max_gap=cap.max_gap * 1.5)
