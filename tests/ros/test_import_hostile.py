"""Issue 26.10, from-bag under hostile input: each is one clear line (exit 2, nothing written) or a
warning that says what was used instead, never a traceback, a silent default or a seed that tests
nothing; and the seed is an ordinary file (not 0600)."""
from __future__ import annotations

import math
import os
import stat
from pathlib import Path

import numpy as np
import pytest
from ros_synthetic import BagOut, World, pose_msg, robot_bag, stamp

from pytest_navscenario.cli import main
from test_import_errors import run_cli


def _odom(bag: BagOut, t: float, x: float, y: float = 0.0, yaw: float = 0.0, at: float | None = None) -> None:
    bag.write("/odom", "nav_msgs/msg/Odometry", t, {
        "header": {"stamp": stamp(t if at is None else at), "frame_id": "odom"}, "child_frame_id": "base_link",
        "pose": {"pose": pose_msg(x, y, yaw)}})


def _scan(bag: BagOut, t: float, **fields) -> None:
    values = {"header": {"stamp": stamp(t), "frame_id": "laser"}, "angle_min": -math.pi,
              "angle_increment": 2 * math.pi / 90, "range_min": 0.05, "range_max": 10.0,
              "ranges": np.full(90, 2.0, np.float32)}
    values.update(fields)
    bag.write("/scan", "sensor_msgs/msg/LaserScan", t, values)


def test_nan_poses_on_odom_are_left_out_with_a_warning(tmp_path, capsys):
    """Before: ValueError: cannot convert float NaN to integer (a traceback)."""
    path = tmp_path / "nan_odom"
    with BagOut(path) as bag:
        for i in range(40):
            _odom(bag, 1.0 + 0.1 * i, math.nan if i in (5, 6, 30) else 0.1 * i)
    out = tmp_path / "s.yaml"
    assert main(["from-bag", str(path), "-o", str(out), "--no-plot"]) == 0
    text = capsys.readouterr().out
    assert "warning: 3 message(s) on /odom with a NaN or infinite pose were left out" in text


def test_only_nan_poses_is_an_error(tmp_path, capsys):
    path = tmp_path / "all_nan"
    with BagOut(path) as bag:
        for i in range(10):
            _odom(bag, 1.0 + 0.1 * i, math.nan)
    err = run_cli(capsys, tmp_path, "from-bag", str(path))
    assert "every pose on /odom (10 messages) has a NaN or infinite position" in err


def test_nan_angle_increment_is_an_error_not_an_empty_seed(tmp_path, capsys):
    """Before: exit 0 and a seed without obstacles."""
    path = tmp_path / "nan_inc"
    with BagOut(path) as bag:
        for i in range(30):
            _odom(bag, 1.0 + 0.1 * i, 0.1 * i)
            _scan(bag, 1.0 + 0.1 * i, angle_increment=math.nan)
    err = run_cli(capsys, tmp_path, "from-bag", str(path))
    assert "every scan read on /scan is unusable" in err and "angle_increment nan is not a number" in err


def test_one_odometry_message_is_an_error(tmp_path, capsys):
    """Before: exit 0 and a seed whose start equals its goal."""
    path = tmp_path / "one"
    with BagOut(path) as bag:
        _odom(bag, 1.0, 0.5)
    err = run_cli(capsys, tmp_path, "from-bag", str(path))
    assert "/odom has 1 usable message(s): a seed needs the robot's poses over time" in err


def test_a_robot_that_never_moved_is_an_error(tmp_path, capsys):
    path = tmp_path / "still"
    with BagOut(path) as bag:
        for i in range(30):
            _odom(bag, 1.0 + 0.1 * i, 0.5)
    err = run_cli(capsys, tmp_path, "from-bag", str(path))
    assert "the robot hardly moved in the window" in err and "--start/--end, --at" in err


def test_all_equal_stamps_are_an_error(tmp_path, capsys):
    """Before: max_speed 0.2 (the default for a robot that never moved) without a word."""
    path = tmp_path / "same_stamp"
    with BagOut(path) as bag:
        for i in range(30):
            _odom(bag, 1.0 + 0.1 * i, 0.1 * i, at=5.0)
    err = run_cli(capsys, tmp_path, "from-bag", str(path))
    assert "all 30 messages on /odom have the same header stamp (5.000 s)" in err


