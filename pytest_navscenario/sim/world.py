"""The MuJoCo world of a scenario: the model built from it, compiled once and cached, and what an
episode asks of it (a fresh MjData, the collision among the current contacts, a clear error when
the physics diverges).

The robot is a rigid body on planar joints (slide-x, slide-y, hinge-yaw) with gravity off, driven by
three velocity actuators attached to a site at its centre, so commands act in the robot frame and the
motion has inertia and tracking lag (time constant ``TRACKING_TAU``, force limited). Obstacles are
static world geoms named after the scenario's obstacles. Only robot-obstacle pairs can collide.
"""
from __future__ import annotations

import logging
import math
import re
from collections import OrderedDict, deque
from dataclasses import dataclass, field, replace
from typing import Any

import mujoco
import numpy as np

from ..core.errors import ScenarioError
from ..scenario.geometry import convex_parts_local, outline_points
from ..scenario.model import (BoxObstacle, CylinderObstacle, Footprint, MeshObstacle, Motion, PolygonObstacle,
                              Scenario)
from .safety import SafetyLayer
from .trajectory import Collision

ROBOT_MASS = 50.0          # kg (about an ANYmal)
ROBOT_HEIGHT = 0.5         # m; the robot's body spans z in [0, ROBOT_HEIGHT]
LIDAR_HEIGHT = 0.2         # m; the lidar plane. Obstacles lower than this are invisible to it.
TRACKING_TAU = 0.05        # s; velocity tracking time constant of the actuators (kv = inertia / tau)
FORCE_HEADROOM = 1.5       # actuator force limit = inertia * max acceleration * headroom
MODEL_CACHE_SIZE = 64      # compiled models kept (the search and repeats re-run the same layout)
PARTS_GROUP = 3            # geom group of a non-convex obstacle's convex parts: they collide, the lidar
                           # skips them and sees the obstacle's one exact prism mesh instead
UNSEEN_GROUP = 4           # geom group of obstacles with visible_to_lidar: false (glass): the lidar skips it

TWO_PI = 2.0 * math.pi
CONTACT_SENSOR = "robot_contacts"   # the planar robot's contact count (sensordata[0])

log = logging.getLogger(__name__)
MUJOCO_WARNINGS: deque[str] = deque(maxlen=5)   # the last texts our handler received


def on_mujoco_warning(message: str) -> None:
    """MuJoCo's warning handler: keep the text for SimulationDivergedError and log it, instead of
    MuJoCo's default of printing and appending to MUJOCO_LOG.TXT in the working directory."""
    MUJOCO_WARNINGS.append(str(message).strip())
    log.warning("MuJoCo: %s", str(message).strip())


if mujoco.get_mju_user_warning() is None:   # leave a handler someone else installed alone
    mujoco.set_mju_user_warning(on_mujoco_warning)


def wrap_angle(a: float) -> float:
    """Angle in radians wrapped to [-pi, pi)."""
    return (a + math.pi) % TWO_PI - math.pi


def steps_per_tick(scenario: Scenario) -> int:
    """Physics steps per control tick: round(1 / (control_rate * timestep)); ScenarioError if < 1."""
    sim = scenario.simulation
    if not (sim.timestep > 0 and sim.control_rate > 0):
        raise ScenarioError(f"timestep and control_rate must be > 0, got {sim.timestep} and "
                            f"{sim.control_rate}", path=scenario.source, field="simulation",
                            hint="e.g. timestep: 0.01, control_rate: 10")
    n = round(1.0 / (sim.control_rate * sim.timestep))
    if n < 1:
        raise ScenarioError(
            f"control_rate {sim.control_rate} Hz is faster than the physics ({1 / sim.timestep:g} Hz)",
            path=scenario.source, field="simulation.control_rate",
            hint="lower control_rate or the timestep so that 1/(control_rate*timestep) >= 1")
    return n


# ---------------------------------------------------------------- model building

def _footprint_inertia(fp: Footprint) -> float:
    """Yaw moment of inertia (kg m^2) of the robot as a uniform box or disc of ROBOT_MASS."""
    if fp.shape == "circle":
        return ROBOT_MASS * fp.radius ** 2 / 2.0
    return ROBOT_MASS * (fp.length ** 2 + fp.width ** 2) / 12.0


