"""run_scenario: planner resolution, seeds, and the outcome/metrics it assembles (real MuJoCo)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from pytest_navscenario import run_scenario
from pytest_navscenario.core.errors import SubjectLoadError
from pytest_navscenario.verdict.result import Outcome
from pytest_navscenario.harness.runner import effective_seed
from pytest_navscenario.subjects.loading import make_planner
from pytest_navscenario.scenario.model import BoxObstacle, Lidar, Mission, Pose, Robot, Safety, Scenario, Simulation


class Straight:
    """Drives at the goal in the robot frame (omni), whatever is in the way."""
    name = "straight-line"
    version = "1.2"

    def reset(self, scenario):
        self.resets = getattr(self, "resets", 0) + 1

    def act(self, obs):
        x, y, yaw = obs.pose
        tx, ty = obs.target
        c, s = math.cos(yaw), math.sin(yaw)
        return (2 * (c * (tx - x) + s * (ty - y)), 2 * (-s * (tx - x) + c * (ty - y)), 0.0)


def make_straight():
    return Straight()


def scenario(obstacles=(), safety=True, seed=0, lidar=Lidar()):
    return Scenario(name="r", mission=Mission(start=Pose(0, 0, 90), goal=Pose(0, 10, 90), timeout=15),
                    obstacles=tuple(obstacles), simulation=Simulation(seed=seed),
                    robot=Robot(safety=Safety(enabled=safety), lidar=lidar))


WALL = BoxObstacle("wall", 0.0, 5.0, 2.0, 1.0)


def test_every_outcome_through_run_scenario():
    ok = run_scenario(scenario([BoxObstacle("side", 3, 5, 1, 1)]), Straight)
    assert ok.outcome is Outcome.SUCCESS and ok.passed and ok.message.startswith("success")
    assert ok.metrics.min_clearance_obstacle == "side"
    assert ok.metrics.min_clearance == pytest.approx(3 - 0.5 - 0.25, abs=0.02)
    assert ok.metrics.duration == pytest.approx(ok.trajectory.duration)
    assert set(ok.timings) >= {"physics", "rays", "planner", "harness", "metrics"}
    assert ok.wall_time > 0 and ok.subject == "straight-line" and ok.subject_version == "1.2"

    hit = run_scenario(scenario([WALL], safety=False), Straight)
    assert hit.outcome is Outcome.COLLISION and hit.collision.obstacle == "wall"
    assert "wall" in hit.message and hit.metrics.min_clearance == 0.0

    stop = run_scenario(scenario([WALL]), Straight)
    assert stop.outcome is Outcome.SAFETY_STOP and stop.safety_stop.obstacle == "wall"

    class Frozen(Straight):
        def act(self, obs):
            return (0.0, 0.0, 0.0)

    late = run_scenario(scenario(), Frozen)
    assert late.outcome is Outcome.TIMEOUT and late.trajectory.duration == pytest.approx(15.0)

    class Broken(Straight):
        def act(self, obs):
            return [0.0] if obs.tick == 2 else (0.5, 0.0, 0.0)

    err = run_scenario(scenario(), Broken)
    assert err.outcome is Outcome.SUBJECT_ERROR and err.subject_failure.tick == 2
    assert "tick 2" in err.message and "length 1" in err.message


def test_planner_given_as_spec_class_factory_or_object():
    sc = scenario()
    builtin = run_scenario(sc, "dwa")
    assert builtin.outcome is Outcome.SUCCESS
    default = run_scenario(sc)
    assert default.trajectory.pose.tobytes() == builtin.trajectory.pose.tobytes()
    by_spec = run_scenario(sc, f"{__name__}:Straight")
    by_factory = run_scenario(sc, make_straight)
    instance = Straight()
    by_object = run_scenario(sc, instance)
    assert instance.resets == 1
    for res in (by_spec, by_factory, by_object):
        assert res.trajectory.pose.tobytes() == run_scenario(sc, Straight).trajectory.pose.tobytes()


def test_bad_planners_are_refused_in_plain_words():
    with pytest.raises(SubjectLoadError, match="no act\\(\\) method"):
        make_planner(lambda: object())
    with pytest.raises(SubjectLoadError, match="raised ValueError: no licence"):
        make_planner(lambda: (_ for _ in ()).throw(ValueError("no licence")))
    with pytest.raises(SubjectLoadError, match="package.module:Attribute"):
        make_planner(42)
    with pytest.raises(SubjectLoadError, match="cannot import module"):
        run_scenario(scenario(), "no_such_module_xyz:Planner")


def test_effective_seed():
    assert effective_seed(17, None) == 17 and effective_seed(17, 0) == 17
    mixed = effective_seed(17, 5)
    assert mixed == effective_seed(17, 5) != 17
    assert len({effective_seed(17, b) for b in range(1, 50)}) == 49
    assert effective_seed(18, 5) != mixed


def test_the_base_seed_changes_the_noise_only_when_given():
    sc = scenario([BoxObstacle("side", 2, 5, 1, 1)], seed=4, lidar=Lidar(noise_sigma=0.05))
    own = run_scenario(sc, Straight)
    assert own.seed == 4
    assert run_scenario(sc, Straight, seed=0).trajectory.ranges.tobytes() == own.trajectory.ranges.tobytes()
    other = run_scenario(sc, Straight, seed=99)
    assert other.seed == effective_seed(4, 99)
    assert not np.array_equal(other.trajectory.ranges, own.trajectory.ranges)
