"""The MuJoCo world of a robot that rides the ground: gravity on, the terrain (sim/ground/terrain.py),
obstacles standing on the ground, the body (sim/bodies/), and what the episode asks of it: which
contact of the chassis is a collision (with an obstacle, or with a terrain face) and the height of
the ground under a point.

The planar body's world (sim/world.py) is untouched by all this: a scenario without terrain and
with the planar body compiles exactly as before.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from ..core.errors import ScenarioError
from ..scenario.ground import surface as ground
from ..scenario.ground.traversable import walls_from_below
from ..scenario.model import Scenario
from .bodies.base import ROBOT_GROUP
from .safety import SafetyLayer
from .ground.terrain import add_terrain, terrain_of_geom
from .trajectory import Collision
from . import world as planar
from .world import PARTS_GROUP, UNSEEN_GROUP, World, _add_obstacles, obstacle_geom_names

GRAVITY = -9.81
FACE_NZ = 0.7            # a chassis contact whose normal is steeper than ~45 degrees from vertical
                         # is a terrain face (a step's riser, a pit's wall), not the ground below
EDGE_ABOVE = 0.02        # m: a face touched no higher than this above the ground the robot last stood on
                         # is that ground's edge, which it goes over (a fall or a tip-over follows), not
                         # terrain it drove into (a riser rises above it: the chassis meets it higher up)


def obstacle_bases(scenario: Scenario) -> list[float]:
    """Each obstacle's base height: its own ``z``, else standing on the highest ground under it."""
    from ..scenario.geometry import obstacle_polygon

    out = []
    for obs in scenario.obstacles:
        if obs.z is not None:
            out.append(float(obs.z))
            continue
        if not scenario.terrain:
            out.append(0.0)
            continue
        pts = np.asarray(obstacle_polygon(obs).exterior.coords)
        pts = np.vstack([pts, [(obs.x, obs.y)]])
        out.append(float(ground.ground_height(scenario, pts[:, 0], pts[:, 1]).max()))
    return out


def build_body_spec(scenario: Scenario, body: Any) -> mujoco.MjSpec:
    """The MjSpec of a robot riding the ground: gravity, terrain, obstacles on it, the body, and a
    contact sensor counting the chassis's contacts (read every physics step: only when it is not
    zero are the contacts looked at)."""
    spec = mujoco.MjSpec()
    spec.modelname = scenario.name or "navscenario"
    spec.compiler.degree = False
    spec.option.gravity = [0.0, 0.0, GRAVITY]
    spec.option.timestep = scenario.simulation.timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    add_terrain(spec, scenario)
    _add_obstacles(spec, scenario, obstacle_bases(scenario))
    body.build(spec)
    objtype, objname = getattr(body, "contact_sensor", (mujoco.mjtObj.mjOBJ_GEOM, "footprint"))
    spec.add_sensor(name="chassis_contacts", type=mujoco.mjtSensor.mjSENS_CONTACT,
                    objtype=objtype, objname=objname, intprm=[1, 0, 1])
    return spec


@dataclass
class BodyWorld(World):
    """A ``World`` whose robot rides the ground: its body model, the terrain's geoms, and the
    chassis-contact sensor's index in ``sensordata``."""
    body: Any = None
    terrain_of_geom: dict = field(default_factory=dict)
    chassis_sensor: int = 0
    element_names: tuple = ()

    def first_collision(self, d: mujoco.MjData, obstacles: tuple, t: float,
                        level: float | None = None) -> Collision | None:
        """The deepest contact of the robot with an obstacle, or of its chassis with a terrain face
        (a contact whose normal is within ~45 degrees of horizontal), or None. Wheels, casters and
        feet meet the terrain freely, and the chassis resting on the ground (high-centred) is no
        collision. (``body.robot_geoms``: the geoms that meet obstacles; ``chassis_geoms``: those
        whose terrain contacts count.) ``level``: the ground height the robot last stood on; a face
        touched no higher than EDGE_ABOVE over it is the edge of that ground, on which a robot going
        over it rolls or pitches while it falls or tips (which of the contact or the tip-over comes
        first moved by ~0.05 s between MuJoCo 4.0.0 and 4.0.1, turning a tip-over off a dock into a
        "collision with the face"): no collision, the terrain watch names the fall."""
        best = None
        floor = -np.inf if level is None else level + EDGE_ABOVE
        contacts = d.contact
        chassis, obstacle_of_geom, terrain = self.body.chassis_geoms, self.obstacle_of_geom, self.terrain_of_geom
        robot = self.body.robot_geoms
        for k in range(d.ncon):
            dist = float(contacts.dist[k])
            if dist >= 0.0:
                continue
            g1, g2 = int(contacts.geom[k][0]), int(contacts.geom[k][1])
            mine, other = (g1, g2) if g1 in robot else ((g2, g1) if g2 in robot else (-1, -1))
            if other < 0:
                continue
            idx = obstacle_of_geom.get(other)
            if idx is not None:
                hit = (dist, obstacles[idx].name, k, False)
            else:
                element = terrain.get(other)
                if element is None or mine not in chassis or abs(float(contacts.frame[k][2])) >= FACE_NZ \
                        or float(contacts.pos[k][2]) <= floor:
                    continue
                hit = (dist, self.element_names[element] if element >= 0 else "floor", k, True)
            if best is None or hit[0] < best[0]:
                best = hit
        if best is None:
            return None
        dist, name, k, face = best
        pos = contacts.pos[k]
        return Collision(t, name, float(pos[0]), float(pos[1]), -dist, terrain=face)

    def chassis_touches(self, d: mujoco.MjData) -> bool:
        return d.sensordata[self.chassis_sensor] > 0.0

    def chassis_on_ground(self, d: mujoco.MjData) -> bool:
        """Whether the chassis itself (``body.chassis_geoms``) touches anything outside the robot:
        the sensor of a user's MJCF robot counts its whole subtree (wheels and feet on the floor
        included), which is what the collision check needs but not what "high-centred" means."""
        chassis, robot = self.body.chassis_geoms, self.body.robot_geoms
        for k in range(d.ncon):
            if float(d.contact.dist[k]) > 0.0:
                continue
            g1, g2 = int(d.contact.geom[k][0]), int(d.contact.geom[k][1])
            if (g1 in chassis and g2 not in robot) or (g2 in chassis and g1 not in robot):
                return True
        return False


