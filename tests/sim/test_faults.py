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


# ---------------------------------------------------------------- localisation drift and latency

class GoTo:
    """Trusts its odometry: drives from the pose it is told straight at the goal, 1 m/s, and stops
    when it believes it is there."""

    def reset(self, scenario):
        self.goal = (scenario.mission.goal.x, scenario.mission.goal.y)

    def act(self, obs):
        x, y, yaw = obs.pose
        dx, dy = self.goal[0] - x, self.goal[1] - y
        d = math.hypot(dx, dy)
        if d < 0.05:
            return (0.0, 0.0, 0.0)
        v = min(1.0, d)
        c, s = math.cos(yaw), math.sin(yaw)
        return (v * (c * dx + s * dy) / d, v * (-s * dx + c * dy) / d, 0.0)


DRIFT = "{localisation: {drift_per_metre: 0.3, yaw_drift_per_metre: 3.0}}"


def test_drift_makes_a_planner_that_trusts_odometry_fail_where_it_succeeds_without():
    clean = run_scenario(scenario("", extra=""), GoTo)
    assert clean.outcome.value == "success"
    drifted = run_scenario(scenario("", robot=DRIFT), GoTo)
    assert drifted.outcome.value == "timeout", drifted.message
    believed = drifted.trajectory.believed
    truth = drifted.trajectory.pose
    # it believes it reached the goal; in truth it stands elsewhere, farther than the tolerance
    assert math.hypot(believed[-1, 0] - 6.0, believed[-1, 1]) < 0.1
    assert math.hypot(truth[-1, 0] - 6.0, truth[-1, 1]) > 0.3
    # the verdict uses the truth: metrics from the true pose
    assert drifted.metrics.goal_position_error == pytest.approx(math.hypot(truth[-1, 0] - 6.0, truth[-1, 1]))
    assert clean.trajectory.believed is None


def test_drift_is_seeded_per_episode_and_grows_with_distance():
    sc = scenario("", robot=DRIFT)
    a, b, other = (simulate(sc, GoTo(), seed=s) for s in (7, 7, 8))
    assert a.trajectory.believed.tobytes() == b.trajectory.believed.tobytes()
    assert a.trajectory.pose.tobytes() == b.trajectory.pose.tobytes()
    assert a.trajectory.believed.tobytes() != other.trajectory.believed.tobytes()
    # standing still, drift per metre adds nothing: the believed pose is the true one
    still = simulate(scenario("", robot="{localisation: {drift_per_metre: 0.5}}"),
                     type("Still", (), {"reset": lambda s, sc: None, "act": lambda s, o: (0, 0, 0)})(),
                     seed=1, max_ticks=20)
    assert np.allclose(still.trajectory.believed, 0.0)


def test_latency_delays_observations_and_commands():
    seen = []

    class Record(GoTo):
        def act(self, obs):
            seen.append((obs.tick, obs.time, float(obs.pose[0])))
            return super().act(obs)

    lag = simulate(scenario("", robot="{latency: {observation: 0.3, command: 0.2}}"), Record(), seed=0,
                   max_ticks=40)
    ticks = [tick for tick, _, _ in seen]
    assert ticks[:6] == [0, 0, 0, 0, 1, 2]            # three ticks (0.3 s) old
    command = lag.trajectory.command
    assert np.all(command[:2] == 0.0) and command[2, 0] > 0.0   # the first answer acts 0.2 s later
    # the planner believed it was at x = 0 for longer than it was
    truth_x = np.interp([t for _, t, _ in seen], lag.trajectory.t, lag.trajectory.pose[:, 0])
    assert [x for _, _, x in seen] == pytest.approx(truth_x.tolist(), abs=1e-9)


def test_a_delay_that_is_not_a_whole_number_of_ticks_is_an_error():
    with pytest.raises(Exception, match=r"faults.yaml.*robot.latency.command: a delay of 0.15 s is not a whole "
                                        r"number of control periods \(0.1 s at 10 Hz\).*e.g. command: 0.2"):
        scenario("", robot="{latency: {command: 0.15}}")


