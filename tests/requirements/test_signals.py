"""Issue 34, the signals: each kind a formula may name, computed from a real episode and checked
against what it means (built-ins against the trajectory, a region's signed distance, the speed
toward an obstacle, a user's function found beside the scenario like a planner)."""
from __future__ import annotations

import math
import textwrap

import numpy as np
import pytest

from pytest_navscenario import ScenarioError, load_scenario, loads_scenario
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.requirements import BUILTIN_SIGNALS
from pytest_navscenario.verdict.signals import episode_signals

OPEN = """\
version: 1
robot: {drive: omni}
mission: {start: {x: 0, y: 0}, goal: {x: 6, y: 0}, waypoints: [{x: 3, y: 0}], timeout: 30}
obstacles:
  - {type: cylinder, name: post, x: 3, y: 1.5, radius: 0.2}
"""


@pytest.fixture(scope="module")
def episode():
    text = OPEN + textwrap.dedent("""\
        signals:
          - {name: in_ring, inside: {x: 3, y: 0, radius: 1}}
          - {name: in_square, inside: {points: [[2, -1], [4, -1], [4, 1], [2, 1]]}}
          - {name: toward_post, speed_toward: post}
          - {name: d_post, distance_to: "po*"}
        """)
    scenario = loads_scenario(text)
    result = run_scenario(scenario, "dwa")
    names = [*BUILTIN_SIGNALS, "d_waypoint1", "in_ring", "in_square", "toward_post", "d_post"]
    return scenario, result, episode_signals(scenario, result.trajectory, names)


def test_every_built_in_is_one_value_per_control_tick(episode):
    scenario, result, values = episode
    n = int(math.floor(result.trajectory.duration * 10 + 1e-6)) + 1
    assert all(len(v) == n for v in values.values())
    assert np.allclose(values["time"], np.arange(n) * 0.1)
    assert values["speed"].max() <= scenario.robot.limits.max_speed + 0.05
    assert np.allclose(values["d_goal"], np.hypot(values["x"] - 6, values["y"]))
    assert np.allclose(values["d_waypoint1"], np.hypot(values["x"] - 3, values["y"]))
    assert not values["pitch"].any() and not values["roll"].any() and not values["height"].any()
    assert values["lidar_min"].min() > 0 and values["lidar_min"].max() <= scenario.robot.lidar.range_max
    assert values["clearance"].min() == pytest.approx(values["d_post"].min())


def test_regions_are_signed_distances_positive_inside(episode):
    _, _, v = episode
    ring = 1 - np.hypot(v["x"] - 3, v["y"])
    assert np.allclose(v["in_ring"], ring)
    inside = (np.abs(v["x"] - 3) < 1) & (np.abs(v["y"]) < 1)
    assert np.all((v["in_square"] > 0) == inside)
    edge = np.minimum(1 - np.abs(v["x"] - 3), 1 - np.abs(v["y"]))
    assert np.allclose(v["in_square"][inside], edge[inside])


def test_speed_toward_is_the_robots_velocity_along_the_line_to_the_obstacle(episode):
    _, _, v = episode
    approaching = v["x"] < 2.5
    assert np.all(v["toward_post"][approaching & (v["speed"] > 0.5)] > 0)
    assert np.all(v["toward_post"][(v["x"] > 3.5) & (v["speed"] > 0.5)] < 0)
    assert np.all(np.abs(v["toward_post"]) <= v["speed"] + 1e-9)


def test_a_users_function_beside_the_scenario_is_a_signal(tmp_path):
    (tmp_path / "mysignals_t34.py").write_text(textwrap.dedent("""\
        import numpy as np
        def lateral(trajectory, scenario, times):
            i = np.searchsorted(trajectory.t, times - 1e-9).clip(0, len(trajectory.t) - 1)
            return np.abs(trajectory.pose[i, 1])
        def wrong(trajectory, scenario, times):
            return [1.0, 2.0]
        """))
    path = tmp_path / "s.yaml"
    path.write_text(OPEN + 'signals:\n  - {name: lateral, function: "mysignals_t34:lateral"}\n'
                    'requirements:\n  - {name: stay-on-line, spec: "always (lateral <= 0.01)"}\n')
    result = run_scenario(load_scenario(path), "dwa")
    (req,) = result.requirements
    assert req.violated and "stay-on-line" in result.message   # dwa swerves around the post
    path.write_text(path.read_text().replace("mysignals_t34:lateral", "mysignals_t34:wrong"))
    with pytest.raises(ScenarioError, match="returned shape"):
        run_scenario(load_scenario(path), "dwa")
