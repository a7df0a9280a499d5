"""Small MuJoCo worlds for the lidar tests: a floor, a robot on a free joint (its geom in the group the
lidars skip, as the bodies' worlds do), and what the test puts in front of it (boxes, a ramp, a
height grid), as a ``World`` the lidars read."""
from __future__ import annotations

import math
from dataclasses import replace

import mujoco
import numpy as np

from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.scenario.ground.heightmap import height_grid
from pytest_navscenario.sim.ground.heightfield import add_heightfield
from pytest_navscenario.sim.world import World

ROBOT_GROUP = 5

SCENARIO = """
version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 9, y: 0}}
"""


def scenario(lidar3d=None, terrain=(), **lidar):
    s = loads_scenario(SCENARIO)
    robot = s.robot
    if lidar:
        robot = replace(robot, lidar=replace(robot.lidar, **lidar))
    if lidar3d is not None:
        robot = replace(robot, lidar3d=lidar3d)
    return replace(s, robot=robot, terrain=tuple(terrain))


def build(scn, boxes=(), ramp=None, floor=True):
    """A World: ``boxes`` are (x, y, z, half x, half y, half z); ``ramp`` (x0, length, rise, width)
    an inclined plane rising along +x from x0 (a box turned about y, its top face the slope), the
    scenario's grid elements as hfields."""
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    if floor:
        spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[50, 50, 1])
    for k, (x, y, z, hx, hy, hz) in enumerate(boxes):
        spec.worldbody.add_geom(name=f"box{k}", type=mujoco.mjtGeom.mjGEOM_BOX, pos=[x, y, z], size=[hx, hy, hz])
    if ramp is not None:
        x0, length, rise, width = ramp
        angle = math.atan2(rise, length)
        slope = math.hypot(length, rise)
        thick = 0.5
        # the box's top face is the slope: centre half a thickness below the slope's midpoint
        cx = x0 + length / 2.0 + math.sin(angle) * thick / 2.0
        cz = rise / 2.0 - math.cos(angle) * thick / 2.0
        spec.worldbody.add_geom(name="ramp", type=mujoco.mjtGeom.mjGEOM_BOX, pos=[cx, 0.0, cz],
                                size=[slope / 2.0, width / 2.0, thick / 2.0],
                                quat=[math.cos(-angle / 2.0), 0.0, math.sin(-angle / 2.0), 0.0])
    for el in scn.terrain:
        add_heightfield(spec, el, height_grid(el, scn))
    robot = spec.worldbody.add_body(name="robot", pos=[0, 0, 0])
    robot.add_freejoint()
    robot.add_geom(name="footprint", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.3, 0.2, 0.1], pos=[0, 0, 0.1],
                   group=ROBOT_GROUP)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    groups = np.ones(6, dtype=np.uint8)
    groups[ROBOT_GROUP] = 0
    groups.flags.writeable = False
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "robot")
    geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "footprint")
    return World(model, body, geom, {}, None, groups), data


def rotation(roll=0.0, pitch=0.0, yaw=0.0):
    """World from base for Z-Y-X angles in degrees (yaw, then pitch, then roll)."""
    r, p, y = (math.radians(a) for a in (roll, pitch, yaw))
    rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    return rz @ ry @ rx
