"""Bags we write: read back with rosbags (every topic, count, type, content), valid MCAP, all
three formats, atomic on failure, and the round trip episode -> bag -> seed scenario.

One real MuJoCo episode per seed scenario is shared by the whole module."""
from __future__ import annotations

import dataclasses
import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.ros.bag_import import scenario_from_bag
from pytest_navscenario.ros.bag_writer import LATCHED, ODOM_MAX_RATE, TOPICS, BagWriteError, default_bag_path, write_episode_bag
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


@pytest.fixture(scope="module")
def episodes():
    """name -> EpisodeResult of the built-in DWA on two seed scenarios (cylinders, boxes2)."""
    return {name: run_scenario(load_scenario(SCENARIOS / f"{name}.yaml"), "dwa")
            for name in ("cylinders", "boxes2")}


def read_bag(path: Path):
    """{topic: (msgtype, [(timestamp_ns, message), ...])} read with rosbags' AnyReader."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    out: dict[str, tuple[str, list]] = {}
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        for conn in reader.connections:
            out.setdefault(conn.topic, (conn.msgtype, []))
        for conn, ts, raw in reader.messages():
            out[conn.topic][1].append((ts, reader.deserialize(raw, conn.msgtype)))
    return out


def expected_counts(result) -> dict[str, int]:
    traj = result.trajectory
    dt = float(np.median(np.diff(traj.t)))
    stride = max(1, round(1.0 / (ODOM_MAX_RATE * dt)))
    n_odom = len(range(0, len(traj.t), stride)) + (0 if (len(traj.t) - 1) % stride == 0 else 1)
    ticks = len(traj.tick_t)
    counts = {topic: 1 for topic in TOPICS}
    counts.update({"/odom": n_odom, "/tf": n_odom, "/scan": ticks, "/cmd_vel": ticks})
    return counts


def check_mcap_file(path: Path) -> int:
    """Walk an MCAP file record by record (magic, opcode, u64 length) up to the footer and the
    closing magic, as the MCAP spec lays it out; return the number of records."""
    data = path.read_bytes()
    magic = b"\x89MCAP0\r\n"
    assert data[:8] == magic and data[-8:] == magic, f"{path}: MCAP magic missing"
    pos, records, opcodes = 8, 0, set()
    while pos < len(data) - 8:
        opcode = data[pos]
        (length,) = struct.unpack_from("<Q", data, pos + 1)
        pos += 9 + length
        records += 1
        opcodes.add(opcode)
        if opcode == 0x02:  # footer
            break
    assert pos == len(data) - 8, f"{path}: records do not end at the closing magic"
    assert {0x01, 0x02, 0x03, 0x04} <= opcodes  # header, footer, schema, channel
    return records


def test_mcap_bag_reads_back_every_topic_count_and_type(episodes, tmp_path):
    result = episodes["cylinders"]
    path = write_episode_bag(result, tmp_path / "ep")
    assert path == tmp_path / "ep" and path.is_dir()
    mcaps = list(path.glob("*.mcap"))
    assert len(mcaps) == 1 and check_mcap_file(mcaps[0]) > 10
    assert "storage_identifier: mcap" in (path / "metadata.yaml").read_text()

    bag = read_bag(path)
    assert {t: m for t, (m, _) in bag.items()} == TOPICS
    assert {t: len(msgs) for t, (_, msgs) in bag.items()} == expected_counts(result)

    traj = result.trajectory
    odom = bag["/odom"][1]
    ts0, first = odom[0]
    assert (first.header.frame_id, first.child_frame_id) == ("odom", "base_link")
    assert first.pose.pose.position.x == traj.pose[0, 0] and first.pose.pose.position.y == traj.pose[0, 1]
    last = odom[-1][1]
    assert last.pose.pose.position.x == traj.pose[-1, 0]  # the final pose is always in the bag
    q = last.pose.pose.orientation
    assert math.isclose(2 * math.atan2(q.z, q.w), traj.pose[-1, 2], abs_tol=1e-9)

    scans = bag["/scan"][1]
    np.testing.assert_array_equal(scans[3][1].ranges, traj.ranges[3])
    assert scans[3][0] == round(traj.tick_t[3] * 1e9)
    assert math.isclose(scans[0][1].angle_min, traj.angles[0], abs_tol=1e-6)
    assert scans[0][1].header.frame_id == "laser"
    cmd = bag["/cmd_vel"][1][5][1]
    assert (cmd.linear.x, cmd.linear.y, cmd.angular.z) == tuple(traj.command[5])

    static = bag["/tf_static"][1][0][1].transforms[0]
    assert (static.header.frame_id, static.child_frame_id) == ("base_link", "laser")
    goal = bag["/goal_pose"][1][0][1].pose.position
    assert (goal.x, goal.y) == (result.scenario.mission.goal.x, result.scenario.mission.goal.y)

    markers = bag["/navscenario/obstacles"][1][0][1].markers
    assert [m.text for m in markers] == [o.name for o in result.scenario.obstacles]
    cyl = result.scenario.obstacles[0]
    assert markers[0].type == 3 and markers[0].scale.x == 2 * cyl.radius

    summary = json.loads(bag["/navscenario/result"][1][0][1].data)
    assert summary["outcome"] == result.outcome.value
    assert summary["metrics"]["min_clearance"] == result.metrics.min_clearance

    from pytest_navscenario.scenario.loader import loads_scenario
    assert loads_scenario(bag["/navscenario/scenario"][1][0][1].data) == result.scenario


def test_latched_topics_carry_transient_local_qos(episodes, tmp_path):
    path = write_episode_bag(episodes["cylinders"], tmp_path / "ep")
    text = (path / "metadata.yaml").read_text()
    import yaml
    meta = yaml.safe_load(text)["rosbag2_bagfile_information"]["topics_with_message_count"]
    durability = {t["topic_metadata"]["name"]: [q["durability"] for q in t["topic_metadata"]["offered_qos_profiles"]]
                  for t in meta}
    assert all(durability[t] == ["transient_local"] for t in LATCHED)
    assert durability["/odom"] == []


@pytest.mark.parametrize("fmt", ["sqlite3", "ros1"])
def test_other_formats_hold_the_same_messages(episodes, tmp_path, fmt):
    result = episodes["boxes2"]
    path = write_episode_bag(result, default_bag_path(tmp_path, "ep", fmt), fmt=fmt)
    assert path.name == ("ep.bag" if fmt == "ros1" else "ep")
    bag = read_bag(path)
    assert {t: m for t, (m, _) in bag.items()} == TOPICS
    assert {t: len(msgs) for t, (_, msgs) in bag.items()} == expected_counts(result)
    np.testing.assert_array_equal(bag["/scan"][1][-1][1].ranges, result.trajectory.ranges[-1])


def test_same_episode_gives_the_same_bytes(episodes, tmp_path):
    a = write_episode_bag(episodes["boxes2"], tmp_path / "a.bag", fmt="ros1").read_bytes()
    b = write_episode_bag(episodes["boxes2"], tmp_path / "b.bag", fmt="ros1").read_bytes()
    assert a == b
    one = write_episode_bag(episodes["boxes2"], tmp_path / "1" / "ep")
    two = write_episode_bag(episodes["boxes2"], tmp_path / "2" / "ep")
    for name in ("ep.mcap", "metadata.yaml"):
        assert (one / name).read_bytes() == (two / name).read_bytes()


def test_rewrite_replaces_and_failure_leaves_nothing(episodes, tmp_path):
    result = episodes["cylinders"]
    path = write_episode_bag(result, tmp_path / "ep")
    write_episode_bag(result, path)  # replaces the bag of a previous run
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ep"]
    broken = dataclasses.replace(result, trajectory=dataclasses.replace(
        result.trajectory, command=result.trajectory.command[:, :2]))  # fails mid-write
    with pytest.raises(ValueError):
        write_episode_bag(broken, tmp_path / "new")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ep"]  # no partial bag, no temp folder
    with pytest.raises(BagWriteError, match="unknown bag format 'db3'.*mcap, sqlite3, ros1"):
        write_episode_bag(result, tmp_path / "x", fmt="db3")


@pytest.mark.parametrize("name", ["cylinders", "boxes2"])
def test_round_trip_episode_bag_seed_recovers_obstacles(episodes, tmp_path, name):
    """Tolerance: every obstacle of the scenario is recovered as one obstacle of the same kind,
    centre within 0.05 m, radius / side lengths within 0.05 m, box yaw within 2 degrees (mod 90);
    start comes from the first odometry pose, the driven path ends at the last (within 1 mm);
    the goal is the recorded navigation goal on /goal_pose, i.e. the scenario's own (issue 17;
    before, the last odometry pose was taken as the goal)."""
    result = episodes[name]
    imported = scenario_from_bag(write_episode_bag(result, tmp_path / name))
    seed = imported.scenario
    original = result.scenario.obstacles
    assert len(seed.obstacles) == len(original), seed.obstacles
    for obs in original:
        got = min(seed.obstacles, key=lambda o: math.hypot(o.x - obs.x, o.y - obs.y))
        assert type(got) is type(obs)
        assert math.hypot(got.x - obs.x, got.y - obs.y) < 0.05, (obs, got)
        if isinstance(obs, CylinderObstacle):
            assert abs(got.radius - obs.radius) < 0.05
        else:
            assert isinstance(got, BoxObstacle)
            assert sorted([got.length, got.width]) == pytest.approx(sorted([obs.length, obs.width]), abs=0.05)
            assert min(abs(got.yaw - obs.yaw) % 90, 90 - abs(got.yaw - obs.yaw) % 90) < 2.0
    pose = result.trajectory.pose
    assert (seed.mission.start.x, seed.mission.start.y) == pytest.approx(tuple(pose[0, :2]), abs=1e-3)
    assert tuple(imported.path[-1, 1:]) == pytest.approx(tuple(pose[-1, :2]), abs=1e-3)
    goal = result.scenario.mission.goal
    assert (seed.mission.goal.x, seed.mission.goal.y) == pytest.approx((goal.x, goal.y), abs=1e-3)
    assert seed.mission.goal.yaw == pytest.approx(goal.yaw, abs=0.01)
    assert any(n.startswith("goal from /goal_pose") for n in imported.notes)


def test_hit_obstacle_is_red_and_the_event_is_in_the_result(episodes, tmp_path):
    from pytest_navscenario.sim.trajectory import Collision
    from pytest_navscenario.verdict.result import Outcome
    result = episodes["cylinders"]
    name = result.scenario.obstacles[1].name
    crashed = dataclasses.replace(result, outcome=Outcome.COLLISION,
                                  collision=Collision(time=4.2, obstacle=name, x=1.0, y=5.0, depth=0.01))
    written = write_episode_bag(crashed, tmp_path / "crash", fmt="ros1")
    assert written == tmp_path / "crash.bag"
    bag = read_bag(written)
    colours = [(m.color.r, m.color.g, m.color.b) for m in bag["/navscenario/obstacles"][1][0][1].markers]
    assert colours[1] == pytest.approx((0.9, 0.2, 0.15)) and colours[0] != colours[1]
    summary = json.loads(bag["/navscenario/result"][1][0][1].data)
    assert summary["outcome"] == "collision" and summary["collision"]["obstacle"] == name
