"""The 3D lidar's points match the geometry it looks at (a known wall at a known distance, the floor,
a known ramp, rough ground), mounted and tilted as declared; its noise is the 2D lidar's, from its
own stream of the episode seed; and the 2D lidar on a tilted body reads terrain as a 2D lidar does
(a ramp ahead is a wall, a drop-off is invisible)."""
import math

import numpy as np
import pytest

from pytest_navscenario.scenario.ground.heightmap import height_grid
from pytest_navscenario.scenario.terrain import Lidar3D, Rough
from pytest_navscenario.sim.lidar import Lidar, sensor_origin
from pytest_navscenario.sim.lidar3d import CloudLidar, mount_rotation, sensor_directions

from sensor_worlds import build, rotation, scenario

WALL_X = 5.0     # the wall's near face


def _world_points(lidar, pts, pos, rot):
    """Sensor-frame points back into the world frame."""
    origin = pos + rot @ lidar.offset
    return origin + (np.asarray(pts, dtype=float) @ mount_rotation(lidar.spec).T) @ rot.T


def _wall_world(**spec):
    lidar3d = Lidar3D(**{"rings": 16, "beams": 360, **spec})
    scn = scenario(lidar3d=lidar3d)
    world, data = build(scn, boxes=[(WALL_X + 0.5, 0.0, 1.0, 0.5, 6.0, 1.0)])
    return scn, CloudLidar(scn, world, data, 4, seed=1)


def test_the_level_ring_sees_a_wall_at_its_distance_and_the_low_rings_see_the_floor():
    scn, lidar = _wall_world(rings=3, fov_low=-10.0, fov_high=10.0, mount_z=0.5)
    pos, rot = np.zeros(3), np.eye(3)
    pts = lidar.scan(0, pos, rot)
    assert pts.dtype == np.float32 and pts.shape[1] == 3 and not pts.flags.writeable
    ahead = pts[(np.abs(pts[:, 1]) < 1e-3) & (pts[:, 0] > 0)]
    # straight ahead: ring -10 deg meets the floor 0.5 / tan(10 deg) away, rings 0 and +10 deg the
    # wall 5 m away (its points' x, the depth along the sensor's axis, is the wall's distance)
    assert np.sort(ahead[:, 0]).tolist() == pytest.approx([0.5 / math.tan(math.radians(10)), WALL_X, WALL_X],
                                                          abs=1e-5)
    assert np.sort(np.linalg.norm(ahead, axis=1))[-1] == pytest.approx(WALL_X / math.cos(math.radians(10)))
    world = _world_points(lidar, pts, pos, rot)
    on_wall = np.abs(world[:, 0] - WALL_X) < 1e-4
    on_floor = np.abs(world[:, 2]) < 1e-4
    assert on_wall.sum() > 50 and on_floor.sum() > 300
    assert np.all(on_wall | on_floor)          # every point lies on the wall or the floor
    assert len(pts) < 3 * 360                  # the upper ring's beams away from the wall: no return


def test_the_mounting_pose_and_a_tilted_body_move_the_points():
    # pitched down 10 degrees on its mount, 0.4 m forward: the level ring meets the floor
    scn, lidar = _wall_world(rings=1, beams=4, mount_x=0.4, mount_z=0.5, mount_pitch=10.0)
    pts = lidar.scan(0, np.zeros(3), np.eye(3))
    ahead = pts[np.argmax(pts[:, 0])]
    assert ahead[0] == pytest.approx(0.5 / math.sin(math.radians(10.0)), abs=1e-5)
    assert ahead[1:] == pytest.approx([0.0, 0.0], abs=1e-6)
    # the same lidar level on its mount, on a base pitched 8 degrees nose up: the wall is further
    scn, lidar = _wall_world(rings=1, beams=4, mount_z=0.5)
    pos, rot = np.array([0.0, 0.0, 0.2]), rotation(pitch=-8.0)
    pts = lidar.scan(0, pos, rot)
    origin = pos + rot @ lidar.offset
    assert pts[np.argmax(pts[:, 0]), 0] == pytest.approx((WALL_X - origin[0]) / math.cos(math.radians(8.0)),
                                                          abs=1e-5)
    world = _world_points(lidar, pts, pos, rot)
    assert np.min(np.abs(world[:, 0] - WALL_X)) < 1e-5