def _geom_names(scenario: Scenario) -> list[str]:
    """MuJoCo geom names: the obstacle's name, unless empty or repeated (then ``obstacle<i>``)."""
    seen: set[str] = set()
    names = []
    for i, obs in enumerate(scenario.obstacles):
        name = obs.name if obs.name and obs.name not in seen and obs.name != "robot" else f"obstacle{i}"
        while name in seen:
            name = f"_{name}"
        seen.add(name)
        names.append(name)
    return names


def _add_robot(spec: mujoco.MjSpec, scenario: Scenario) -> None:
    """The robot body on its planar joints, its footprint geom and the three velocity actuators."""
    fp = scenario.robot.footprint
    limits = scenario.robot.limits
    robot = spec.worldbody.add_body(name="robot", pos=[0.0, 0.0, ROBOT_HEIGHT / 2.0])
    robot.add_joint(name="x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
    robot.add_joint(name="y", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
    robot.add_joint(name="yaw", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    if fp.shape == "circle":
        robot.add_geom(name="footprint", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                       size=[fp.radius, ROBOT_HEIGHT / 2.0, 0.0], mass=ROBOT_MASS,
                       contype=1, conaffinity=2, rgba=[0.2, 0.4, 0.9, 1])
    else:
        robot.add_geom(name="footprint", type=mujoco.mjtGeom.mjGEOM_BOX,
                       size=[fp.length / 2.0, fp.width / 2.0, ROBOT_HEIGHT / 2.0], mass=ROBOT_MASS,
                       contype=1, conaffinity=2, rgba=[0.2, 0.4, 0.9, 1])
    robot.add_site(name="centre", pos=[0.0, 0.0, 0.0])

    inertia = _footprint_inertia(fp)
    lin_force = ROBOT_MASS * limits.max_accel * FORCE_HEADROOM
    yaw_torque = inertia * math.radians(limits.max_yaw_accel) * FORCE_HEADROOM
    for name, gear, kv, limit in (
            ("vx", [1, 0, 0, 0, 0, 0], ROBOT_MASS / TRACKING_TAU, lin_force),
            ("vy", [0, 1, 0, 0, 0, 0], ROBOT_MASS / TRACKING_TAU, lin_force),
            ("wz", [0, 0, 0, 0, 0, 1], inertia / TRACKING_TAU, yaw_torque)):
        act = spec.add_actuator(name=name, trntype=mujoco.mjtTrn.mjTRN_SITE, target="centre", gear=gear)
        act.set_to_velocity(kv=kv)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-limit, limit]


def _add_obstacles(spec: mujoco.MjSpec, scenario: Scenario, bases: list[float] | None = None) -> None:
    """One geom per obstacle standing on z = 0 (a polygon or mesh: one convex prism geom per convex
    part, named ``<name>/<k>``): static ones on the world body, a moving one on its own mocap body
    (kinematic: the loop writes its position, MuJoCo moves its geoms and detects their contacts like
    any other; mocap_pos order = moving obstacles' order)."""
    for j, (obs, gname) in enumerate(zip(scenario.obstacles, _geom_names(scenario))):
        h = obs.height
        z0 = 0.0 if bases is None else bases[j]
        yaw = getattr(obs, "yaw_rad", 0.0)
        quat = [math.cos(yaw / 2.0), 0.0, 0.0, math.sin(yaw / 2.0)]
        if getattr(obs, "motion", None) is not None:
            parent = spec.worldbody.add_body(name=f"moving:{gname}", mocap=True, pos=[obs.x, obs.y, z0],
                                             quat=quat)
            pos, quat, rgba = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.9, 0.5, 0.2, 1]
        else:
            parent, pos, rgba = spec.worldbody, [obs.x, obs.y, z0], [0.6, 0.6, 0.6, 1]
        unseen = not getattr(obs, "visible_to_lidar", True)
        if unseen:
            rgba = [0.6, 0.85, 0.95, 0.4]
        common = dict(contype=2, conaffinity=1, rgba=rgba, quat=quat, group=UNSEEN_GROUP if unseen else 0)
        if isinstance(obs, BoxObstacle):
            parent.add_geom(name=gname, type=mujoco.mjtGeom.mjGEOM_BOX, pos=[pos[0], pos[1], pos[2] + h / 2.0],
                            size=_solid_size(obs), **common)
        elif isinstance(obs, CylinderObstacle):
            parent.add_geom(name=gname, type=mujoco.mjtGeom.mjGEOM_CYLINDER, pos=[pos[0], pos[1], pos[2] + h / 2.0],
                            size=_solid_size(obs), **common)
        elif isinstance(obs, (PolygonObstacle, MeshObstacle)):
            parts = convex_parts_local(tuple(outline_points(obs)))
            for k, part in enumerate(parts):
                mesh = f"{gname}/{k}"
                verts = np.concatenate([np.column_stack([part, np.zeros(len(part))]),
                                        np.column_stack([part, np.full(len(part), h)])])
                spec.add_mesh(name=mesh, uservert=verts.ravel().tolist())
                group = UNSEEN_GROUP if unseen else (PARTS_GROUP if len(parts) > 1 else 0)
                parent.add_geom(name=mesh, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh, pos=pos,
                                **{**common, "group": group})
            if len(parts) > 1 and not unseen:   # the lidar sees one exact prism mesh (cheaper than the parts)
                verts, faces = prism_mesh(outline_points(obs), h)
                spec.add_mesh(name=f"{gname}/outline", uservert=verts.ravel().tolist(),
                              userface=faces.ravel().tolist())
                parent.add_geom(name=f"{gname}/outline", type=mujoco.mjtGeom.mjGEOM_MESH,
                                meshname=f"{gname}/outline", pos=pos, contype=0, conaffinity=0,
                                rgba=rgba, quat=common["quat"])
        else:
            raise ScenarioError(f"unknown obstacle type {type(obs).__name__}", path=scenario.source,
                                field=f"obstacles[{obs.name}]", hint="use a box, cylinder, polygon or mesh")


def _solid_size(obs: BoxObstacle | CylinderObstacle) -> list[float]:
    """MuJoCo's size of a box's or a cylinder's geom (half sizes; radius and half height)."""
    if isinstance(obs, BoxObstacle):
        return [obs.length / 2.0, obs.width / 2.0, obs.height / 2.0]
    return [obs.radius, obs.height / 2.0, 0.0]


def _movable(obs: Any) -> bool:
    """A static box or cylinder: a layout of the same structure may move and resize its geom."""
    return isinstance(obs, (BoxObstacle, CylinderObstacle)) and getattr(obs, "motion", None) is None


def prism_mesh(points, h: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (2n, 3), triangles (m, 3)) of a simple polygon extruded from 0 to ``h``: its
    constrained Delaunay triangles as floor and top, two triangles per wall, facing outwards."""
    import shapely
    import shapely.geometry.polygon
    from shapely.geometry import Polygon

    pts = np.asarray(points, dtype=float)
    n = len(pts)
    ccw = shapely.geometry.polygon.orient(Polygon(pts), 1.0)
    if not np.allclose(np.asarray(ccw.exterior.coords)[0], pts[0]) or not Polygon(pts).exterior.is_ccw:
        pts = np.asarray(ccw.exterior.coords)[:-1]
    index = {tuple(p): i for i, p in enumerate(pts.tolist())}
    faces = []
    for tri in shapely.constrained_delaunay_triangles(Polygon(pts)).geoms:
        a, b, c = (index[tuple(p)] for p in np.asarray(shapely.geometry.polygon.orient(tri, 1.0)
                                                       .exterior.coords)[:-1].tolist())
        faces += [(a, c, b), (a + n, b + n, c + n)]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, j + n), (i, j + n, i + n)]
    verts = np.concatenate([np.column_stack([pts, np.zeros(n)]), np.column_stack([pts, np.full(n, h)])])
    return verts, np.array(faces, dtype=int)


def obstacle_geom_names(scenario: Scenario) -> list[list[str]]:
    """The MuJoCo geom names of each obstacle (a polygon or mesh has one per convex part)."""
    out = []
    for obs, gname in zip(scenario.obstacles, _geom_names(scenario)):
        if isinstance(obs, (PolygonObstacle, MeshObstacle)):
            out.append([f"{gname}/{k}" for k in range(len(convex_parts_local(tuple(outline_points(obs)))))])
        else:
            out.append([gname])
    return out


def add_floor_plane(spec: mujoco.MjSpec, name: str = "floor", **geom: Any) -> Any:
    """An infinite floor plane at z = 0 (a geom named ``name``) on a static body of its own:
    ``mj_multiRay`` skips a body whose bounding sphere a ray misses, and a plane is left out of its
    body's bounds (MuJoCo 4.0, measured: a plane in the world body beside a box was missed by 285
    of 360 beams pointing down; ``mj_ray`` saw all 360). Returns the geom."""
    geom.setdefault("rgba", [0.8, 0.8, 0.8, 1])
    return spec.worldbody.add_body(name="floor").add_geom(
        name=name, type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0.0, 0.0, 1.0], **geom)


def build_spec(scenario: Scenario) -> mujoco.MjSpec:
    """The MjSpec of a scenario: planar robot with velocity actuators, static obstacle geoms."""
    spec = mujoco.MjSpec()
    spec.modelname = scenario.name or "navscenario"
    spec.compiler.degree = False              # every angle below is in radians
    spec.option.gravity = [0.0, 0.0, 0.0]     # planar: no gravity, no floor
    spec.option.timestep = scenario.simulation.timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST  # stable with stiff kv
    _add_robot(spec, scenario)
    _add_obstacles(spec, scenario)
    if scenario.robot.lidar3d is not None:   # the floor a 3D lidar sees (it touches nothing)
        add_floor_plane(spec, contype=0, conaffinity=0)
    # the robot's contacts at every step, for the batch engine's physics (sim/batching/cohort.py: a
    # tick stepped in one mujoco.rollout call is looked at only when it had a contact); a
    # sensor never changes the dynamics
    spec.add_sensor(name=CONTACT_SENSOR, type=mujoco.mjtSensor.mjSENS_CONTACT,
                    objtype=mujoco.mjtObj.mjOBJ_GEOM, objname="footprint", intprm=[1, 0, 1])
    return spec


def model_xml(scenario: Scenario) -> str:
    """The scenario's MuJoCo model as MJCF text (to keep beside a frozen failure, or view it)."""
    spec = build_spec(scenario)
    spec.compile()
    return spec.to_xml()


