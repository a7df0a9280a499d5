"""The ground as a pure function: the height under any (x, y) of a scenario's terrain, vectorised,
and each element's outline and pieces. No MuJoCo: the world (sim/ground/terrain.py) builds the same
pieces as geoms, and the verdict, the loader's checks and the pictures read heights from here.

What each element is (its own frame: +x along ``length``, the direction it rises or runs along):

* a *solid* rises from below the floor up to its surface: a ramp (``z`` at -x to ``z + rise`` at
  +x), steps going up (step k's top at ``z + (k + 1) rise``), a platform (``z + height``), rough
  ground and a heightfield (their grid above ``z``);
* a *cut* removes the floor over its outline down to its surface: a pit (``-depth``) and each
  step of a flight going down whose top lies below the floor (a stairwell); a step going down
  whose top is at or above the floor (a flight from a platform down to the floor) is a solid.

The ground at a point is the highest solid surface covering it, or else the floor: 0, or the
lowest cut covering it. Solids reach down into cuts (a ramp over a pit bridges it).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..terrain import Heightfield, Pit, Platform, Ramp, Rough, Steps, TerrainElement

FLOOR = 0.0


@dataclass(frozen=True)
class Piece:
    """One convex block of an element, in the element's frame: ``u0..u1`` along its length, the
    full width, its top a plane from ``top0`` (at u0) to ``top1`` (at u1). ``cut``: the floor is
    removed over it (its top lies below the floor)."""
    element: int          # index in scenario.terrain
    u0: float
    u1: float
    top0: float
    top1: float
    cut: bool = False


def frame(element: TerrainElement) -> tuple[float, float, float, float]:
    """(x, y, cos yaw, sin yaw) of an element."""
    yaw = math.radians(element.yaw)
    return element.x, element.y, math.cos(yaw), math.sin(yaw)


def extent(element: TerrainElement) -> tuple[float, float]:
    """(length, width) of the element's outline."""
    return float(element.length), float(element.width)


def outline(element: TerrainElement) -> np.ndarray:
    """The outline's four corners (4, 2), counter-clockwise, world frame."""
    x, y, c, s = frame(element)
    hl, hw = extent(element)
    hl, hw = hl / 2.0, hw / 2.0
    local = np.array([(hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw)])[::-1]
    return np.column_stack([x + c * local[:, 0] - s * local[:, 1], y + s * local[:, 0] + c * local[:, 1]])


