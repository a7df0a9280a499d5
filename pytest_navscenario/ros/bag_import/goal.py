"""The seed's goal: the navigation goal the bag recorded (Nav2 / RViz ``/goal_pose``, a
NavigateToPose goal, a ROS 1 ``move_base`` goal or ``/move_base_simple/goal``), not the place the
robot stopped, which in a failure is not where it was going.

The goal in force at the end of the window is used: the last one sent before it. A goal in the
odometry frame is moved into the map frame with the correction at its time; a goal in a frame
the seed cannot reach is a warning and the last pose of the window is the goal instead.
"""
from __future__ import annotations

import math

import numpy as np

from .frames import compose, held
from .reading import BagData, BagImportError


def choose_goal(data: BagData, corr: np.ndarray | None, goal_topic: str | None = None
                ) -> tuple[tuple[float, float, float] | None, str]:
    """(x, y, yaw rad) of the goal in the seed's world frame, or None (use the last pose); and a
    note saying which was used and why."""
    goals = data.goals
    if goal_topic is not None:
        topics = sorted({g[5] for g in goals})
        goals = [g for g in goals if g[5] == goal_topic]
        if not goals:
            raise BagImportError(f"{data.path}: no goal on {goal_topic!r} (goal topics in the bag: "
                                 f"{', '.join(topics) or 'none'}); fix --goal-topic")
    end = float(data.odom[-1, 0])
    before = [g for g in goals if g[0] <= end + 1e-6]
    last_pose = "the last pose of the window"
    if not before:
        why = "no navigation goal in the bag" if not goals else f"the first goal is sent after the window ({goals[0][0]:.1f} s)"
        return None, f"goal: {last_pose} ({why})"
    t, frame, x, y, yaw, topic = before[-1]
    count = f"{len(before)} goals before the window's end, the last used" if len(before) > 1 else "the only goal"
    where = f"{topic}, sent at t={t:.1f} s ({count})"
    if frame in (data.frame, "") or (frame == data.odom_frame and corr is None):
        pose = (x, y, yaw)
    elif frame == data.odom_frame and corr is not None:
        pose = tuple(compose(held(corr, np.array([t]))[0], np.array([x, y, yaw])))
        where += f", moved from {frame} into {data.frame} with the correction at its time"
    else:
        return None, (f"warning: the goal on {where} is in frame {frame!r}, which the seed's frame {data.frame!r} "
                      f"cannot be related to (no transform in the bag): the goal is {last_pose} instead")
    return (float(pose[0]), float(pose[1]), float(pose[2])), f"goal from {where}: x={pose[0]:.2f} y={pose[1]:.2f} " \
        f"yaw={math.degrees(pose[2]):.0f} deg"
