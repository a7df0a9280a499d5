"""The terrain in MuJoCo: the floor (a plane, or slabs around the holes of pits and stairwells),
ramps, steps, platforms and pit bottoms as primitives (boxes, and convex prisms for slopes), with
the contact settings every body rides on.

Ramps, steps and platforms are built from primitives, not heightfields: MuJoCo collides and
ray-casts boxes and convex meshes fast (the design notes measured ``mj_multiRay`` with 5760 rays at
~1 ms against boxes and 9-240 ms against heightfields of 32-256 cells a side). Rough ground and
heightfields are grids: ``sim/ground/heightfield.py`` builds them. Shapes come from ``scenario/ground/surface.py``
(the same pieces the verdict reads heights from), so the world and the ground function agree.

Geom names: ``terrain:<element index>/<piece>`` for an element's blocks, ``floor/<k>`` for the
floor. ``terrain_of_geom`` maps a compiled model's geom ids back to the element (-1: the floor).
"""
from __future__ import annotations

import math

import mujoco
import numpy as np

from ...scenario.ground import surface as ground
from ...scenario.model import Scenario

# collision bits (contype / conaffinity): the robot's chassis 1, obstacles 2, terrain 4, the robot's
# running gear (wheels, casters, feet) 8. The chassis meets obstacles and terrain; the running gear
# meets only terrain (a wheel never touches an obstacle before the chassis does: it lies inside the
# footprint); obstacles and terrain never meet (both are static, or mocap).
CHASSIS_BITS = (1, 0)
GEAR_BITS = (8, 4)
TERRAIN_BITS = (4, 1 | 8)
SLAB = 0.5                # m of floor below the deepest hole (the holes' walls and the world's bottom)
EXTENT_MARGIN = 30.0      # m the floor reaches beyond everything the scenario places
FLOOR_RGBA = [0.82, 0.80, 0.74, 1]
ELEMENT_RGBA = {"ramp": [0.55, 0.70, 0.55, 1], "steps": [0.65, 0.60, 0.75, 1],
                "platform": [0.72, 0.62, 0.48, 1], "pit": [0.45, 0.42, 0.38, 1]}
EMBED = 0.02              # m a ramp's slope reaches below the floor (see _add_piece)
FRICTION = (1.0, 0.005, 0.0001)   # sliding, torsional, rolling: MuJoCo's defaults, rubber on concrete


