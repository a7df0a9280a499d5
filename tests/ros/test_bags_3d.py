"""Bags of episodes with a 3D lidar: its scans as sensor_msgs/PointCloud2 in its own frame (read back
with rosbags: the same points the planner was handed), its mount and the 2D lidar's on /tf_static,
and the scans crossing from an xdist worker only when bags ask for them."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.ros.bag_writer import CLOUD_TOPIC, write_episode_bag
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.scenario.terrain import Lidar3D
from pytest_navscenario.sim.trajectory import trajectory_from_dict, trajectory_to_dict

from test_bags import read_bag

SCENARIO = """
version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 6, y: 0}, timeout: 4}
obstacles:
  - {type: box, name: wall, x: 3, y: 1.5, length: 4, width: 0.3, height: 1.5}
"""


class Seen:
    """Drives ahead slowly, keeping the points it is handed."""

    def __init__(self):
        self.points = []

    def reset(self, scenario):
        self.points.clear()

    def act(self, obs):
        self.points.append(np.array(obs.points))
        return (0.4, 0.0, 0.0)


@pytest.fixture(scope="module")
def episode():
    s = loads_scenario(SCENARIO)
    s = replace(s, robot=replace(s.robot, lidar=replace(s.robot.lidar, mount_height=0.3),
                                 lidar3d=Lidar3D(rings=8, beams=180, fov_low=-15, fov_high=5, mount_x=0.2,
                                                 mount_z=0.6, mount_pitch=5.0)))
    planner = Seen()
    return run_scenario(s, planner), planner


@pytest.mark.parametrize("fmt", ["mcap", "ros1"])
def test_the_3d_lidar_is_a_pointcloud2_in_its_own_frame(tmp_path, episode, fmt):
    result, planner = episode
    path = write_episode_bag(result, tmp_path / "ep", fmt=fmt)
    bag = read_bag(path)
    msgtype, msgs = bag[CLOUD_TOPIC]
    assert msgtype == "sensor_msgs/msg/PointCloud2" and len(msgs) == result.trajectory.cloud.shape[0]
    first = msgs[0][1]
    assert first.header.frame_id == "lidar3d" and first.height == 1 and first.point_step == 16
    assert [f.name for f in first.fields] == ["x", "y", "z", "ring"]
    record = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("ring", "<u2"), ("pad", "<u2")])
    pts = np.frombuffer(bytes(first.data), dtype=record)
    assert len(pts) == first.width == len(planner.points[0])
    xyz = np.column_stack([pts["x"], pts["y"], pts["z"]])
    assert np.allclose(xyz, planner.points[0], atol=1e-5)        # what the planner was handed
    assert pts["ring"].min() == 0 and pts["ring"].max() <= 7
    (static,) = [m for _, m in bag["/tf_static"][1]]
    frames = {t.child_frame_id: t.transform for t in static.transforms}
    assert frames["laser"].translation.z == pytest.approx(0.3)
    mount = frames["lidar3d"]
    assert (mount.translation.x, mount.translation.z) == pytest.approx((0.2, 0.6))
    assert mount.rotation.y == pytest.approx(math.sin(math.radians(5.0) / 2.0))


def test_a_bag_without_a_3d_lidar_has_no_points_topic(tmp_path, episode):
    result, _ = episode
    plain = run_scenario(replace(result.scenario, robot=replace(result.scenario.robot, lidar3d=None)), "dwa")
    assert CLOUD_TOPIC not in read_bag(write_episode_bag(plain, tmp_path / "plain"))


def test_the_scans_cross_from_a_worker_only_on_request_and_whole(episode):
    result, _ = episode
    traj = result.trajectory
    assert "cloud" not in trajectory_to_dict(traj)
    back = trajectory_from_dict(trajectory_to_dict(traj, cloud=True))
    assert back.cloud.dtype == np.float32 and np.array_equal(back.cloud, traj.cloud)


def test_a_bag_of_a_robot_on_terrain_has_its_3d_pose_and_the_ground(tmp_path):
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "sim"))
    from test_sensors_riding import RAMP, Straight

    from pytest_navscenario.ros.bag_writer import TERRAIN_TOPIC
    from pytest_navscenario.scenario.ground import surface as ground

    s = loads_scenario(RAMP.replace("  lidar3d: {rings: 16, beams: 360, mount_z: 0.5}\n", ""))
    assert s.robot.lidar3d is None
    result = run_scenario(s, Straight(speed=0.5))
    bag = read_bag(write_episode_bag(result, tmp_path / "ramp"))
    # the base's height and attitude on /tf and /odom, as recorded
    traj = result.trajectory
    tfs = [(ts, m.transforms[0]) for ts, m in bag["/tf"][1]]
    up = [(ts, tf) for ts, tf in tfs if tf.transform.translation.z > 0.2]
    assert up, "the base never rose on the ramp"
    ts, tf = up[len(up) // 2]
    i = int(round(ts * 1e-9 / s.simulation.timestep))
    q = tf.transform.rotation
    pitch = math.asin(max(-1.0, min(1.0, 2 * (q.w * q.y - q.z * q.x))))
    assert tf.transform.translation.z == pytest.approx(traj.z[i], abs=1e-9)
    assert pitch == pytest.approx(traj.pitch[i], abs=1e-6)
    odom = bag["/odom"][1][len(bag["/odom"][1]) // 2][1]
    assert odom.pose.pose.orientation.y != 0.0 or odom.pose.pose.position.z == 0.0
    # the ground: a triangle list per element whose vertices lie on the ground
    (markers,) = [m for _, m in bag[TERRAIN_TOPIC][1]]
    assert [m.text for m in markers.markers] == ["ramp 'up'", "platform 'top'"]
    ramp = markers.markers[0]
    assert ramp.type == 11 and len(ramp.points) % 3 == 0 and len(ramp.colors) == len(ramp.points)
    pts = np.array([(p.x, p.y, p.z) for p in ramp.points])
    assert np.allclose(pts[:, 2], ground.ground_height(s, pts[:, 0], pts[:, 1]))
    assert pts[:, 2].max() == pytest.approx(0.7053, abs=1e-3)
