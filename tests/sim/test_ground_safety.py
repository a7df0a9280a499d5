"""The safety layer on terrain: with a 3D lidar it stops a robot before a pit it can see (from the
map of the ground its scans built), and it cannot stop one before a drop it does not see (a lidar
that never looks down; the 2D lidar, whose plane passes over every drop)."""
import numpy as np
import pytest

from pytest_navscenario.scenario.terrain import Lidar3D, WheeledBody
from pytest_navscenario.sim.ground.ground_safety import GroundLimits, GroundSafety, limits_of
from pytest_navscenario.sim.lidar3d import CloudLidar, mount_rotation

from sensor_worlds import build, scenario

EDGE = 3.0           # the pit's near edge (x)
SPEED = 0.5          # m/s, straight ahead


def _floor_with_a_pit():
    """Ground at z = 0 from x = -6 to the edge, a 1 m deep pit 2 m long, ground again beyond."""
    return [(-1.5, 0.0, -0.5, 4.5, 4.0, 0.5),                 # x -6 .. 3, top at 0
            (4.0, 0.0, -1.5, 1.0, 4.0, 0.5),                  # the pit's bottom, top at -1
            (10.0, 0.0, -0.5, 5.0, 4.0, 0.5)]                 # x 5 .. 15


def _drive_to_the_edge(lidar3d):
    scn = scenario(lidar3d=lidar3d)
    world, data = build(scn, boxes=_floor_with_a_pit(), floor=False)
    lidar = CloudLidar(scn, world, data, 1, seed=0)
    layer = GroundSafety(scn, GroundLimits(drop=0.1, slope=25.0), (-6.0, -4.0, 15.0, 4.0))
    rot = np.eye(3)
    half = scn.robot.footprint.length / 2.0
    for x in np.arange(-4.0, EDGE - half + 1e-9, 0.05):           # one scan every 0.1 s
        pos = np.array([x, 0.0, 0.0])
        origin = pos + rot @ lidar.offset
        pts = lidar.scan(0, pos, rot).astype(float)
        world_pts = origin + (pts @ mount_rotation(lidar.spec).T) @ rot.T
        layer.see(origin, world_pts, 0.0)
        halt = layer.check(x, 0.0, 0.0, 0.0, SPEED, 0.0, 0.0)
        if halt is not None:
            return scn, x, halt
    return scn, None, None


def test_it_stops_a_robot_before_a_pit_its_3d_lidar_sees():
    scn, x, halt = _drive_to_the_edge(Lidar3D(rings=16, beams=360, mount_z=0.5))
    assert x is not None, "the layer never halted the robot"
    front = x + scn.robot.footprint.length / 2.0
    safety = scn.robot.safety
    # halted while the footprint is still on the ground, once its sweep reaches the edge
    assert front < EDGE
    assert front + safety.margin + SPEED * safety.horizon >= EDGE - 0.1
    assert "drop ahead" in halt


def test_it_cannot_stop_a_robot_before_a_drop_its_lidar_does_not_see():
    # the same robot with a 3D lidar that looks level and up only: the pit lies below every beam
    scn, x, halt = _drive_to_the_edge(Lidar3D(rings=8, beams=360, fov_low=0.0, fov_high=15.0, mount_z=0.5))
    assert x is None and halt is None


def test_the_bodys_limits():
    from dataclasses import replace
    scn = scenario(lidar3d=Lidar3D())
    wheeled = replace(scn, robot=replace(scn.robot, body=WheeledBody()))
    limits = limits_of(wheeled, drop_limit=0.1)
    # two driven wheels of 10 N m at 0.1 m radius push 50 kg up sin(slope) = 20 / (50 * 9.81 * 0.1)
    assert limits.slope == pytest.approx(np.degrees(np.arcsin(20 / (50 * 9.81 * 0.1))))
    assert limits.drop == 0.1


def test_rough_ground_the_body_can_ride_does_not_halt_it():
    from pytest_navscenario.scenario.ground.heightmap import height_grid
    from pytest_navscenario.scenario.terrain import Rough

    rough = Rough("yard", 4.0, 0.0, length=10.0, width=6.0, amplitude=0.08, wavelength=1.0, seed=2)
    scn = scenario(lidar3d=Lidar3D(mount_z=0.5), terrain=[rough])
    world, data = build(scn)
    lidar = CloudLidar(scn, world, data, 1, seed=0)
    layer = GroundSafety(scn, GroundLimits(drop=0.1, slope=24.0), (-2.0, -3.0, 9.0, 3.0))
    grid = height_grid(rough)
    for x in np.arange(-1.0, 7.0, 0.05):
        z = float(np.nan_to_num(grid.sample(x - 4.0, 0.0), nan=0.0))
        pos, rot = np.array([x, 0.0, z]), np.eye(3)
        origin = pos + lidar.offset
        layer.see(origin, origin + lidar.scan(0, pos, rot).astype(float), z)
        assert layer.check(x, 0.0, z, 0.0, SPEED, 0.0, 0.0) is None, x


@pytest.mark.parametrize("rise, halted", [(0.35, False), (1.2, True)])     # 10 and 31 degrees over 2 m
def test_it_stops_before_a_slope_steeper_than_the_body_climbs(rise, halted):
    scn = scenario(lidar3d=Lidar3D(rings=16, beams=360, mount_z=0.5))
    world, data = build(scn, ramp=(3.0, 2.0, rise, 3.0))
    lidar = CloudLidar(scn, world, data, 1, seed=0)
    layer = GroundSafety(scn, GroundLimits(drop=0.1, slope=24.0), (-2.0, -3.0, 9.0, 3.0))
    halt = None
    for x in np.arange(-1.0, 3.0 - scn.robot.footprint.length / 2.0, 0.05):
        pos, rot = np.array([x, 0.0, 0.0]), np.eye(3)
        origin = pos + lidar.offset
        layer.see(origin, origin + lidar.scan(0, pos, rot).astype(float), 0.0)
        halt = layer.check(x, 0.0, 0.0, 0.0, SPEED, 0.0, 0.0)
        if halt is not None:
            break
    assert (halt is not None) == halted, halt
    if halted:
        assert "a slope of" in halt and "(the body climbs 24)" in halt
