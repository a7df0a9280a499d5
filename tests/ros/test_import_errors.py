"""Bad input to the importers: one clear line naming the file and what is wrong, exit status 2,
and no output file (nor temporary file) left behind."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.cli import main

DATA = Path(__file__).resolve().parents[1] / "data"
TB3 = DATA / "fuse_turtlebot3.bag"


def run_cli(capsys, tmp_path, *argv):
    out = tmp_path / "out" / "seed.yaml"
    rc = main([*argv, "-o", str(out)])
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert len(err.splitlines()) == 1, err
    leftovers = sorted(p.name for p in out.parent.iterdir()) if out.parent.exists() else []
    assert leftovers == [], f"left behind: {leftovers}"
    return err


def write_map(folder: Path, image: str = "m.pgm", make_image: bool = True) -> Path:
    if make_image:
        img = np.full((4, 5), 254, np.uint8)
        (folder / "m.pgm").write_bytes(b"P5\n5 4\n255\n" + img.tobytes())
    yaml_path = folder / "map.yaml"
    yaml_path.write_text(f"image: {image}\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"
                         f"occupied_thresh: 0.65\nfree_thresh: 0.196\nnegate: 0\n")
    return yaml_path


def test_not_a_bag(capsys, tmp_path):
    bad = tmp_path / "notes.bag"
    bad.write_text("this is not a bag\n")
    err = run_cli(capsys, tmp_path, "from-bag", str(bad))
    assert str(bad) in err and "not a readable ROS 1 / rosbag2 bag" in err


def test_truncated_bag(capsys, tmp_path):
    cut = tmp_path / "cut.bag"
    cut.write_bytes(TB3.read_bytes()[:600_000])
    err = run_cli(capsys, tmp_path, "from-bag", str(cut))
    assert f"{cut}: a damaged or truncated bag" in err


def test_truncated_mcap_bag(capsys, tmp_path):
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    from pytest_navscenario.ros.bag_writer import build
    ts = get_typestore(Stores.ROS2_HUMBLE)
    bag = tmp_path / "run"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conn = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        for i in range(200):
            msg = build(ts, "nav_msgs/msg/Odometry", {"header": {"stamp": {"sec": i}}})
            w.write(conn, (i + 1) * 1_000_000_000, ts.serialize_cdr(msg, "nav_msgs/msg/Odometry"))
    mcap = bag / "run.mcap"
    mcap.write_bytes(mcap.read_bytes()[: mcap.stat().st_size // 2])
    err = run_cli(capsys, tmp_path, "from-bag", str(bag))
    assert f"{bag}: a damaged or truncated bag" in err


def test_missing_bag(capsys, tmp_path):
    err = run_cli(capsys, tmp_path, "from-bag", str(tmp_path / "nope.bag"))
    assert "nope.bag: no such bag file or folder" in err


def test_bag_without_odometry(capsys, tmp_path):
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    from pytest_navscenario.ros.bag_writer import build
    ts = get_typestore(Stores.ROS1_NOETIC)
    bag = tmp_path / "cmd_only.bag"
    with Writer(bag) as w:
        conn = w.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=ts)
        w.write(conn, 1_000_000_000, ts.serialize_ros1(build(ts, "geometry_msgs/msg/Twist"), "geometry_msgs/msg/Twist"))
    err = run_cli(capsys, tmp_path, "from-bag", str(bag))
    assert str(bag) in err and "no odometry (nav_msgs/msg/Odometry)" in err and "/cmd_vel" in err


def test_unknown_topic_name(capsys, tmp_path):
    err = run_cli(capsys, tmp_path, "from-bag", str(TB3), "--odom-topic", "/wheel_odom")
    assert "no topic '/wheel_odom'" in err and "/odom (nav_msgs/msg/Odometry)" in err and "--odom-topic" in err
    err = run_cli(capsys, tmp_path, "from-bag", str(TB3), "--scan-topic", "/imu")
    assert "topic /imu is sensor_msgs/msg/Imu, not sensor_msgs/msg/LaserScan" in err


def test_empty_time_window(capsys, tmp_path):
    err = run_cli(capsys, tmp_path, "from-bag", str(TB3), "--start", "500")
    assert "fewer than 2 odometry messages" in err and "--start 500" in err


def test_map_image_missing(capsys, tmp_path):
    yaml_path = write_map(tmp_path, make_image=False)
    err = run_cli(capsys, tmp_path, "from-map", str(yaml_path), "--start", "0,0,0", "--goal", "1,0,0")
    assert str(yaml_path) in err and "image: 'm.pgm' not found" in err


def test_map_image_absolute_path(capsys, tmp_path):
    yaml_path = write_map(tmp_path, image=str(tmp_path / "m.pgm"))
    err = run_cli(capsys, tmp_path, "from-map", str(yaml_path), "--start", "0,0,0", "--goal", "1,0,0")
    assert str(yaml_path) in err and "absolute path" in err and "image: m.pgm" in err


def test_map_image_not_pgm(capsys, tmp_path):
    yaml_path = write_map(tmp_path)
    (tmp_path / "m.pgm").write_bytes(b"\x89PNG\r\n")
    err = run_cli(capsys, tmp_path, "from-map", str(yaml_path), "--start", "0,0,0", "--goal", "1,0,0")
    assert "m.pgm: not a PGM image" in err


def test_sdf_not_xml(capsys, tmp_path):
    bad = tmp_path / "w.world"
    bad.write_text("<sdf version='1.6'><world name='x'>\n<model name='a'>\n")
    err = run_cli(capsys, tmp_path, "import", "sdf", str(bad), "--start=0,0,0", "--goal=1,0,0")
    assert str(bad) in err and "not well-formed XML" in err


def test_sdf_without_mission(capsys, tmp_path):
    err = run_cli(capsys, tmp_path, "import", "sdf", str(DATA / "barn_world_0.world"))
    assert "pass --start x,y,yaw and --goal x,y,yaw" in err


def test_aerialist_template_placeholders(capsys, tmp_path):
    src = DATA / "aerialist_template.yaml"
    err = run_cli(capsys, tmp_path, "import", "aerialist", str(src))
    assert f"{src}:10: simulation.obstacles[0]: expected a number, got 'l'" in err


def test_start_inside_an_obstacle_writes_nothing(capsys, tmp_path):
    err = run_cli(capsys, tmp_path, "import", "sdf", str(DATA / "barn_world_0.world"),
                  "--start=-0.075,0.075,0", "--goal=-2.25,13,90")
    assert "not written" in err and "mission.start" in err and "unit_cylinder_0" in err


def test_existing_output_is_not_replaced(capsys, tmp_path):
    out = tmp_path / "seed.yaml"
    out.write_text("hand-edited\n")
    rc = main(["import", "aerialist", str(DATA / "aerialist_mission1.yaml"), "-o", str(out)])
    assert rc == 2 and "already exists" in capsys.readouterr().err
    assert out.read_text() == "hand-edited\n"
    assert main(["import", "aerialist", str(DATA / "aerialist_mission1.yaml"), "-o", str(out), "--force"]) == 0


@pytest.mark.parametrize("pose", ["1,2,3,4", "a,b,c", "nan,0,0"])
def test_bad_pose_option(capsys, tmp_path, pose):
    err = run_cli(capsys, tmp_path, "from-map", str(write_map(tmp_path)), f"--start={pose}", "--goal=1,0,0")
    assert "--start" in err and "expected x,y,yaw" in err
