"""check_planner: the built-ins pass; each kind of broken planner gets its own plain message."""
from __future__ import annotations

import math
import random
import time

import numpy as np
import pytest

from pytest_navscenario import check_planner
from pytest_navscenario.harness.conformance import PlannerCheck
from pytest_navscenario.core.errors import SubjectLoadError
from pytest_navscenario.subjects.planners import DynamicWindowPlanner


class Base:
    name = "test"
    version = "0"

    def reset(self, scenario):
        pass


class ReturnsNone(Base):
    def act(self, obs):
        return None


class ReturnsString(Base):
    def act(self, obs):
        return "forward"


class ReturnsTwo(Base):
    def act(self, obs):
        return [0.5, 0.0]


class ReturnsWrongShape(Base):
    def act(self, obs):
        return np.zeros((3, 1))


class ReturnsNaN(Base):
    def act(self, obs):
        return (math.nan, 0.0, 0.0)


class ReturnsInf(Base):
    def act(self, obs):
        return (0.5, 0.0, math.inf)


class Raises(Base):
    def act(self, obs):
        return {}["missing key"]


class ResetRaises(Base):
    def reset(self, scenario):
        raise ValueError("no map server")

    def act(self, obs):
        return (0.0, 0.0, 0.0)


class NoAct(Base):
    pass


class NoReset:
    def act(self, obs):
        return (0.0, 0.0, 0.0)


class ResetWithoutScenario(Base):
    def reset(self):
        pass

    def act(self, obs):
        return (0.0, 0.0, 0.0)


class WritesIntoObservation(Base):
    def act(self, obs):
        obs.ranges[obs.ranges > 5.0] = 5.0      # "clip the far returns", in place
        return (0.3, 0.0, 0.0)


class Random(Base):
    def act(self, obs):
        return (random.random(), 0.0, 0.0)


class Fast(Base):
    def act(self, obs):
        return (3.0, 2.0, 0.0)


class Degrees(Base):
    def act(self, obs):
        return (0.2, 0.0, 45.0)        # meant 45 deg/s


class Slow(Base):
    def act(self, obs):
        time.sleep(0.06)
        return (0.2, 0.0, 0.0)


class Anonymous:
    def reset(self, scenario):
        pass

    def act(self, obs):
        return (0.2, 0.0, 0.0)


@pytest.mark.parametrize("spec", ["dwa", "potential-field"])
def test_builtin_planners_pass(spec):
    check = check_planner(spec)
    assert check.ok, str(check)
    assert check.problems == [] and check.ticks == 20
    assert not any("name" in w or "limit" in w for w in check.warnings), check.warnings


PROBLEMS = [
    (ReturnsNone, "returned NoneType None"),
    (ReturnsString, "returned str 'forward'"),
    (ReturnsTwo, "list of length 2"),
    (ReturnsWrongShape, "shape (3, 1), expected shape (3,)"),
    (ReturnsNaN, "non-finite command (vx=nan"),
    (ReturnsInf, "non-finite command"),
    (Raises, "planner.act raised KeyError: 'missing key'"),
    (ResetRaises, "planner.reset raised ValueError: no map server"),
    (NoAct, "has no act() method; add `def act(self, obs):`"),
    (NoReset, "has no reset() method"),
    (ResetWithoutScenario, "must be `def reset(self, scenario):`"),
    (WritesIntoObservation, "wrote into the observation's arrays: obs.ranges (tick 0)"),
    (Random, "nondeterministic: two fresh instances given the same observations"),
]


@pytest.mark.parametrize("planner, message", PROBLEMS, ids=[p.__name__ for p, _ in PROBLEMS])
def test_each_protocol_mistake_is_a_problem_in_plain_words(planner, message):
    check = check_planner(planner, ticks=3)
    assert not check.ok
    assert any(message in p for p in check.problems), check.problems
    assert "FAILED" in str(check) and message in str(check)
    with pytest.raises(SubjectLoadError, match="problem: "):
        check.raise_if_failed()


def test_act_errors_name_the_tick_and_the_planners_own_line():
    check = check_planner(Raises, ticks=3)
    assert "at tick 0 (t=0.00 s)" in check.problems[0]
    assert "test_conformance.py" in check.problems[0] and "in act" in check.problems[0]


WARNINGS = [
    (Fast, "vx up to 3 m/s exceeds robot.limits.max_speed 1 m/s"),
    (Degrees, "did you send degrees?"),
    (Slow, "act() is slow: 2 of 2 ticks after the first took more than 50 ms"),
    (Anonymous, "no `name` attribute"),
]


@pytest.mark.parametrize("planner, message", WARNINGS, ids=[p.__name__ for p, _ in WARNINGS])
def test_questionable_but_legal_behaviour_is_a_warning(planner, message):
    check = check_planner(planner, ticks=3)
    assert check.ok, str(check)
    assert any(message in w for w in check.warnings), check.warnings
    assert check.raise_if_failed() is check


def test_accepts_instances_factories_and_specs_and_reports_what_it_checked():
    by_instance = check_planner(DynamicWindowPlanner(horizon=1.0), ticks=5)
    by_factory = check_planner(lambda: DynamicWindowPlanner(horizon=1.0), ticks=5)
    assert by_instance.ok and by_factory.ok
    assert by_instance.subject == "DynamicWindowPlanner"
    assert by_instance.ticks == 5 and 0 < by_instance.median_tick_time <= by_instance.max_tick_time
    text = str(check_planner("dwa", ticks=2))
    assert text.startswith("check_planner(dwa): OK after 2 ticks (act: median")


def test_a_factory_that_raises_and_an_unloadable_spec():
    def factory():
        raise RuntimeError("licence server down")

    check = check_planner(factory)
    assert check.problems == ["calling test_a_factory_that_raises_and_an_unloadable_spec.<locals>"
                              ".factory() to make a planner raised RuntimeError: licence server "
                              "down (a subject must be a class or a zero-argument factory)"]
    with pytest.raises(SubjectLoadError, match="cannot import module 'no_such_pkg.planner'"):
        check_planner("no_such_pkg.planner:Planner")
    with pytest.raises(SubjectLoadError, match="got int"):
        check_planner(42)


def test_planner_check_str_lists_problems_and_warnings():
    check = PlannerCheck("x", problems=["p1"], warnings=["w1"], ticks=1, max_tick_time=0.002,
                         median_tick_time=0.001)
    assert str(check) == ("check_planner(x): FAILED after 1 tick (act: median 1.00 ms, max 2.00 ms)\n"
                          "  problem: p1\n  warning: w1")


class Hangs(Base):
    def act(self, obs):
        time.sleep(5.0)
        return (0.0, 0.0, 0.0)


def test_a_hung_tick_is_stopped_and_reported_with_the_planners_line():
    t0 = time.perf_counter()
    check = check_planner(Hangs, ticks=3, tick_limit=0.2)
    assert time.perf_counter() - t0 < 2.0
    assert not check.ok
    assert "did not answer within the per-tick limit of 0.2 s" in check.problems[0]
    assert "test_conformance.py" in check.problems[0] and "in act" in check.problems[0]