def build_body_world(scenario: Scenario, body: Any) -> BodyWorld:
    spec = build_body_spec(scenario, body)
    try:
        model = _compile(spec, body)
    except Exception as exc:
        clash = _name_clash(scenario, str(exc))
        if clash is not None:
            raise clash from None
        raise ScenarioError(f"MuJoCo could not build the model: {exc}", path=scenario.source,
                            hint="check the terrain's and the obstacles' sizes, and the robot's body") from exc
    body.bind(model)
    robot_body = body.base_body
    robot_geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "footprint")
    obstacle_of_geom = {mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, gname): i
                        for i, names in enumerate(obstacle_geom_names(scenario)) for gname in names}
    walls = walls_from_below(scenario) if scenario.robot.safety.enabled else ()
    safety = SafetyLayer(scenario, walls) if scenario.robot.safety.enabled and (scenario.obstacles or walls) else None
    groups = np.ones(6, dtype=np.uint8)
    for g in (PARTS_GROUP, UNSEEN_GROUP, ROBOT_GROUP):
        if (model.geom_group == g).any():
            groups[g] = 0
    groups.flags.writeable = False
    sensor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, "chassis_contacts")
    names = tuple(ground.describe_element(el) for el in scenario.terrain)
    return BodyWorld(model, robot_body, robot_geom, obstacle_of_geom, safety, groups, body=body,
                     terrain_of_geom=terrain_of_geom(model), chassis_sensor=int(model.sensor_adr[sensor]),
                     element_names=names)


def _name_clash(scenario: Scenario, error: str) -> ScenarioError | None:
    """The error for MuJoCo's 'repeated name' of a robot MJCF that uses a name the scenario's world
    uses (its floor, an obstacle, a sensor): the file, its line in the scenario, the owner and the
    fix; None for any other error."""
    import re

    found = re.search(r"repeated name '([^']*)' in (\w+)", error)
    if found is None or scenario.robot.body.kind != "mjcf":
        return None
    from ..scenario.loader import field_line
    from .bodies.mjcf import mjcf_path

    name, kind = found.groups()
    field, owner, fix = "robot.body.file", None, None
    for i, names in enumerate(obstacle_geom_names(scenario)):
        if name in names or name == f"moving:{names[0]}":
            obstacle = scenario.obstacles[i]
            owner = f"obstacle {obstacle.name!r} (obstacles[{i}])"
            fix = f"rename obstacles[{i}] in the scenario, or the {kind} in the MJCF file"
            break
    if owner is None:
        owner = "its own floor" if name.startswith("floor") else "its own elements"
        fix = f"rename the {kind} {name!r} in the MJCF file, and where your controller names it"
    return ScenarioError(f"{mjcf_path(scenario)} has a {kind} named {name!r}, a name the scenario's world "
                         f"already gives {owner}", path=scenario.source,
                         line=field_line(scenario.source, field), field=field, hint=fix)


def rides_the_ground(scenario: Scenario) -> bool:
    """True when the scenario's robot is not the planar body, or the scenario has terrain."""
    return bool(scenario.terrain) or scenario.robot.body.kind != "planar"


def compiled_body_world(scenario: Scenario) -> BodyWorld:
    """The compiled BodyWorld of a scenario, from the planar worlds' LRU cache (its key holds the
    body and the terrain)."""
    from .bodies import body_model

    key = planar._cache_key(scenario)
    world = planar._CACHE.get(key)
    if world is not None:
        planar._CACHE.move_to_end(key)
        return world
    world = build_body_world(scenario, body_model(scenario))
    planar._CACHE[key] = world
    if len(planar._CACHE) > planar.MODEL_CACHE_SIZE:
        planar._CACHE.popitem(last=False)
    return world


def any_world(scenario: Scenario) -> World:
    """The compiled world of any scenario: planar (sim/world.py) or riding the ground."""
    return compiled_body_world(scenario) if rides_the_ground(scenario) else planar.compiled_world(scenario)


def model_xml(scenario: Scenario) -> str:
    """Any scenario's MuJoCo model as MJCF text (to keep beside a frozen failure, or view it)."""
    if not rides_the_ground(scenario):
        return planar.model_xml(scenario)
    from .bodies import body_model
    body = body_model(scenario)
    spec = build_body_spec(scenario, body)
    _compile(spec, body)
    if body.kind_name == "mjcf":
        from .bodies.mjcf import kept_names
        with kept_names():
            return spec.to_xml()
    return spec.to_xml()


def _compile(spec: mujoco.MjSpec, body: Any) -> mujoco.MjModel:
    """``spec.compile()``; a user's MJCF robot attached with its own names compiles quietly."""
    if body.kind_name == "mjcf":
        from .bodies.mjcf import kept_names
        with kept_names():
            return spec.compile()
    return spec.compile()
