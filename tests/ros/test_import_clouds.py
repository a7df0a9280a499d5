"""Issue 17, point clouds: a bag from a known world seen by a 3D lidar (16 rings, ground in view),
in the field layouts of three drivers (Velodyne: unorganised, packed 22-byte points; Ouster:
organised 16 x 720 with NaN where a beam hits nothing; Hesai: organised, float64 timestamps, rows
padded past their points). The ground is removed, a box lower
than a 2D laser's plane comes through with its height, a tall wall is cut at the robot's height."""
from __future__ import annotations

import math

import numpy as np
import pytest
from ros_synthetic import World, robot_bag

from shapely.geometry import Point, box
from shapely.ops import unary_union

from pytest_navscenario.ros.bag_import import BagImportError, scenario_from_bag
from pytest_navscenario.scenario.geometry import obstacle_polygon
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle, PolygonObstacle

WORLD = World(pillars=[(2.0, 1.2, 0.25, 1.0)],
              boxes=[(3.0, -1.0, 0.5, 0.5, 0.0, 0.15),      # low: under a 2D laser at 0.2 m
                     (2.5, 2.6, 6.0, 0.2, 0.0, 1.5)])       # a wall taller than the robot
LIDAR = (0.0, 0.0, 0.6)
CLOUD = {"azimuths": np.radians(np.arange(-180.0, 180.0, 0.5)), "elevations": np.radians(np.arange(-15.0, 16.0, 2.0))}


def _drive():
    t = np.arange(60) * 0.1
    return np.stack([t, -1.0 + 0.6 * t, 0 * t, 0 * t], 1)   # straight along y = 0, from x = -1 to 2.5


@pytest.fixture(scope="module", params=["velodyne", "ouster", "hesai"])
def cloud_seed(request, tmp_path_factory):
    path = robot_bag(tmp_path_factory.mktemp(request.param) / "c", WORLD, _drive(), scans=False, laser=LIDAR,
                     cloud={**CLOUD, "layout": request.param})
    return scenario_from_bag(path)


def test_the_pillar_and_the_low_box_with_its_height(cloud_seed):
    obs = cloud_seed.scenario.obstacles
    pillar = [o for o in obs if isinstance(o, CylinderObstacle)]
    assert len(pillar) == 1
    assert (pillar[0].x, pillar[0].y, pillar[0].radius) == pytest.approx((2.0, 1.2, 0.25), abs=0.04)
    # the low box, seen on its two faces towards the path (west x = 2.75, north y = -0.75): the
    # two faces' pieces are merged into one polygon
    low = [o for o in obs if isinstance(o, (BoxObstacle, PolygonObstacle)) and math.hypot(o.x - 3.0, o.y + 1.0) < 0.4]
    assert len(low) == 1 and all(o.height == pytest.approx(0.15, abs=0.03) for o in low), obs
    x0, y0, x1, y1 = unary_union([obstacle_polygon(o) for o in low]).bounds
    assert x0 == pytest.approx(2.75, abs=0.05) and y1 == pytest.approx(-0.75, abs=0.05)
    # the outline reaches 0.15 m behind the seen faces (the far ones were never seen): at most that far out
    assert x1 < 3.25 + 0.16 and y0 > -1.25 - 0.16
    # the wall: taller than the robot, cut at the robot's height; its near face at y = 2.5
    wall = [o for o in obs if obstacle_polygon(o).bounds[2] - obstacle_polygon(o).bounds[0] > 3]
    assert len(wall) == 1 and wall[0].height == pytest.approx(1.0, abs=0.01)
    assert obstacle_polygon(wall[0]).bounds[1] == pytest.approx(2.5, abs=0.05)
    # nothing else: the ground is not an obstacle; every piece lies on a true object
    truth = [Point(x, y).buffer(r) for x, y, r, _ in WORLD.pillars] + \
        [box(x - ln / 2, y - w / 2, x + ln / 2, y + w / 2) for x, y, ln, w, _, _ in WORLD.boxes]
    for o in obs:
        assert min(obstacle_polygon(o).distance(t) for t in truth) < 0.02, o
    assert any("ground found at z=-0.00 m" in n or "ground found at z=0.00 m" in n for n in cloud_seed.notes), \
        cloud_seed.notes


def test_ouster_nans_are_counted(tmp_path):
    path = robot_bag(tmp_path / "o", WORLD, _drive()[:10], scans=False, laser=LIDAR, cloud={**CLOUD, "layout": "ouster"})
    seed = scenario_from_bag(path)
    assert any("NaN points (no return) dropped" in n for n in seed.notes)


def test_a_2d_laser_misses_the_low_box(tmp_path):
    seed = scenario_from_bag(robot_bag(tmp_path / "s", WORLD, _drive()))
    assert not [o for o in seed.scenario.obstacles if math.hypot(o.x - 3.0, o.y + 1.0) < 0.4]