# ---------------------------------------------------------------- the compiled world

@dataclass
class World:
    """A compiled model and the lookups the loop needs, shared by episodes (the model is never
    changed; only the pool of MjData to reuse is)."""
    model: mujoco.MjModel
    robot_body: int
    robot_geom: int
    obstacle_of_geom: dict[int, int]   # geom id -> index in scenario.obstacles
    safety: SafetyLayer | None
    # the geom groups mj_multiRay casts against: None (all) unless the model has convex parts or
    # unseen obstacles for the lidar to skip; per model, not per episode (numpy scans of the model)
    lidar_groups: np.ndarray | None = None
    # MjData pool: creating one costs ~0.5 ms; shared by the worlds of one structure (_pool_key),
    # whose MjData have the same sizes: a search's layouts reuse each other's
    free_data: list = field(default_factory=list)

    def take_data(self) -> mujoco.MjData:
        """A freshly reset MjData (mj_resetData gives exactly the state of a new one)."""
        try:
            d = self.free_data.pop()
        except IndexError:
            return mujoco.MjData(self.model)
        mujoco.mj_resetData(self.model, d)
        return d

    def give_back(self, d: mujoco.MjData) -> None:
        if len(self.free_data) < 2:
            self.free_data.append(d)

    def first_collision(self, d: mujoco.MjData, obstacles: tuple, t: float) -> Collision | None:
        """The deepest robot-obstacle penetration among the current contacts of ``d``, or None."""
        best = None
        contacts = d.contact
        robot_geom, obstacle_of_geom = self.robot_geom, self.obstacle_of_geom
        for k in range(d.ncon):
            dist = float(contacts.dist[k])
            if dist >= 0.0:
                continue
            g1, g2 = int(contacts.geom[k][0]), int(contacts.geom[k][1])
            other = g2 if g1 == robot_geom else (g1 if g2 == robot_geom else -1)
            idx = obstacle_of_geom.get(other)
            if idx is None:
                continue
            if best is None or dist < best[0]:
                best = (dist, idx, k)
        if best is None:
            return None
        dist, idx, k = best
        pos = contacts.pos[k]
        return Collision(t, obstacles[idx].name, float(pos[0]), float(pos[1]), -dist)


