"""Sensor and localisation faults (issue 12, part 3): obstacles the lidar cannot see (glass), the
datasheet lidar noise model, localisation drift and latency. Real MuJoCo episodes."""
from __future__ import annotations

import math

import numpy as np
import pytest

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.dump import dump_scenario
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.scenario.model import content_hash
from pytest_navscenario.sim.episode import simulate


def scenario(text: str, robot: str = "{}", extra: str = ""):
    return loads_scenario(f"version: 1\nrobot: {robot}\nmission: {{start: {{x: 0, y: 0}}, goal: {{x: 6, y: 0}}, "
                          f"timeout: 15}}\nobstacles:\n{text}\n{extra}", source="faults.yaml")


class Straight:
    """Drives along +x at 1 m/s, blind; keeps the scans it saw."""

    def __init__(self):
        self.scans = []

    def reset(self, scenario):
        self.scans = []

    def act(self, obs):
        self.scans.append(np.array(obs.ranges))
        return (1.0, 0.0, 0.0)


GLASS = "  - {type: box, name: pane, x: 3, y: 0, length: 0.05, width: 2, visible_to_lidar: false}"


def test_the_lidar_does_not_see_a_glass_obstacle_that_the_robot_then_hits():
    planner = Straight()
    result = run_scenario(scenario(GLASS), lambda: planner)
    assert result.outcome.value == "collision" and result.collision.obstacle == "pane"
    ahead = int(np.argmin(np.abs(np.asarray(result.trajectory.angles))))
    assert all(scan[ahead] == pytest.approx(8.0) for scan in planner.scans)   # never a return ahead
    # the same pane, visible: the lidar sees it and the safety layer halts the robot before it
    seen = Straight()
    visible = run_scenario(scenario(GLASS.replace(", visible_to_lidar: false", "")), lambda: seen)
    assert visible.outcome.value == "safety-stop" and visible.safety_stop.obstacle == "pane"
    assert seen.scans[0][ahead] == pytest.approx(3.0 - 0.025, abs=1e-4)


def test_glass_round_trips_and_the_default_hashes_as_before():
    sc = scenario(GLASS)
    assert sc.obstacle("pane").visible_to_lidar is False
    assert loads_scenario(dump_scenario(sc)) == sc
    seen = scenario(GLASS.replace(", visible_to_lidar: false", ""))
    assert content_hash(seen) != content_hash(sc)
    assert "visible_to_lidar" not in dump_scenario(seen)
    with pytest.raises(Exception, match=r"faults.yaml:5: obstacles\[0\].visible_to_lidar: expected true or false"):
        scenario(GLASS.replace("false", "maybe"))