def _cloud(bag: BagOut, t: float, step: int, x_offset: int = 0, size: int | None = None) -> None:
    data = np.zeros((size if size is not None else 100 * 22), np.uint8)
    bag.write("/points", "sensor_msgs/msg/PointCloud2", t, {
        "header": {"stamp": stamp(t), "frame_id": "laser"}, "height": 1, "width": 100,
        "fields": [{"name": n, "offset": o, "datatype": 7, "count": 1}
                   for n, o in (("x", x_offset), ("y", 4), ("z", 8))],
        "is_bigendian": False, "point_step": step, "row_step": step * 100, "data": data, "is_dense": True})


@pytest.mark.parametrize("step, x_offset, expected", [
    (29, 0, "the point cloud's data is 2200 bytes, but its header (width 100 x height 1, point_step 29, row_step "
            "2900) needs 2900; its data holds 22 bytes a point"),
    (0, 0, "the point cloud's point_step is 0"),
    (22, 40, "point cloud field x at offset 40 (4 bytes) lies outside a point of point_step 22 bytes"),
])
def test_a_point_cloud_whose_header_does_not_fit_its_data(tmp_path, capsys, step, x_offset, expected):
    """Before: 'damaged or truncated' with a ValueError."""
    path = tmp_path / f"cloud{step}"
    with BagOut(path) as bag:
        for i in range(20):
            _odom(bag, 1.0 + 0.1 * i, 0.1 * i)
            _cloud(bag, 1.0 + 0.1 * i, step, x_offset)
    err = run_cli(capsys, tmp_path, "from-bag", str(path))
    assert f"{path}: /points: {expected}" in err


def test_a_goal_on_an_obstacle_names_the_output_file_not_a_temporary_one(tmp_path, capsys):
    """Before: the error named /tmp/tmpXXXX/seed.yaml, a copy that no longer exists."""
    world = World(pillars=[(3.0, 1.5, 0.3, 1.0)])
    t = np.arange(40) * 0.1
    drive = np.stack([t, 0.5 * t, 0 * t, 0 * t], 1)

    def goal(bag):
        bag.write("/goal_pose", "geometry_msgs/msg/PoseStamped", 0.5, {
            "header": {"stamp": stamp(0.5), "frame_id": "map"}, "pose": pose_msg(3.0, 1.5, 0.0)})

    path = robot_bag(tmp_path / "goal_in_pillar", world, drive, extra=goal)
    err = run_cli(capsys, tmp_path, "from-bag", str(path))
    out = tmp_path / "out" / "seed.yaml"
    assert err.startswith(f"navscenario from-bag: error: {out}: not written") and "mission.goal" in err
    assert "/tmp" not in err.replace(str(tmp_path), "")


def test_the_seed_is_written_with_the_usual_mode(tmp_path):
    """Before: 0600 (the temporary file's mode), unreadable by the rest of a team."""
    out = tmp_path / "s.yaml"
    t = np.arange(30) * 0.1
    path = robot_bag(tmp_path / "b", World(pillars=[(2.0, 1.0, 0.2, 1.0)]), np.stack([t, 0.5 * t, 0 * t, 0 * t], 1))
    old = os.umask(0o022)
    try:
        assert main(["from-bag", str(path), "-o", str(out), "--no-plot", "--path-as", "both"]) == 0
    finally:
        os.umask(old)
    for f in (out, tmp_path / "s.reference.csv", tmp_path / "s.fit.json"):
        assert stat.S_IMODE(f.stat().st_mode) == 0o644, f


def test_a_loop_back_to_the_start_without_waypoints_is_an_error(tmp_path, capsys):
    """The TurtleBot3 drives a loop and stops where it started: as a reference trajectory only (no
    waypoints), the seed's goal would be its start; the error says so and how to keep the loop."""
    tb3 = Path(__file__).resolve().parents[1] / "data" / "fuse_turtlebot3.bag"
    err = run_cli(capsys, tmp_path, "from-bag", str(tb3), "--path-as", "reference")
    assert "the robot drove a loop in the window" in err and "--path-as waypoints or both" in err
