"""Issue 24, the new load errors: a scenario whose shortest way cannot be driven within its timeout at
the robot's top speed, and a moving obstacle whose path crosses a static one, are errors of the
scenario (its file, line and field), never a planner failure; the search discards such candidates
(counted by reason), like a blocked start. Real pytest runs, real searches."""
from __future__ import annotations

from pathlib import Path

import pytest

import pytest_navscenario.plugin.payload  # noqa: F401  (numpy: in-process runs cannot import it afresh)
import pytest_navscenario.verdict.feasibility  # noqa: F401
from pytest_navscenario.scenario.loader import load_scenario, loads_scenario  # noqa: F401
from pytest_navscenario.verdict.feasibility import infeasible
from pytest_navscenario.verdict.movers import mover_through

PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none"]


# scenario texts kept as .txt: as .yaml the project's own test run would collect them as scenarios
DATA = Path(__file__).resolve().parents[1] / "data" / "infeasible"
LONG = (DATA / "long.txt").read_text()                   # 50 m to drive in 30 s at 1.1 m/s
THROUGH_WALL = (DATA / "through_wall.txt").read_text()   # a person walking through a wall


def test_a_route_too_long_for_its_timeout_is_an_error_naming_the_field(pytester: pytest.Pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makefile(".yaml", long=LONG)
    result = pytester.runpytest_subprocess(*PLUGIN, "--nav-subject=dwa")
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines([
        "*ERROR at setup of*long*",
        "*long.yaml:5: mission.timeout: the timeout of 30 s is too short: the shortest way the robot can take "
        "is 49.7 m (to the edge of the goal's tolerance), which takes at least 44.5 s at its top speed of "
        "1.11803 m/s, so every planner would time out; raise mission.timeout (e.g. to 99 s)*"])
    assert "timeout after" not in result.stdout.str()


def test_a_moving_obstacle_through_a_wall_is_an_error_naming_the_field(pytester: pytest.Pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makefile(".yaml", through=THROUGH_WALL)
    result = pytester.runpytest_subprocess(*PLUGIN, "--nav-subject=dwa")
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines([
        "*through.yaml:11: obstacles[[]1].motion.path: moving obstacle 'person' walks through static obstacle "
        "'wall' on its way from (1, 2) to (5, 2): the simulation would move it through*"])


def test_what_is_not_an_error():
    """A timeout that suffices at top speed, a path that only grazes a wall, a periodic mover whose
    crossing comes after the timeout, a mover whose path goes around: all ordinary scenarios."""
    ok = loads_scenario(LONG.replace("timeout: 30", "timeout: 45"), "ok.yaml")
    assert infeasible(ok) is None
    graze = loads_scenario(THROUGH_WALL.replace("[[1, 2], [5, 2]]", "[[1, 3.25], [5, 3.25]]"), "g.yaml")
    assert mover_through(graze) is None            # its edge runs along the wall's end (y = 3)
    late = loads_scenario(THROUGH_WALL.replace("[[1, 2], [5, 2]]", "[[-20, 2], [5, 2]]")
                          .replace("  goal: {x: 6, y: 0}", "  goal: {x: 6, y: 0}\n  timeout: 10"), "l.yaml")
    assert mover_through(late) is None             # 1 m/s from x = -20: the wall is 22 m away, after 10 s
    around = loads_scenario(THROUGH_WALL.replace("[[1, 2], [5, 2]]", "[[1, 2], [1, 3.5], [5, 3.5]]"), "a.yaml")
    assert mover_through(around) is None


def test_constant_velocity_into_a_wall_before_the_timeout():
    text = THROUGH_WALL.replace("    radius: 0.25\n", "    x: 1\n    y: 2\n    radius: 0.25\n").replace(
        "      path: [[1, 2], [5, 2]]\n      speed: 1.0\n", "      velocity: [0.5, 0]\n")
    found = infeasible(loads_scenario(text, "v.yaml"))
    assert found.code == "mover-through" and found.field == "obstacles[1].motion.velocity"
    assert "at constant velocity from (1, 2), walks through static obstacle 'wall' before the timeout" in str(found)