def test_a_known_ramp_gives_points_on_its_slope():
    lidar3d = Lidar3D(rings=16, beams=360, mount_z=0.5)
    scn = scenario(lidar3d=lidar3d)
    x0, length, rise = 2.0, 4.0, 0.8                 # 11.3 degrees
    world, data = build(scn, ramp=(x0, length, rise, 3.0))
    lidar = CloudLidar(scn, world, data, 1, seed=0)
    pos, rot = np.zeros(3), np.eye(3)
    w = _world_points(lidar, lidar.scan(0, pos, rot), pos, rot)
    on_ramp = (w[:, 0] > x0 + 0.05) & (w[:, 0] < x0 + length - 0.05) & (np.abs(w[:, 1]) < 1.4) & (w[:, 2] > 1e-3)
    assert on_ramp.sum() > 20
    assert w[on_ramp, 2] == pytest.approx((w[on_ramp, 0] - x0) * rise / length, abs=1e-5)


def test_rough_ground_is_seen_through_the_grid_cast():
    rough = Rough("yard", 3.0, 0.0, length=6.0, width=6.0, amplitude=0.3, wavelength=1.0, seed=4)
    scn = scenario(lidar3d=Lidar3D(mount_z=0.6), terrain=[rough])
    world, data = build(scn)
    lidar = CloudLidar(scn, world, data, 1, seed=0)
    assert lidar.grids and lidar.groups[2] == 0          # mj_multiRay skips the hfield
    pos, rot = np.zeros(3), np.eye(3)
    w = _world_points(lidar, lidar.scan(0, pos, rot), pos, rot)
    inside = (np.abs(w[:, 0] - 3.0) < 2.9) & (np.abs(w[:, 1]) < 2.9)
    assert inside.sum() > 200
    ground = height_grid(rough).sample(w[inside, 0] - 3.0, w[inside, 1])
    assert w[inside, 2] == pytest.approx(ground, abs=1e-5)


def test_noise_is_the_2d_lidars_from_a_stream_of_its_own():
    spec = dict(rings=4, beams=90, mount_z=0.5, noise_sigma=0.02, dropout=0.1, spurious=0.05)
    scn, a = _wall_world(**spec)
    _, b = _wall_world(**spec)
    pa, pb = a.scan(0, np.zeros(3), np.eye(3)), b.scan(0, np.zeros(3), np.eye(3))
    assert np.array_equal(pa, pb)                          # the same seed, the same points
    scn, clean = _wall_world(**{**spec, "noise_sigma": 0.0, "dropout": 0.0, "spurious": 0.0})
    exact = clean.scan(0, np.zeros(3), np.eye(3))
    assert not np.array_equal(pa, exact)
    # beams without a return stay without one (but for spurious returns short of range_max)
    assert np.all(np.linalg.norm(pa, axis=1) < a.range_max - 1e-3)
    _, gone = _wall_world(**{**spec, "dropout": 1.0, "spurious": 0.0})
    assert len(gone.scan(0, np.zeros(3), np.eye(3))) == 0


def test_the_beam_table_is_ring_major_from_the_lowest_ring():
    dirs = sensor_directions(Lidar3D(rings=3, beams=4, fov_low=-10, fov_high=20))
    assert dirs.shape == (12, 3)
    assert np.degrees(np.arcsin(dirs[::4, 2])) == pytest.approx([-10, 5, 20])
    assert dirs[0] == pytest.approx([-math.cos(math.radians(10)), 0, -math.sin(math.radians(10))], abs=1e-12)


# ---------------------------------------------------------------- the 2D lidar on a tilted body


def _planar_scan(scn, world, data, pos, rot):
    lidar = Lidar(scn, world, data, 2, seed=0)
    origin = sensor_origin(pos, rot, (0.0, 0.0, scn.robot.lidar.mount_height))
    return lidar, np.asarray(lidar.scan_posed(0, origin, rot))