def to_local(element: TerrainElement, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World points in the element's frame (u along its length, v across)."""
    x, y, c, s = frame(element)
    dx, dy = px - x, py - y
    return c * dx + s * dy, -s * dx + c * dy


def pieces(terrain: Sequence[TerrainElement]) -> tuple[Piece, ...]:
    """The convex blocks of every primitive element (ramps, steps, platforms, pits); rough ground
    and heightfields are grids (scenario/ground/heightmap.py) and have none. Cached per terrain (the ground
    is asked for heights every tick)."""
    terrain = tuple(terrain)
    try:
        return _PIECES[terrain]
    except KeyError:
        pass
    out = _pieces(terrain)
    if len(_PIECES) >= 256:
        _PIECES.clear()
    _PIECES[terrain] = out
    return out


_PIECES: dict = {}


def _pieces(terrain: tuple) -> tuple[Piece, ...]:
    out: list[Piece] = []
    for i, el in enumerate(terrain):
        if isinstance(el, Ramp):
            out.append(Piece(i, -el.length / 2, el.length / 2, el.z, el.z + el.rise))
        elif isinstance(el, Platform):
            out.append(Piece(i, -el.length / 2, el.length / 2, el.z + el.height, el.z + el.height))
        elif isinstance(el, Pit):
            out.append(Piece(i, -el.length / 2, el.length / 2, -el.depth, -el.depth, cut=True))
        elif isinstance(el, Steps):
            sign = 1.0 if el.direction == "up" else -1.0
            for k in range(el.count):
                top = el.z + sign * (k + 1) * el.rise
                u0 = -el.length / 2 + k * el.run
                out.append(Piece(i, u0, u0 + el.run, top, top, cut=top < FLOOR - 1e-12))
    return tuple(out)


def grid_elements(terrain: Sequence[TerrainElement]) -> list[int]:
    """Indices of the elements given as height grids (rough ground, heightfields)."""
    return [i for i, el in enumerate(terrain) if isinstance(el, (Rough, Heightfield))]


def _piece_height(piece: Piece, u: np.ndarray) -> np.ndarray:
    if piece.top0 == piece.top1:
        return np.full(u.shape, piece.top0)
    return piece.top0 + (piece.top1 - piece.top0) * (u - piece.u0) / (piece.u1 - piece.u0)


def _grid_height(element: TerrainElement, scenario, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Height of a grid element (rough, heightfield) at local (u, v) inside it, on the grid's
    triangles as MuJoCo collides them (scenario/ground/heightmap.py owns the grid)."""
    from .heightmap import height_grid

    return element.z + height_grid(element, scenario).sample(u, v)


def ground_height(scenario, px, py) -> np.ndarray:
    """The ground's height at world points (px, py) (arrays of one shape, or floats): the highest
    solid covering each, else the floor (0, or the lowest cut covering it)."""
    px, py = np.asarray(px, dtype=float), np.asarray(py, dtype=float)
    terrain = scenario.terrain
    floor = np.full(np.broadcast(px, py).shape, FLOOR)
    if not terrain:
        return floor
    solid = np.full(floor.shape, -np.inf)
    for piece in pieces(terrain):
        el = terrain[piece.element]
        u, v = to_local(el, px, py)
        inside = (u >= piece.u0 - 1e-9) & (u <= piece.u1 + 1e-9) & (np.abs(v) <= el.width / 2 + 1e-9)
        if not inside.any():
            continue
        h = _piece_height(piece, u)
        if piece.cut:
            floor = np.where(inside, np.minimum(floor, h), floor)
        else:
            solid = np.where(inside, np.maximum(solid, h), solid)
    for i in grid_elements(terrain):
        el = terrain[i]
        u, v = to_local(el, px, py)
        inside = (np.abs(u) <= el.length / 2 + 1e-9) & (np.abs(v) <= el.width / 2 + 1e-9)
        if inside.any():
            solid = np.where(inside, np.maximum(solid, _grid_height(el, scenario, u, v)), solid)
            if grid_low(el, scenario) < FLOOR:       # a grid dipping below the floor cuts it
                floor = np.where(inside, -np.inf, floor)
    return np.maximum(solid, floor)


def grid_low(element: TerrainElement, scenario) -> float:
    """The lowest surface of a grid element (rough ground, heightfield); cached (asked for with
    every height on it)."""
    key = (element, getattr(scenario, "source", None))
    low = _GRID_LOW.get(key)
    if low is None:
        from .heightmap import height_grid

        if len(_GRID_LOW) >= 256:
            _GRID_LOW.clear()
        low = _GRID_LOW[key] = float(element.z + np.asarray(height_grid(element, scenario).heights).min())
    return low


_GRID_LOW: dict = {}


def element_at(scenario, x: float, y: float, margin: float = 0.0) -> int | None:
    """Index of the terrain element whose outline (grown by ``margin``) covers (x, y), the highest
    surface first; None over the plain floor."""
    best, best_h = None, -math.inf
    for i, el in enumerate(scenario.terrain):
        u, v = to_local(el, np.float64(x), np.float64(y))
        hl, hw = extent(el)
        if abs(float(u)) <= hl / 2 + margin and abs(float(v)) <= hw / 2 + margin:
            h = float(ground_height(scenario, x, y))
            if isinstance(el, Pit):
                h = -el.depth
            if best is None or h > best_h:
                best, best_h = i, h
    return best


def describe_element(element: TerrainElement) -> str:
    """"ramp 'r1'", "steps 'stairs'": how messages name an element."""
    return f"{element.kind} '{element.name}'" if element.name else element.kind


def holes(scenario) -> list[tuple[np.ndarray, float]]:
    """The cuts in the floor: (outline corners (4, 2) world frame, its surface height) of each
    pit, each step of a flight going down that lies below the floor, and each grid (rough ground,
    heightfield) whose surface dips below it (its lowest height)."""
    out = []
    for piece in pieces(scenario.terrain):
        if piece.cut:
            out.append((piece_outline(scenario.terrain[piece.element], piece), piece.top0))
    for i in grid_elements(scenario.terrain):
        el = scenario.terrain[i]
        low = grid_low(el, scenario)
        if low < FLOOR:
            out.append((outline(el)[::-1].copy(), low))
    return out


def piece_outline(element: TerrainElement, piece: Piece) -> np.ndarray:
    """The corners (4, 2) of a piece's outline in the world frame, counter-clockwise."""
    x, y, c, s = frame(element)
    hw = element.width / 2
    local = np.array([(piece.u0, -hw), (piece.u1, -hw), (piece.u1, hw), (piece.u0, hw)])
    return np.column_stack([x + c * local[:, 0] - s * local[:, 1], y + s * local[:, 0] + c * local[:, 1]])


def lowest(scenario) -> float:
    """The lowest surface of the terrain (0 with no cuts)."""
    return min([FLOOR] + [h for _, h in holes(scenario)])


def highest(scenario) -> float:
    """The highest surface of the terrain (0 with nothing raised)."""
    tops = [max(p.top0, p.top1) for p in pieces(scenario.terrain) if not p.cut]
    for i in grid_elements(scenario.terrain):
        el = scenario.terrain[i]
        tops.append(el.z + getattr(el, "max_height", getattr(el, "amplitude", 0.0)))
    return max([FLOOR] + tops)


BODY_DRIVES = {"planar": ("omni", "diff"), "wheeled": ("diff",), "legged": ("omni", "diff"),
               "mjcf": ("omni", "diff")}
FACE_STEP = 0.3     # m: ground under a footprint differing by more than this stands it in a face
MAX_BLOCKS = 5000   # terrain blocks, each step of a flight one: 5000 build in ~0.2 s, 100 000 took 17 s and 0.5 GB
MAX_HOLES = 100     # elements cutting the floor: the floor around 100 holes at random places ~0.15 s
                    # (sim/terrain._floor_parts), around 1000 about 9 s
FLOAT_GAP = 0.01    # m an obstacle's explicit base may stand above the highest ground under it


def terrain_problem(scenario) -> tuple[str, str, str] | None:
    """(field, message, fix) when the terrain is too large to build in about a second: more than
    MAX_BLOCKS blocks, or more than MAX_HOLES elements cutting the floor; None otherwise."""
    terrain = scenario.terrain
    blocks = sum(el.count if isinstance(el, Steps) else 1 for el in terrain)
    if blocks > MAX_BLOCKS:
        return ("terrain", f"the terrain has {blocks} blocks (each step of a flight counts), more than the limit "
                           f"of {MAX_BLOCKS}: building its world would take tens of seconds",
                "use fewer, deeper steps, or a heightfield for ground this detailed")
    cutting = {piece.element for piece in pieces(terrain) if piece.cut}
    cutting |= {i for i in grid_elements(terrain) if grid_low(terrain[i], scenario) < FLOOR}
    if len(cutting) > MAX_HOLES:
        return ("terrain", f"{len(cutting)} elements cut holes in the floor (pits, flights going down, grids "
                           f"dipping below it), more than the limit of {MAX_HOLES}: the floor around them would "
                           f"take tens of seconds to build",
                "merge neighbouring pits, or give ground this broken as a heightfield")
    return None


def obstacle_problem(scenario) -> tuple[str, str, str] | None:
    """(field, message, fix) when an obstacle's explicit ``z`` puts it where the verdict, the safety
    layer and the paths (all of which see an obstacle as standing on the ground under it) cannot
    follow: floating above the highest ground under it (a shelf over the route, at which the
    safety layer would halt the robot with nothing in its way), entirely under the lowest, or
    anywhere but on the floor for the planar body, whose world puts every obstacle on it; None
    otherwise."""
    from ..geometry import obstacle_polygon

    planar = scenario.robot.body.kind == "planar" and not scenario.terrain
    for i, obs in enumerate(scenario.obstacles):
        if obs.z is None:
            continue
        what = f"{obs.kind} '{obs.name}'"
        if planar:
            if obs.z != 0.0:
                return (f"obstacles[{i}].z", f"{what} {'floats' if obs.z > 0 else 'sinks'} {abs(obs.z):g} m "
                        f"{'above' if obs.z > 0 else 'below'} the floor, but the planar body's world is a flat "
                        f"floor on which every obstacle stands", "leave z out (or give the robot a body that "
                        "rides the ground: robot.body)")
            continue
        pts = np.asarray(obstacle_polygon(obs).exterior.coords)
        heights = ground_height(scenario, np.append(pts[:, 0], obs.x), np.append(pts[:, 1], obs.y))
        high, low = float(heights.max()), float(heights.min())
        if obs.z > high + FLOAT_GAP:
            return (f"obstacles[{i}].z", f"{what} floats {obs.z - high:.3g} m above the ground under it "
                    f"(z = {obs.z:g}, the ground {high:.3g} m at most): the verdict, the safety layer and the "
                    f"paths see every obstacle standing on the ground (overhangs are not modelled)",
                    f"leave z out to stand it on the ground, or give z: {high:.3g}")
        if obs.z + obs.height <= low:
            return (f"obstacles[{i}].z", f"{what} lies under the ground (its top at {obs.z + obs.height:.3g} m, "
                    f"the ground under it {low:.3g} m at least): nothing of it stands above the ground",
                    "leave z out to stand it on the ground")
    return None


def body_problem(scenario) -> tuple[str, str, str] | None:
    """(field, message, fix) when the robot's body and drive, or its body and the terrain, do not
    go together; None when they do (which combinations exist: sim/bodies/__init__.py)."""
    kind, drive = scenario.robot.body.kind, scenario.robot.drive
    if drive not in BODY_DRIVES[kind]:
        return ("robot.drive", f"a {kind} body cannot drive '{drive}': it cannot move sideways",
                f"set robot.drive: {BODY_DRIVES[kind][0]}")
    if kind == "planar" and scenario.terrain:
        return ("robot.body", "the planar body (the default) slides on a flat floor and cannot ride terrain",
                "give the robot a body that meets the ground: robot.body: {type: wheeled} "
                "(or legged, or mjcf with your own robot)")
    from .chassis import wheeled_problem
    return wheeled_problem(scenario)


def mission_problem(scenario) -> tuple[str, str, str] | None:
    """(field, message, fix) when the start or the goal stands over a hole (a pit, a stairwell) or
    inside a terrain face (the ground under its footprint differs by more than FACE_STEP: half on a
    platform, half off), or a waypoint lies over a hole; None when the mission stands on the ground."""
    if not scenario.terrain:
        return None
    from ..geometry import footprint_polygon

    m = scenario.mission
    checks = [("mission.start", m.start, True), ("mission.goal", m.goal, True)]
    checks += [(f"mission.waypoints[{i}]", w, False) for i, w in enumerate(m.waypoints)]
    cuts = [(piece, scenario.terrain[piece.element]) for piece in pieces(scenario.terrain) if piece.cut]
    for field, pose, footprint in checks:
        for piece, el in cuts:
            u, v = to_local(el, np.float64(pose.x), np.float64(pose.y))
            if piece.u0 <= float(u) <= piece.u1 and abs(float(v)) <= el.width / 2:
                return (field, f"({pose.x:g}, {pose.y:g}) lies over {describe_element(el)}, "
                               f"{-piece.top0:g} m below the floor",
                        f"move it onto the ground, or move {describe_element(el)}")
        if footprint:
            outline = np.asarray(footprint_polygon(scenario.robot.footprint, pose.x, pose.y,
                                                   pose.yaw_rad).exterior.coords)
            heights = ground_height(scenario, outline[:, 0], outline[:, 1])
            if float(heights.max() - heights.min()) > FACE_STEP:
                el = element_at(scenario, pose.x, pose.y, margin=1.0)
                what = describe_element(scenario.terrain[el]) if el is not None else "the terrain"
                return (field, f"the robot's footprint at ({pose.x:g}, {pose.y:g}) stands in a face of "
                               f"{what}: the ground under it spans {float(heights.min()):.2f} to "
                               f"{float(heights.max()):.2f} m",
                        f"move it fully onto {what} or off it")
    return None