_CACHE: OrderedDict[Any, World] = OrderedDict()
_MOVES = Motion()     # stands for any motion in a cache key


def _cache_key(scenario: Scenario) -> Any:
    # Everything the compiled model (and the safety geometry) depends on, names included (the
    # content hash ignores names, but contacts must map to the right name).
    # A moving obstacle's timing and speed are not in the model (the loop writes its positions),
    # so candidates of a search that differ only in those share one compiled model.
    robot = scenario.robot
    obstacles = scenario.obstacles
    if any(getattr(o, "motion", None) is not None for o in obstacles):
        obstacles = tuple(o if o.motion is None else replace(o, motion=_MOVES) for o in obstacles)
    return (robot.footprint, robot.limits, robot.safety, obstacles, scenario.simulation.timestep,
            robot.body, scenario.terrain, robot.lidar3d is not None)


_POOLS: OrderedDict[Any, list] = OrderedDict()   # structure -> the MjData its worlds give back


def _pool_key(scenario: Scenario) -> Any:
    """What the sizes of a model's MjData depend on: the cache key with each static box's and
    cylinder's pose and size left out (they move and resize geoms, never add or remove one), so
    a search's candidates that only move or resize obstacles share their MjData (mj_resetData
    gives exactly the state of a new one of those sizes)."""
    key = _cache_key(scenario)
    shapes = tuple((type(o).__name__, getattr(o, "visible_to_lidar", True)) if _movable(o) else o
                   for o in key[3])
    return (*key[:3], shapes, *key[4:])