def floor_extent(scenario: Scenario) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1): everything the scenario places (mission, obstacles, terrain), grown by
    EXTENT_MARGIN: where the slab floor ends when there are holes."""
    m = scenario.mission
    xs = [m.start.x, m.goal.x, *(w.x for w in m.waypoints), *(o.x for o in scenario.obstacles)]
    ys = [m.start.y, m.goal.y, *(w.y for w in m.waypoints), *(o.y for o in scenario.obstacles)]
    for el in scenario.terrain:
        corners = ground.outline(el)
        xs += corners[:, 0].tolist()
        ys += corners[:, 1].tolist()
    return (min(xs) - EXTENT_MARGIN, min(ys) - EXTENT_MARGIN, max(xs) + EXTENT_MARGIN, max(ys) + EXTENT_MARGIN)


def add_terrain(spec: mujoco.MjSpec, scenario: Scenario) -> None:
    """The floor and every primitive terrain element as static world geoms (see the module doc)."""
    bottom = ground.lowest(scenario) - SLAB
    common = dict(contype=TERRAIN_BITS[0], conaffinity=TERRAIN_BITS[1], friction=list(FRICTION))
    _add_floor(spec, scenario, bottom, common)
    for k, piece in enumerate(ground.pieces(scenario.terrain)):
        el = scenario.terrain[piece.element]
        _add_piece(spec, el, piece, f"terrain:{piece.element}/{k}", bottom, common)
    grids = ground.grid_elements(scenario.terrain)
    if grids:
        from .heightfield import add_heightfield   # rough ground and height files (their own module)
        from ...scenario.ground.heightmap import height_grid
        for i in grids:
            el = scenario.terrain[i]
            add_heightfield(spec, el, height_grid(el, scenario), name=f"terrain:{i}/0",
                            contype=common["contype"], conaffinity=common["conaffinity"])


def _add_floor(spec: mujoco.MjSpec, scenario: Scenario, bottom: float, common: dict) -> None:
    holes = ground.holes(scenario)
    if not holes:
        from ..world import add_floor_plane     # on a body of its own: the lidars' rays see it
        add_floor_plane(spec, name="floor/0", rgba=FLOOR_RGBA, **common)
        return
    for k, part in enumerate(_floor_parts(floor_extent(scenario), [h[0] for h in holes])):
        _add_prism(spec, f"floor/{k}", part, bottom, 0.0, 0.0, FLOOR_RGBA, common)


def _floor_parts(extent: tuple[float, float, float, float], holes: list[np.ndarray]) -> list[np.ndarray]:
    """The floor's outline minus the holes, cut into convex parts (each a (k, 2) array of corners,
    counter-clockwise): vertical strips through every corner, so each strip's pieces are
    trapezoids (rectangles when the holes are axis-aligned)."""
    import shapely
    from shapely.geometry import Polygon, box

    x0, y0, x1, y1 = extent
    region = box(x0, y0, x1, y1).difference(shapely.union_all([Polygon(h) for h in holes]))
    xs = sorted({round(float(x), 9) for geom in getattr(region, "geoms", [region])
                 for ring in [geom.exterior, *geom.interiors] for x, _ in ring.coords})
    parts = []
    for xa, xb in zip(xs, xs[1:]):
        if xb - xa < 1e-9:
            continue
        strip = region.intersection(box(xa, y0 - 1, xb, y1 + 1))
        for poly in getattr(strip, "geoms", [strip]):
            if isinstance(poly, Polygon) and poly.area > 1e-9:
                simple = shapely.geometry.polygon.orient(poly.simplify(1e-9), 1.0)
                parts.append(np.asarray(simple.exterior.coords)[:-1])
    return parts


def _add_prism(spec: mujoco.MjSpec, name: str, corners: np.ndarray, bottom: float, top_at: float,
               slope: float, rgba, common: dict) -> None:
    """A vertical prism over convex ``corners`` from ``bottom`` to a flat top at ``top_at`` (a box
    when the corners are an axis-aligned rectangle)."""
    xs, ys = corners[:, 0], corners[:, 1]
    rect = len(corners) == 4 and all(
        abs(corners[i, 0] - corners[(i + 1) % 4, 0]) < 1e-9 or abs(corners[i, 1] - corners[(i + 1) % 4, 1]) < 1e-9
        for i in range(4))
    if rect:
        spec.worldbody.add_geom(
            name=name, type=mujoco.mjtGeom.mjGEOM_BOX,
            pos=[(xs.min() + xs.max()) / 2, (ys.min() + ys.max()) / 2, (bottom + top_at) / 2],
            size=[(xs.max() - xs.min()) / 2, (ys.max() - ys.min()) / 2, (top_at - bottom) / 2],
            rgba=rgba, **common)
        return
    verts = np.concatenate([np.column_stack([corners, np.full(len(corners), bottom)]),
                            np.column_stack([corners, np.full(len(corners), top_at)])])
    spec.add_mesh(name=name, uservert=verts.ravel().tolist())
    spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name, rgba=rgba, **common)


def _add_piece(spec: mujoco.MjSpec, el, piece: ground.Piece, name: str, bottom: float, common: dict) -> None:
    """One block of an element: a box when its top is flat, else a convex prism (a ramp's wedge,
    solid down to the world's bottom), placed at the element's pose."""
    x, y, c, s = ground.frame(el)
    yaw = math.radians(el.yaw)
    quat = [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
    hw = el.width / 2
    rgba = ELEMENT_RGBA.get(el.kind, [0.6, 0.6, 0.6, 1])
    if piece.top0 == piece.top1:
        um = (piece.u0 + piece.u1) / 2
        spec.worldbody.add_geom(
            name=name, type=mujoco.mjtGeom.mjGEOM_BOX, quat=quat,
            pos=[x + c * um, y + s * um, (bottom + piece.top0) / 2],
            size=[(piece.u1 - piece.u0) / 2, hw, (piece.top0 - bottom) / 2], rgba=rgba, **common)
        return
    u0, top0 = piece.u0, piece.top0
    if abs(top0 - ground.FLOOR) < 1e-9 and piece.top1 > top0:
        # a ramp rising from the floor: its slope goes on EMBED below the floor, so a wheel sunk
        # into the floor by its soft contact meets the slope, not the wedge's end face
        u0 -= EMBED * (piece.u1 - piece.u0) / (piece.top1 - top0)
        top0 -= EMBED
    local = []
    for u, top in ((u0, top0), (piece.u1, piece.top1)):
        for v in (-hw, hw):
            local += [(u, v, bottom), (u, v, top)]
    spec.add_mesh(name=name, uservert=np.array(local, dtype=float).ravel().tolist())
    spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name, pos=[x, y, 0.0],
                            quat=quat, rgba=rgba, **common)


def terrain_of_geom(model: mujoco.MjModel) -> dict[int, int]:
    """Geom id -> terrain element index (-1: the floor) of a compiled model."""
    out = {}
    for g in range(model.ngeom):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or ""
        if name.startswith("floor/"):
            out[g] = -1
        elif name.startswith("terrain:"):
            out[g] = int(name[len("terrain:"):].split("/")[0])
    return out
