"""The oracle: outcome precedence and the one-line message a user reads in a failure report."""
import numpy as np
import pytest

from pytest_navscenario.verdict.oracle import classify
from pytest_navscenario.sim.trajectory import Collision, SafetyStop, SubjectFailure, Trajectory
from pytest_navscenario.verdict.result import Outcome
from pytest_navscenario.scenario.model import Mission, Pose, Scenario


def scenario(timeout=30.0, waypoints=()):
    return Scenario(mission=Mission(start=Pose(0, 0, 90), goal=Pose(0, 10, 90), timeout=timeout,
                                    waypoints=tuple(waypoints)))


def trajectory(duration=11.2, end=(0.0, 10.0), waypoint_times=()):
    t = np.linspace(0.0, duration, 5)
    pose = np.column_stack([np.linspace(0, end[0], 5), np.linspace(0, end[1], 5), np.full(5, np.pi / 2)])
    return Trajectory(t=t, pose=pose, velocity=np.zeros((5, 3)), tick_t=t, command=np.zeros((5, 3)),
                      ranges=np.zeros((5, 4), np.float32), angles=np.zeros(4),
                      waypoint_times=tuple(waypoint_times))


HIT = Collision(time=4.3211, obstacle="box_left", x=0.4104, y=4.5249, depth=0.0121)
STOP = SafetyStop(time=3.1, obstacle="wall_east", speed=0.8213)
FAIL = SubjectFailure(message="ValueError: bad\n  second line", tick=12, time=1.2)


@pytest.mark.parametrize("events, expected", [
    (dict(collision=HIT, safety_stop=STOP, subject_failure=FAIL), Outcome.SUBJECT_ERROR),
    (dict(collision=HIT, safety_stop=STOP, subject_failure=None), Outcome.COLLISION),
    (dict(collision=None, safety_stop=STOP, subject_failure=None), Outcome.SAFETY_STOP),
])
def test_precedence_even_when_the_goal_was_reached(events, expected):
    outcome, _ = classify(scenario(), trajectory(), goal_reached=True, **events)
    assert outcome is expected


def test_messages_name_what_where_and_when():
    s, tr = scenario(), trajectory()
    none = dict(collision=None, safety_stop=None, subject_failure=None)
    assert classify(s, tr, goal_reached=False, **{**none, "collision": HIT})[1] == (
        "collision with 'box_left' at t=4.32 s (depth 12 mm) at (0.41, 4.52)")
    assert classify(s, tr, goal_reached=False, **{**none, "safety_stop": STOP})[1] == (
        "safety stop at t=3.10 s: predicted to hit 'wall_east' at 0.82 m/s")
    assert classify(s, tr, goal_reached=False, **{**none, "subject_failure": FAIL})[1] == (
        "planner error at tick 12 (t=1.20 s): ValueError: bad second line")
    assert classify(s, tr, goal_reached=True, **none) == (Outcome.SUCCESS, "success in 11.2 s")


def test_timeout_says_how_far_from_the_goal_and_how_many_waypoints():
    s = scenario(timeout=30.0, waypoints=[Pose(1, 3), Pose(-1, 6)])
    tr = trajectory(duration=30.0, end=(0.0, 7.69), waypoint_times=(3.5,))
    outcome, message = classify(s, tr, collision=None, safety_stop=None, subject_failure=None,
                                goal_reached=False)
    assert outcome is Outcome.TIMEOUT
    assert message == "timeout after 30.0 s, 2.31 m from the goal (1 of 2 waypoints passed)"


def test_goal_reached_too_late_is_a_timeout():
    outcome, message = classify(scenario(timeout=10.0), trajectory(duration=10.5), collision=None,
                                safety_stop=None, subject_failure=None, goal_reached=True)
    assert outcome is Outcome.TIMEOUT
    assert "10.5 s" in message and "10.0 s allowed" in message


def test_reaching_the_goal_exactly_at_the_timeout_succeeds():
    outcome, _ = classify(scenario(timeout=10.0), trajectory(duration=10.0), collision=None,
                          safety_stop=None, subject_failure=None, goal_reached=True)
    assert outcome is Outcome.SUCCESS


def test_long_planner_messages_stay_one_short_line():
    failure = SubjectFailure(message="RuntimeError: " + "x" * 1000 + "\nmore", tick=0, time=0.0)
    _, message = classify(scenario(), trajectory(), collision=None, safety_stop=None,
                          subject_failure=failure, goal_reached=False)
    assert "\n" not in message and len(message) < 400 and message.endswith("...")