def test_the_plot_shows_the_believed_pose_beside_the_true_one(tmp_path):
    pytest.importorskip("matplotlib")
    from pytest_navscenario.report.plots import trajectory_figure

    result = run_scenario(scenario("", robot=DRIFT), GoTo)
    fig = trajectory_figure(result)
    labels = [" ".join(t.get_text().split()) for leg in fig.legends for t in leg.get_texts()]  # wrapped entries
    assert "believed pose (localisation drift)" in labels
    assert any(t.get_text().startswith("believed: ") and t.get_text().endswith(" m off") for t in fig.axes[0].texts)
    fig.savefig(tmp_path / "drift.png")


# ---------------------------------------------------------------- the datasheet lidar noise model

def _ranges(lidar: str, seed: int = 0, ticks: int = 200):
    """Ranges straight ahead (a wall at 2 m) and straight behind (a wall at 6 m) of a standing robot."""
    walls = ("  - {type: box, name: near, x: 2.5, y: 0, length: 1, width: 30}\n"
             "  - {type: box, name: far, x: -6.5, y: 0, length: 1, width: 30}")
    sc = scenario(walls, robot="{lidar: " + lidar + "}")
    sc = sc.__class__(**{**sc.__dict__, "mission": sc.mission.__class__(
        **{**sc.mission.__dict__, "goal": sc.mission.goal.__class__(0.0, 1.0)})})
    res = simulate(sc, type("Still", (), {"reset": lambda s, sc: None, "act": lambda s, o: (0, 0, 0)})(),
                   seed=seed, max_ticks=ticks)
    angles = np.asarray(res.trajectory.angles)
    ahead, behind = int(np.argmin(np.abs(angles))), int(np.argmin(np.abs(np.abs(angles) - math.pi)))
    return res.trajectory.ranges[:, ahead].astype(float), res.trajectory.ranges[:, behind].astype(float)


def test_range_proportional_noise_grows_with_range():
    near, far = _ranges("{beams: 72, noise_sigma: 0.01, noise_per_metre: 0.01}")
    assert near.mean() == pytest.approx(2.0, abs=0.01) and far.mean() == pytest.approx(6.0, abs=0.02)
    assert near.std() == pytest.approx(0.01 + 0.01 * 2.0, rel=0.2)
    assert far.std() == pytest.approx(0.01 + 0.01 * 6.0, rel=0.2)


def test_dropout_grows_with_range_and_spurious_returns_fall_short():
    near, far = _ranges("{beams: 72, dropout: 0.0, dropout_at_max: 0.8}")
    assert (near == 8.0).mean() == pytest.approx(0.8 * 2 / 8, abs=0.08)
    assert (far == 8.0).mean() == pytest.approx(0.8 * 6 / 8, abs=0.1)
    near, far = _ranges("{beams: 72, spurious: 0.3}")
    for ranges, true in ((near, 2.0), (far, 6.0)):
        short = ranges < true - 1e-3
        assert short.mean() == pytest.approx(0.3, abs=0.1) and (ranges[short] >= 0.05).all()
        assert np.allclose(ranges[~short], true, atol=1e-4)


def test_the_noise_is_seeded_per_episode():
    a, b, c = (_ranges("{noise_per_metre: 0.02, spurious: 0.1, dropout_at_max: 0.3}", seed=s, ticks=30)
               for s in (4, 4, 5))
    assert a[0].tobytes() == b[0].tobytes() and a[0].tobytes() != c[0].tobytes()


def test_the_search_opts_into_faults_and_frozen_drift_failures_fail_again(tmp_path):
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search.engine import run_search
    from pytest_navscenario.search.freeze import freeze_failures
    from pytest_navscenario.search.space import SearchSpace

    seed_file = tmp_path / "drifty.yaml"
    seed_file.write_text("version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 6, y: 0}, timeout: 15}\n"
                         "search: {drift_per_metre: [0, 0.4], lidar_spurious: [0, 0.2], frozen: [start, goal], "
                         "insert: 0}\n")
    seed = load_scenario(seed_file)
    space = SearchSpace(seed)
    assert [p.name for p in space.params] == ["robot.lidar_spurious", "robot.drift_per_metre"]
    report = run_search(seed, GoTo, budget=10, seed_value=2, shrink_budget=4, space=space)
    assert report.failures and all(f.shrunk.outcome == "timeout" for f in report.failures)
    for frozen in freeze_failures(report, space, tmp_path / "regressions"):
        again = load_scenario(frozen.path)
        assert again.robot.localisation.drift_per_metre > 0
        assert run_scenario(again, GoTo).outcome.value == frozen.outcome