_SPECS: OrderedDict[Any, tuple[mujoco.MjSpec, list]] = OrderedDict()   # structure -> a spec built, its geoms


def layout_spec(scenario: Scenario) -> mujoco.MjSpec:
    """The scenario's MjSpec to compile: the spec built for an earlier layout of the same structure
    (``_pool_key`` and the geom names), its static boxes' and cylinders' geoms moved and resized to
    this layout with the values ``build_spec`` writes, else a new one (``build_spec``, ~0.3 ms in an
    episode). MuJoCo compiles an edited spec to the model a new spec of the layout compiles to
    (every MjModel array compared: tests/sim/test_model_reuse.py)."""
    key = (_pool_key(scenario), tuple(_geom_names(scenario)))
    held = _SPECS.pop(key, None)
    if held is None:
        spec = build_spec(scenario)
        names = _geom_names(scenario)
        geoms = [spec.geom(names[j]) if _movable(o) else None for j, o in enumerate(scenario.obstacles)]
    else:
        spec, geoms = held
        spec.modelname = scenario.name or "navscenario"
        for obs, geom in zip(scenario.obstacles, geoms):
            if geom is not None:
                yaw = getattr(obs, "yaw_rad", 0.0)
                geom.pos = [obs.x, obs.y, 0.0 + obs.height / 2.0]
                geom.quat = [math.cos(yaw / 2.0), 0.0, 0.0, math.sin(yaw / 2.0)]
                geom.size = _solid_size(obs)
    _SPECS[key] = (spec, geoms)
    if len(_SPECS) > MODEL_CACHE_SIZE:
        _SPECS.popitem(last=False)
    return spec


def compiled_world(scenario: Scenario) -> World:
    """The compiled World for a scenario of the planar body, from a small LRU cache (a body that
    rides the ground: ``body_world.compiled_body_world``)."""
    key = _cache_key(scenario)
    world = _CACHE.get(key)
    if world is not None:
        _CACHE.move_to_end(key)
        return world
    spec = layout_spec(scenario)
    try:
        model = spec.compile()
    except Exception as exc:  # mujoco.FatalError / ValueError with MuJoCo's own text
        _SPECS.clear()        # a spec MuJoCo refused is not edited again
        raise ScenarioError(f"MuJoCo could not build the model: {exc}", path=scenario.source,
                            hint="check obstacle sizes and heights (> 0) and the robot footprint") from exc
    robot_body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "robot")
    robot_geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "footprint")
    obstacle_of_geom = {mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, gname): i
                        for i, names in enumerate(obstacle_geom_names(scenario)) for gname in names}
    safety = SafetyLayer(scenario) if scenario.robot.safety.enabled and scenario.obstacles else None
    pool_key = _pool_key(scenario)
    pool = _POOLS.pop(pool_key, None)
    _POOLS[pool_key] = pool = [] if pool is None else pool
    if len(_POOLS) > MODEL_CACHE_SIZE:
        _POOLS.popitem(last=False)
    world = World(model, robot_body, robot_geom, obstacle_of_geom, safety, _lidar_groups(model), pool)
    _CACHE[key] = world
    if len(_CACHE) > MODEL_CACHE_SIZE:
        _CACHE.popitem(last=False)
    return world


