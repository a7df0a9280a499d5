"""A terrain face the body cannot cross is something to keep clear of, as an obstacle is (issue
36.3): the minimum clearance, the requirements' ``clearance`` signal and a search's culprit count
it; a face the body climbs, and a body that declares no limits, do not add one. Real MuJoCo
episodes of the built-in wheeled body driven straight at stairs."""
import dataclasses
import math
import sys
from pathlib import Path

import pytest

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.bodies import LeggedBody, WheeledBody
from pytest_navscenario.scenario.model import BoxObstacle, Footprint, Mission, Pose, Robot, Safety, Scenario
from pytest_navscenario.scenario.terrain import Platform, Steps
from pytest_navscenario.sim.trajectory import SafetyStop
from pytest_navscenario.verdict.metrics import min_clearance

sys.path.insert(0, str(Path(__file__).parents[1] / "search"))
from straight_planner import Straight  # noqa: E402

FP = Footprint(shape="box", length=0.9, width=0.5)
STAIRS = Steps("stairs", 5.0, 0.0, count=5, rise=0.17, run=0.3, width=2.0)   # first riser at x = 4.25


def scene(terrain, body=WheeledBody(clearance=0.1), goal=(3.74, 0.0), obstacles=(), safety=True):
    return Scenario(mission=Mission(start=Pose(0, 0, 0), goal=Pose(*goal, 0.0), timeout=20),
                    terrain=tuple(terrain), obstacles=tuple(obstacles),
                    robot=Robot(footprint=FP, drive="diff", body=body, safety=Safety(enabled=safety)))


def test_stopping_short_of_a_stair_face_it_cannot_climb_is_its_minimum_clearance():
    res = run_scenario(scene([STAIRS]), Straight(), seed=0)
    assert res.outcome.value == "success"
    front = float(res.trajectory.pose[-1, 0]) + FP.length / 2
    m = res.metrics
    assert m.min_clearance == pytest.approx(4.25 - front, abs=2e-3)   # to the riser itself
    # it stops where the goal is first within its tolerance (0.3 m, a tick of 0.1 m at 1 m/s
    # at most beyond): its front at most 0.4 m short of a goal 6 cm from the riser
    assert 0.0 < m.min_clearance < 4.25 - (3.74 + FP.length / 2) + 0.4
    assert m.min_clearance_obstacle == "steps 'stairs' (0.17 m step)"
    assert m.min_clearance_time == pytest.approx(float(res.trajectory.t[-1]), abs=0.05)


def test_an_obstacle_nearer_than_the_face_is_still_the_one_named():
    crate = BoxObstacle("crate", 3.0, 0.6, length=0.4, width=0.4, height=0.5)
    res = run_scenario(scene([STAIRS], obstacles=[crate]), Straight(), seed=0)
    assert res.metrics.min_clearance_obstacle == "crate"
    assert res.metrics.min_clearance == pytest.approx(0.6 - 0.2 - FP.width / 2, abs=1e-6)


def test_a_face_the_body_climbs_or_a_body_without_limits_adds_no_clearance():
    step = Platform("step", 5.0, 0.0, length=1.5, width=2.0, height=0.17)
    assert min_clearance(scene([step]), *_poses(3.3))[:2] == pytest.approx((5.0 - 0.75 - 3.3 - 0.45, "platform 'step' (0.17 m step)"))
    legged = scene([step], body=LeggedBody(max_step=0.2))   # climbs it
    assert min_clearance(legged, *_poses(3.3))[:2] == (math.inf, "")
    low = scene([Platform("sill", 4.5, 0.0, length=0.5, width=2.0, height=0.02)])   # a 2 cm sill it crosses
    assert min_clearance(low, *_poses(3.3))[:2] == (math.inf, "")


def test_driving_into_a_platform_face_is_zero_clearance_to_that_face():
    res = run_scenario(scene([Platform("wall", 4.0, 0.0, length=1.0, width=3.0, height=0.6)], goal=(12.0, 0.0),
                             safety=False), Straight(), seed=0)    # on, the safety layer halts before it
    assert res.outcome.value == "collision"
    assert res.metrics.min_clearance == pytest.approx(0.0, abs=5e-3)
    assert res.metrics.min_clearance_obstacle.startswith("platform 'wall'")


def test_the_requirement_signal_clearance_sees_the_face_too():
    from pytest_navscenario.verdict.signals import BUILTINS, samples

    res = run_scenario(scene([STAIRS]), Straight(), seed=0)
    clearance = BUILTINS["clearance"](samples(res.scenario, res.trajectory))
    assert float(clearance.min()) == pytest.approx(res.metrics.min_clearance, abs=2e-3)
    assert clearance[0] == pytest.approx(4.25 - FP.length / 2, abs=2e-3)   # at the start, 3.8 m away


def _poses(x: float):
    import numpy as np
    return np.array([0.0]), np.array([[x, 0.0, 0.0]])


def test_the_clearance_to_the_obstacle_a_stop_was_for_is_to_that_obstacle_alone():
    """A safety stop's clearance to its obstacle is not the nearer terrain face (the dock's edge
    under the robot's corner): the search summary said "clearance to 'pallet_a' 0.000 m"."""
    from pytest_navscenario.verdict.metrics import culprit_clearance

    crate = BoxObstacle("crate", 3.0, 0.8, length=0.4, width=0.4, height=0.5)
    res = run_scenario(scene([STAIRS], obstacles=[crate]), Straight(), seed=0)
    stopped = dataclasses.replace(res, safety_stop=SafetyStop(1.0, "crate", 1.0))
    name, dist, _ = culprit_clearance(stopped) or ("", math.nan, 0)
    assert name == "crate" and dist == pytest.approx(0.8 - 0.2 - FP.width / 2, abs=1e-6)
