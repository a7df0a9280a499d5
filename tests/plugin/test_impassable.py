"""Issue 15 item 4: a scenario no planner can pass (walled in; a waypoint or the goal closer to an
obstacle than half the robot's width with all its tolerance) is an error item saying so and why,
never a planner failure that ran to its timeout; a goal equal to the start does not pass silently.
Real pytest runs with the built-in planner; real MuJoCo for the ordinary scenario beside them."""
from __future__ import annotations

import json

import pytest

import pytest_navscenario.plugin.payload  # noqa: F401  (numpy: in-process runs cannot import it afresh)
import pytest_navscenario.verdict.feasibility  # noqa: F401
from pytest_navscenario.scenario.loader import load_scenario  # noqa: F401  (see test_ini_types.py)

PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none"]
BASE = "version: 1\nmission: {{start: {{x: 0, y: 0}}, goal: {{x: {gx}, y: 0}}, timeout: 30{extra}}}\n"
ROOM = "".join(f"  - {{type: box, name: {n}, x: {x}, y: {y}, length: {l}, width: {w}}}\n" for n, x, y, l, w in [
    ("north", 4, 1.2, 2.6, 0.2), ("south", 4, -1.2, 2.6, 0.2), ("east", 5.2, 0, 0.2, 2.6), ("west", 2.8, 0, 0.2, 2.6)])
FILES = {
    "walled_in": BASE.format(gx=4, extra="") + "obstacles:\n" + ROOM,
    "shelf": BASE.format(gx=4, extra=", waypoints: [{x: 2, y: 1.1}], waypoint_tolerance: 0.05")
    + "obstacles:\n  - {type: box, name: shelf, x: 2, y: 1.5, length: 1, width: 0.6}\n",
    "at_start": BASE.format(gx=0.1, extra=""),
    "ordinary": BASE.format(gx=2, extra=""),
}


def test_impassable_scenarios_are_errors_that_say_why(pytester: pytest.Pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    for name, text in FILES.items():
        pytester.makefile(".yaml", **{name: text})
    result = pytester.runpytest_subprocess(*PLUGIN, "--nav-subject=potential-field", "--nav-results=r.jsonl")
    result.assert_outcomes(passed=1, errors=3)
    out = result.stdout.str()
    assert "timeout after" not in out and "subject-error" not in out   # nothing blamed on the planner
    assert "_callers.py" not in out and "_ _ _ _" not in out   # the message, not a traceback through pytest
    result.stdout.fnmatch_lines([
        "*ERROR at setup of*at_start*",
        "*at_start.yaml: the start (0, 0) already satisfies the goal (0.1, 0)*tests nothing*",
        "*ERROR at setup of*shelf*",
        "*no planner can pass this scenario*from the start to waypoint 0 (2, 1.1): waypoint 0 (2, 1.1) "
        "lies within 0.10 m of obstacle 'shelf'*",
        "*ERROR at setup of*walled_in*",
        "*no planner can pass this scenario*(0.5 m wide) from the start to the goal (4, 0): obstacles "
        "close every way between them*",
    ])
    assert "failed" not in out.splitlines()[-1]


def test_an_impassable_scenario_marked_xfail_is_an_expected_failure(pytester: pytest.Pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makefile(".yaml", walled_in=FILES["walled_in"] + "marks: [{xfail: {reason: a closed room}}]\n")
    result = pytester.runpytest(*PLUGIN, "-rx")
    result.assert_outcomes(xfailed=1)


def test_impassable_scenarios_on_local_workers_are_the_same_setup_errors(pytester: pytest.Pytester, monkeypatch):
    """--nav-workers 2: the workers check feasibility before simulating (issue 14: this process
    shares the cores with them) and the items report exactly what a serial run reports."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    for name, text in FILES.items():
        pytester.makefile(".yaml", **{name: text})
    runs = {}
    for label, extra in (("serial", []), ("workers", ["--nav-workers=2"])):
        result = pytester.runpytest_subprocess(*PLUGIN, "--nav-subject=potential-field", "-p", "no:cacheprovider",
                                               f"--nav-results={label}.jsonl", *extra)
        result.assert_outcomes(passed=1, errors=3)
        runs[label] = [line for line in result.outlines
                       if line.startswith(("ERROR at setup", "E   ", "_")) or "no planner can pass" in line
                       or "already satisfies" in line]
    assert "episodes run on 2 local worker process" in result.stdout.str()
    assert runs["workers"] == runs["serial"] and len(runs["serial"]) >= 6
    recs = {label: [{k: v for k, v in json.loads(line).items() if k != "wall_time"}
                    for line in (pytester.path / f"{label}.jsonl").read_text().splitlines()]
            for label in runs}
    assert recs["workers"] == recs["serial"] and [r["scenario"] for r in recs["serial"]] == ["ordinary"]