def _lidar_groups(model: mujoco.MjModel) -> np.ndarray | None:
    """The lidar's geom-group mask: it skips non-convex obstacles' convex parts (it sees their prism
    mesh) and obstacles with visible_to_lidar: false; None when the model has neither."""
    skipped = [g for g in (PARTS_GROUP, UNSEEN_GROUP) if (model.geom_group == g).any()]
    if not skipped:
        return None
    groups = np.ones(6, dtype=np.uint8)
    groups[skipped] = 0
    groups.flags.writeable = False
    return groups


def clear_model_cache() -> None:
    _CACHE.clear()
    _POOLS.clear()
    _SPECS.clear()


def fatal_message(scenario: Scenario, model: mujoco.MjModel, exc: BaseException, t: float) -> str:
    """What SimulationFatalError says: where, when, MuJoCo's own text, and the fix (for an arena that
    overflowed, the ``<size memory>`` that holds what MuJoCo asked for, or a smaller model)."""
    where = scenario.name or "<unnamed scenario>"
    if scenario.source:
        where += f" ({scenario.source})"
    text = " ".join(str(exc).split())
    size = f"{model.nbody} bodies, {model.ngeom} geoms"
    body = scenario.robot.body
    mjcf = getattr(body, "file", None) if getattr(body, "kind", None) == "mjcf" else None
    asked = re.search(r"requested = (\d+)", text)
    if "out of memory" in text or "size memory" in text:
        need = int(asked.group(1)) + int(model.narena) if asked else 2 * int(model.narena)
        mega = 1 << max(0, (need - 1) // 2**20).bit_length()      # MB, a power of two that holds it
        memory = f"{mega // 1024}G" if mega >= 1024 else f"{mega}M"
        fix = (f'add <size memory="{memory}"/> to the robot\'s MJCF file {mjcf} (robot.body.file), or '
               f"simplify it" if mjcf else "simplify the scenario (fewer or simpler obstacles and terrain)")
        arena = int(model.narena)
        shown = f"{arena / 2**20:.0f} MB" if arena >= 2**20 else f"{arena / 1024:.0f} KB"
        why = f"the model ({size}) needs more memory than MuJoCo's arena of {shown}"
    else:
        fix = (f"simplify the robot's MJCF file {mjcf} (robot.body.file) until it runs in MuJoCo's own "
               f"simulate viewer" if mjcf else "simplify the scenario (obstacles and terrain)")
        why = f"the model ({size}) cannot be simulated"
    return f"MuJoCo stopped scenario {where} at t={t:.3f} s: {why}: {text} (fix: {fix})"


def divergence_message(scenario: Scenario, d: mujoco.MjData, t: float) -> str:
    """What SimulationDivergedError says: where, when, MuJoCo's warnings and the state, and what to
    check."""
    where = scenario.name or "<unnamed scenario>"
    if scenario.source:
        where += f" ({scenario.source})"
    warned = [f"{mujoco.mjtWarning(k).name} (x{int(w.number)}, info {int(w.lastinfo)})"
              for k, w in enumerate(d.warning) if w.number]
    state = f"qpos={np.array2string(d.qpos, precision=3)}, qvel={np.array2string(d.qvel, precision=3)}"
    why = ("MuJoCo warnings: " + ", ".join(warned)) if warned else "non-finite state"
    if MUJOCO_WARNINGS:
        why += f" ({MUJOCO_WARNINGS[-1]})"
    return (f"simulation diverged in scenario {where} by t={t:.3f} s: {why}; {state}. "
            f"The physics cannot be trusted: check robot.limits (huge speeds or accelerations) and "
            f"simulation.timestep (try 0.01 s or smaller).")