def test_a_cloud_without_xyz_is_an_error(tmp_path):
    from ros_synthetic import BagOut, pose_msg, stamp

    path = tmp_path / "noxyz"
    with BagOut(path) as bag:
        for i in range(5):
            t = 0.1 * i
            bag.write("/odom", "nav_msgs/msg/Odometry", t, {"header": {"stamp": stamp(t), "frame_id": "odom"},
                      "child_frame_id": "base_link", "pose": {"pose": pose_msg(0.1 * i, 0, 0)}})
            bag.write("/points", "sensor_msgs/msg/PointCloud2", t, {
                "header": {"stamp": stamp(t), "frame_id": "base_link"}, "height": 1, "width": 2,
                "fields": [{"name": "range", "offset": 0, "datatype": 7, "count": 1}], "point_step": 4,
                "row_step": 8, "data": np.zeros(8, np.uint8), "is_dense": True})
    with pytest.raises(BagImportError, match=r"/points: the point cloud has no x, y, z field\(s\) \(fields: range\)"):
        scenario_from_bag(path)


def test_clouds_without_odometry_is_an_error(tmp_path, capsys):
    from ros_synthetic import BagOut, cloud_msg, cloud_points

    from pytest_navscenario.cli import main

    path = tmp_path / "clouds_only"
    with BagOut(path) as bag:
        for i in range(3):
            pts = cloud_points(WORLD, 0.0, 0.0, 0.0, 0.6, CLOUD["azimuths"], CLOUD["elevations"])
            bag.write("/points", "sensor_msgs/msg/PointCloud2", 0.1 * i, cloud_msg(pts, 0.1 * i, "velodyne"))
    assert main(["from-bag", str(path), "-o", str(tmp_path / "s.yaml")]) == 2
    err = capsys.readouterr().err
    assert "no odometry (nav_msgs/msg/Odometry) in the bag (topics: /points (sensor_msgs/msg/PointCloud2))" in err


def test_cloud_fields_in_any_layout_byte_order_and_width():
    """x, y, z as big-endian float64 after other fields, rows padded: read exactly; integer x is an error."""
    from types import SimpleNamespace as NS

    from pytest_navscenario.ros.bag_import.clouds import cloud_xyz

    pts = np.array([[1.5, -2.0, 0.25], [np.nan, np.nan, np.nan], [3.0, 4.0, -0.5]])
    dt = np.dtype({"names": ["ring", "x", "y", "z"], "formats": [">u2", ">f8", ">f8", ">f8"],
                   "offsets": [0, 8, 16, 24], "itemsize": 40})
    arr = np.zeros(3, dt)
    arr["x"], arr["y"], arr["z"] = pts[:, 0], pts[:, 1], pts[:, 2]
    data = np.frombuffer(arr.tobytes() + b"\0" * 8, np.uint8)          # one row, padded by 8 bytes
    fields = [NS(name="ring", offset=0, datatype=4), NS(name="x", offset=8, datatype=8),
              NS(name="y", offset=16, datatype=8), NS(name="z", offset=24, datatype=8)]
    msg = NS(fields=fields, is_bigendian=True, point_step=40, width=3, height=1, row_step=128, data=data)
    got, nan = cloud_xyz(msg, "bag: /points")
    assert nan == 1 and np.allclose(got, pts[[0, 2]])
    fields[1] = NS(name="x", offset=8, datatype=6)
    with pytest.raises(BagImportError, match=r"bag: /points: point cloud field\(s\) x are not float32/float64"):
        cloud_xyz(msg, "bag: /points")


def test_scan_and_cloud_topic_together_is_an_error(tmp_path):
    with pytest.raises(BagImportError, match="--scan-topic and --cloud-topic: give one"):
        scenario_from_bag(tmp_path / "any.bag", scan_topic="/scan", cloud_topic="/points")


def test_a_tilted_lidar_is_levelled_with_its_mounting(tmp_path):
    """The lidar pitched 12 degrees nose down (as on legged robots), its mounting on /tf_static: the
    pillar and the low box come out as with a level lidar; read as level, the ground would tilt
    into the band and the result would be wrong."""
    path = robot_bag(tmp_path / "tilt", WORLD, _drive(), scans=False, laser=LIDAR, pitch=12.0,
                     cloud={**CLOUD, "layout": "velodyne"})
    obs = scenario_from_bag(path).scenario.obstacles
    pillar = [o for o in obs if isinstance(o, CylinderObstacle)]
    assert len(pillar) == 1 and (pillar[0].x, pillar[0].y, pillar[0].radius) == pytest.approx((2.0, 1.2, 0.25), abs=0.04)
    low = [o for o in obs if isinstance(o, (BoxObstacle, PolygonObstacle)) and math.hypot(o.x - 3.0, o.y + 1.0) < 0.4]
    assert low and all(o.height == pytest.approx(0.15, abs=0.03) for o in low)
    truth = [Point(x, y).buffer(r) for x, y, r, _ in WORLD.pillars] + \
        [box(x - ln / 2, y - w / 2, x + ln / 2, y + w / 2) for x, y, ln, w, _, _ in WORLD.boxes]
    assert all(min(obstacle_polygon(o).distance(t) for t in truth) < 0.02 for o in obs), obs
