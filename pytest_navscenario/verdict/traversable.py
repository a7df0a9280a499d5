"""What the robot's body cannot cross on the scenario's terrain, as obstacles for the path search.

The rule is the legged body's (``scenario/ground/crossing.py``), with the body's ``Capability``
(``crossing.body_capability``: a legged body's declared limits, a wheeled body's estimated ones):

* a *face* (where the ground jumps: a step's riser, a platform's edge, a pit's wall, a ramp's
  side) higher than ``max_step`` is a wall, both ways (up it cannot climb, down it would fall),
  unless it is the wall of a gap no wider than ``max_gap`` (ground within ``max_step`` of the
  upper side comes back within ``max_gap``: a trench it strides over);
* a slope steeper than ``max_slope`` rising more than ``max_step`` in all (a steep ramp) is a
  wall over its whole surface;
* a pit is enclosed by its walls: a hole.

Ramps, steps, platforms and pits are exact (their faces are found along their edges, 5 cm apart,
from ``scenario.ground.surface``'s heights on either side); rough ground and height files are checked on
their grid (a cell where the ground jumps by more than ``max_step`` to a neighbour, and connected
cells steeper than ``max_slope`` whose heights span more than ``max_step``).

``barriers(scenario)`` gives them as thin ``BoxObstacle``s named after the element and what it is
("platform 'kerb' (0.30 m step)"): ``verdict/paths.py`` grows them by the footprint like any
obstacle, so the shortest path goes round a step the body cannot climb and up a ramp it can, and
the feasibility check says "no planner can pass this" when the terrain closes every way. A body
that declares no limits (an MJCF robot) gets no barriers. Cached per terrain and body.
"""
from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import replace

import numpy as np

from ..scenario.ground import surface as ground
from ..scenario.ground.crossing import Capability, body_capability, steep_cells, steep_piece
from ..scenario.model import BoxObstacle, Scenario

EDGE_SPACING = 0.05     # m between the points along an element's edge where faces are measured
PROBE = 0.01            # m either side of an edge where the two heights are read
WALL = 0.02             # m: the thickness of a face's barrier box
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
    out = tuple(_piece_barriers(scenario, cap)) + tuple(_grid_barriers(scenario, cap))
    _CACHE[key] = out
    if len(_CACHE) > CACHE_SIZE:
        _CACHE.popitem(last=False)
    return out


_CACHE: OrderedDict = OrderedDict()


def _name(scenario: Scenario, element: int, what: str) -> str:
    return f"{ground.describe_element(scenario.terrain[element])} ({what})"


def _piece_barriers(scenario: Scenario, cap: Capability) -> list[BoxObstacle]:
    """Steep ramps, and the faces along every piece's four edges: all edges' points probed in one
    call to the ground function for each side (and one for the gaps), then cut into runs."""
    out = []
    edges = []          # (element, pose, a, b, n, first point)
    points, normals = [], []
    for piece in ground.pieces(scenario.terrain):
        el = scenario.terrain[piece.element]
        x, y, c, s = ground.frame(el)
        rise = piece.top1 - piece.top0
        run = piece.u1 - piece.u0
        if steep_piece(rise, run, cap):
            um = (piece.u0 + piece.u1) / 2
            out.append(BoxObstacle(_name(scenario, piece.element, f"{math.degrees(math.atan2(abs(rise), run)):.0f} "
                                                                   f"deg slope"),
                                   x + c * um, y + s * um, run, el.width, yaw=el.yaw, height=1.0))
        hw = el.width / 2
        corners = [(piece.u0, -hw), (piece.u1, -hw), (piece.u1, hw), (piece.u0, hw)]
        for k in range(4):        # counter-clockwise round the piece: the outside is on the right
            a, b = corners[k], corners[(k + 1) % 4]
            length = math.hypot(b[0] - a[0], b[1] - a[1])
            n = max(2, int(math.ceil(length / EDGE_SPACING)) + 1)
            t = (np.arange(n) + 0.5) / n
            lu, lv = a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t
            dx, dy = (b[0] - a[0]) / length, (b[1] - a[1]) / length
            edges.append((piece.element, (x, y, c, s), a, b, n, sum(len(p) for p in points)))
            points.append(np.column_stack([x + c * lu - s * lv, y + s * lu + c * lv]))
            normals.append(np.tile((c * dy + s * dx, s * dy - c * dx), (n, 1)))
    if not edges:
        return out
    p, nrm = np.concatenate(points), np.concatenate(normals)
    inside = ground.ground_height(scenario, p[:, 0] - nrm[:, 0] * PROBE, p[:, 1] - nrm[:, 1] * PROBE)
    outside = ground.ground_height(scenario, p[:, 0] + nrm[:, 0] * PROBE, p[:, 1] + nrm[:, 1] * PROBE)
    jump = outside - inside
    wall = np.abs(jump) > cap.max_step + 1e-9
    if not wall.any():
        return out
    if cap.max_gap > 0:
        at = np.flatnonzero(wall)
        wall[at] = ~_bridged(scenario, cap, p[at], nrm[at], inside[at], outside[at])
    for element, (x, y, c, s), a, b, n, first in edges:
        mine = wall[first:first + n]
        if not mine.any():
            continue
        length = math.hypot(b[0] - a[0], b[1] - a[1])
        dx, dy = (b[0] - a[0]) / length, (b[1] - a[1]) / length
        runs = np.flatnonzero(np.diff(np.concatenate([[0], mine.astype(int), [0]])))
        for start, stop in zip(runs[::2], runs[1::2]):
            t0, t1 = start / n, stop / n
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


def _grid_barriers(scenario: Scenario, cap: Capability) -> list[BoxObstacle]:
    """Rough ground and height files: barrier cells on the element's own grid, as boxes (a run
    of cells along a row is one box)."""
    out = []
    from ..scenario.ground.heightmap import height_grid

    for i in ground.grid_elements(scenario.terrain):
        el = scenario.terrain[i]
        grid = height_grid(el, scenario)
        heights = np.asarray(grid.heights, dtype=float)
        dx, dy = grid.cell
        blocked = _blocked_cells(heights, dx, dy, cap)
        if not blocked.any():
            continue
        x, y, c, s = ground.frame(el)
        for r in range(blocked.shape[0]):
            runs = np.flatnonzero(np.diff(np.concatenate([[0], blocked[r].astype(int), [0]])))
            for start, stop in zip(runs[::2], runs[1::2]):
                u0, u1 = -el.length / 2 + (start - 0.5) * dx, -el.length / 2 + (stop - 0.5) * dx
                v = -el.width / 2 + r * dy
                um = (u0 + u1) / 2
                out.append(BoxObstacle(_name(scenario, i, "ground it cannot cross"), x + c * um - s * v,
                                       y + s * um + c * v, max(u1 - u0, WALL), max(dy, WALL), yaw=el.yaw,
                                       height=1.0))
    return out


def _blocked_cells(h: np.ndarray, dx: float, dy: float, cap: Capability) -> np.ndarray:
    """Cells of a height grid the body cannot cross: a jump of more than max_step to a neighbour,
    or steep ground (``crossing.steep_cells``: a connected patch steeper than max_slope whose
    heights span more than max_step)."""
    blocked = np.zeros(h.shape, dtype=bool)
    jx = np.abs(np.diff(h, axis=1)) > cap.max_step
    jy = np.abs(np.diff(h, axis=0)) > cap.max_step
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
