"""Issue 17, the goal: the robot stops halfway to its navigation goal (an unexpected stop); the seed's
goal is the recorded goal, not where it stopped, whichever way the goal was recorded, and in the
seed's frame. Generated bags: drifting odometry with the exact map -> odom on /tf."""
from __future__ import annotations

import math

import numpy as np
import pytest
from ros_synthetic import World, compose, invert, register_goal_types, robot_bag, stamp, stop_drive, pose_msg

from pytest_navscenario.ros.bag_import import BagImportError, scenario_from_bag

WORLD = World(pillars=[(1.0, 1.2, 0.2, 1.0), (3.0, -1.2, 0.2, 1.0)])
GOAL = (4.0, 0.0, 0.0)        # map frame


def _drift(truth):
    t = truth[:, 0]
    return np.stack([0.05 * t, 0.03 * t, np.radians(1.0 * t)], 1)


def _goal_writer(topic, msgtype, frame, value_of, t_goal=0.5):
    def write(bag):
        register_goal_types(bag.ts, bag.ros1)
        truth = stop_drive()
        drift = _drift(truth)
        k = int(round(t_goal / 0.1))
        gx, gy, gyaw = GOAL if frame == "map" else compose(invert(drift[k]), np.array(GOAL))
        ps = {"header": {"stamp": stamp(t_goal), "frame_id": frame}, "pose": pose_msg(gx, gy, gyaw)}
        bag.write(topic, msgtype, t_goal, value_of(ps))
    return write


CASES = {
    "nav2 /goal_pose": (False, "/goal_pose", "geometry_msgs/msg/PoseStamped", "map", lambda ps: ps),
    "nav2 NavigateToPose goal, in odom": (False, "/navigate_to_pose/goal", "nav2_msgs/action/NavigateToPose_Goal",
                                          "odom", lambda ps: {"pose": ps}),
    "nav2 send_goal service event (Jazzy)": (False, "/navigate_to_pose/_action/send_goal/_service_event",
                                             "nav2_msgs/msg/NavigateToPose_SendGoal_Event", "map",
                                             lambda ps: {"info": {"event_type": 0},
                                                         "request": [{"goal": {"pose": ps}}]}),
    "ros1 move_base goal": (True, "/move_base/goal", "move_base_msgs/msg/MoveBaseActionGoal", "map",
                            lambda ps: {"header": ps["header"], "goal": {"target_pose": ps}}),
    "ros1 rviz goal, in odom": (True, "/move_base_simple/goal", "geometry_msgs/msg/PoseStamped", "odom",
                                lambda ps: ps),
}


@pytest.mark.parametrize("case", list(CASES))
def test_goal_is_the_recorded_goal_in_the_map_frame(tmp_path, case):
    ros1, topic, msgtype, frame, value_of = CASES[case]
    truth = stop_drive()
    path = robot_bag(tmp_path / ("g.bag" if ros1 else "g"), WORLD, truth, drift=_drift(truth), ros1=ros1,
                     extra=_goal_writer(topic, msgtype, frame, value_of))
    seed = scenario_from_bag(path)
    g = seed.scenario.mission.goal
    assert (g.x, g.y) == pytest.approx(GOAL[:2], abs=0.01) and abs(g.yaw) < 0.1
    assert (seed.scenario.mission.start.x, seed.scenario.mission.start.y) == pytest.approx((0, 0), abs=0.01)
    note = next(n for n in seed.notes if n.startswith("goal from"))
    assert topic in note and "t=0.5 s" in note
    assert ("moved from odom into map" in note) == (frame == "odom")


def test_without_a_goal_the_last_pose_and_it_says_so(tmp_path):
    truth = stop_drive()
    seed = scenario_from_bag(robot_bag(tmp_path / "n", WORLD, truth, drift=_drift(truth)))
    assert seed.scenario.mission.goal.x == pytest.approx(2.0, abs=0.01)
    assert "goal: the last pose of the window (no navigation goal in the bag)" in seed.notes


def test_goal_in_a_frame_that_cannot_be_reached_is_a_warning(tmp_path):
    truth = stop_drive()
    path = robot_bag(tmp_path / "e", WORLD, truth, drift=_drift(truth),
                     extra=_goal_writer("/goal_pose", "geometry_msgs/msg/PoseStamped", "earth", lambda ps: ps))
    seed = scenario_from_bag(path)
    assert seed.scenario.mission.goal.x == pytest.approx(2.0, abs=0.01)
    assert any(n.startswith("warning: the goal on /goal_pose") and "'earth'" in n for n in seed.notes)
    with pytest.raises(BagImportError, match="no goal on '/nav/goal'.*goal topics in the bag: /goal_pose"):
        scenario_from_bag(path, goal_topic="/nav/goal")
