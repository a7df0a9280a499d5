"""The sensors of a wheeled robot riding the terrain, in real episodes: the 2D lidar's plane tilts
with the body (a ramp ahead reads as a wall, a pit is invisible), the IMU's attitude and the 3D
lidar's points are in the observation, and the safety layer stops the robot before a pit its 3D
lidar sees but cannot before one it does not see (it falls in)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.verdict.result import Outcome

PIT = """
version: 1
robot:
  body: {type: wheeled}
  drive: diff
  LIDAR3D
mission: {start: {x: 0, y: 0}, goal: {x: 8, y: 0}, timeout: 20}
terrain:
  - {type: pit, name: hole, x: 4.5, y: 0, length: 1.5, width: 6, depth: 1.0}
"""

RAMP = """
version: 1
robot:
  body: {type: wheeled}
  drive: diff
  lidar3d: {rings: 16, beams: 360, mount_z: 0.5}
mission: {start: {x: 0, y: 0}, goal: {x: 12, y: 0}, timeout: 15}
terrain:
  - {type: ramp, name: up, x: 4, y: 0, length: 4, width: 3, rise: 0.70530, z: 0}    # 10 degrees
  - {type: platform, name: top, x: 8, y: 0, length: 4, width: 3, height: 0.70530}
"""


class Straight:
    """Drives straight ahead, keeping what it is handed."""

    def __init__(self, speed: float = 0.6):
        self.speed, self.seen = speed, []

    def reset(self, scenario):
        self.seen.clear()

    def act(self, obs):
        self.seen.append(obs)
        return (self.speed, 0.0, 0.0)


def test_the_safety_layer_stops_a_robot_before_a_pit_its_3d_lidar_sees():
    s = loads_scenario(PIT.replace("LIDAR3D", "lidar3d: {}"))
    result = run_scenario(s, Straight())
    assert result.outcome is Outcome.SAFETY_STOP, result.message
    assert "drive into a drop ahead at pit 'hole'" in result.message and "3D lidar" in result.message
    front = result.trajectory.pose[-1, 0] + s.robot.footprint.length / 2.0
    assert front < 4.5 - 0.75                       # still on the ground before the pit's edge
    assert "lidar3d" in result.timings


def test_without_a_3d_lidar_it_cannot_see_the_pit_and_the_robot_falls_in():
    s = loads_scenario(PIT.replace("LIDAR3D", ""))
    planner = Straight()
    result = run_scenario(s, planner)
    assert result.outcome is Outcome.FALL and "fell into pit 'hole'" in result.message
    # the 2D lidar's plane passed over the pit: no beam ahead returned while the robot was level
    ahead = np.argmin(np.abs(planner.seen[0].angles))
    level = [obs for obs in planner.seen if abs(obs.attitude[1]) < 0.01]
    assert len(level) > 20
    assert all(obs.ranges[ahead] == np.float32(s.robot.lidar.range_max) for obs in level)
    assert all(obs.points is None for obs in planner.seen)


def test_on_a_ramp_the_2d_lidar_sees_a_wall_then_tilts_with_the_body_and_the_imu_reads_the_slope():
    s = loads_scenario(RAMP)
    planner = Straight(speed=0.5)
    result = run_scenario(s, planner)
    first = planner.seen[0]
    ahead = int(np.argmin(np.abs(first.angles)))
    mount = s.robot.lidar.mount_height
    # at the start the scan plane (0.2 m up) meets the 10 degree slope 0.2 / tan(10 deg) up the ramp
    assert first.ranges[ahead] == pytest.approx(2.0 + mount / math.tan(math.radians(10.0)), abs=0.06)
    assert first.attitude == pytest.approx([0.0, 0.0], abs=0.01)
    on_ramp = [o for o in planner.seen if 3.0 < o.pose[0] < 5.0]
    assert on_ramp, result.message
    traj = result.trajectory
    for obs in on_ramp:
        # the IMU reads the body's attitude (nose up on the 10 degree slope: pitch is positive nose
        # down; the chassis on its wheels and casters sits a little steeper than the slope) ...
        i = int(round(obs.time / s.simulation.timestep))
        assert obs.attitude.tolist() == pytest.approx([traj.roll[i], traj.pitch[i]], abs=1e-9)
        assert -math.radians(14.0) < obs.attitude[1] < -math.radians(9.0)
        # ... and the scan plane is parallel to the slope: the beam ahead no longer meets the ramp
        assert obs.ranges[ahead] > 3.0
    # the 3D lidar's floor points lie 0.5 m under the level sensor at the start
    pts = first.points
    floor = pts[(np.abs(pts[:, 1]) < 1.0) & (pts[:, 0] > 0) & (pts[:, 0] < 1.9)]
    assert len(floor) > 5 and floor[:, 2] == pytest.approx(-0.5, abs=0.02)