def test_a_ramp_ahead_reads_as_a_wall_and_a_drop_is_invisible_to_the_2d_lidar():
    scn = scenario(beams=360, fov=360.0)
    x0, length, rise = 2.0, 4.0, 0.8
    world, data = build(scn, ramp=(x0, length, rise, 3.0))
    lidar, ranges = _planar_scan(scn, world, data, np.zeros(3), np.eye(3))
    ahead = ranges[np.argmin(np.abs(lidar.angles))]
    # the scan plane at 0.2 m meets the slope where it is 0.2 m high: 1 m up the ramp
    assert ahead == pytest.approx(x0 + 0.2 * length / rise, abs=1e-4)
    # a raised floor ending ahead (a loading dock's edge): the plane passes over the drop
    world, data = build(scn, boxes=[(0.0, 0.0, -0.5, 3.0, 3.0, 0.5)], floor=False)
    lidar, ranges = _planar_scan(scn, world, data, np.zeros(3), np.eye(3))
    assert np.all(ranges == np.float32(lidar.range_max))
    # pitched 5 degrees nose down (braking on the dock), the plane meets the floor ahead (the lidar,
    # 0.2 m up the base's tilted axis, is 0.2 cos 5 deg above the floor)
    world, data = build(scn)
    lidar, ranges = _planar_scan(scn, world, data, np.zeros(3), rotation(pitch=5.0))
    ahead = ranges[np.argmin(np.abs(lidar.angles))]
    assert ahead == pytest.approx(0.2 / math.tan(math.radians(5.0)), abs=1e-4)


def test_the_2d_lidar_at_its_mount_height_sees_over_a_low_box():
    world_low = dict(boxes=[(3.0, 0.0, 0.15, 0.2, 0.2, 0.15)])       # a box 0.3 m high, 2.8 m ahead
    scn = scenario(beams=8, fov=360.0, mount_height=0.2)
    world, data = build(scn, **world_low)
    lidar, ranges = _planar_scan(scn, world, data, np.zeros(3), np.eye(3))
    assert ranges[np.argmin(np.abs(lidar.angles))] == pytest.approx(2.8, abs=1e-4)
    scn = scenario(beams=8, fov=360.0, mount_height=0.4)
    world, data = build(scn, **world_low)
    lidar, ranges = _planar_scan(scn, world, data, np.zeros(3), np.eye(3))
    assert ranges[np.argmin(np.abs(lidar.angles))] == np.float32(lidar.range_max)


# ---------------------------------------------------------------- in an episode


class _Recorder:
    """Drives straight ahead and keeps what it was handed."""

    def __init__(self):
        self.seen = []

    def reset(self, scenario):
        self.seen.clear()

    def act(self, obs):
        self.seen.append(obs)
        return (0.5, 0.0, 0.0)


def test_an_episode_hands_the_planner_points_and_attitude_and_times_the_3d_lidar_apart():
    from dataclasses import replace

    from pytest_navscenario.scenario.loader import loads_scenario
    from pytest_navscenario.sim.episode import simulate

    s = loads_scenario("""
version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 20, y: 0}, timeout: 2}
obstacles:
  - {type: box, name: wall, x: 6.5, y: 0, length: 1, width: 8, height: 2}
""")
    s = replace(s, robot=replace(s.robot, lidar3d=Lidar3D(rings=16, beams=360, mount_z=0.5, noise_sigma=0.01)))
    planner = _Recorder()
    result = simulate(s, planner, seed=3)
    first = planner.seen[0]
    assert first.attitude.tolist() == [0.0, 0.0] and not first.attitude.flags.writeable
    pts = first.points
    wall = pts[(np.abs(pts[:, 1]) < 1.0) & (pts[:, 2] > -0.45)]
    assert wall[:, 0] == pytest.approx(6.0, abs=0.05)                   # the wall's face, 6 m ahead
    floor = pts[pts[:, 2] < -0.45]
    assert len(floor) > 1000 and floor[:, 2] == pytest.approx(-0.5, abs=0.05)   # the floor, 0.5 m below
    assert result.trajectory.cloud.shape == (result.ticks, 16, 360)
    assert result.trajectory.cloud.dtype == np.float32
    assert "lidar3d" in result.timings and result.timings["lidar3d"] > 0.0
    again = simulate(s, _Recorder(), seed=3)
    assert np.array_equal(again.trajectory.cloud, result.trajectory.cloud)
    assert np.array_equal(again.trajectory.pose, result.trajectory.pose)
    # the 2D lidar's scans are those of the same episode without a 3D lidar (its own noise stream)
    plain = simulate(replace(s, robot=replace(s.robot, lidar3d=None)), _Recorder(), seed=3)
    assert np.array_equal(plain.trajectory.ranges, result.trajectory.ranges)
    assert plain.trajectory.cloud is None and "lidar3d" not in plain.timings
