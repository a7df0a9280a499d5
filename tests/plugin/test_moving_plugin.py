"""Moving obstacles through real pytest runs: the same results on 0 and 2 workers, the HTML viewer
moving them, and frozen failures of the search re-running with the same outcome."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from pytest_navscenario.report.results_file import read_results
from pytest_navscenario.scenario.loader import load_scenario

ROOT = Path(__file__).resolve().parents[2]
PLUGIN = ["-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider", "--nav-subject=dwa"]
ONCOMING = """\
version: 1
description: in a narrow corridor a person walks towards the robot and back
mission: {start: {x: 0, y: 0}, goal: {x: 8, y: 0}, timeout: 20}
obstacles:
  - {type: box, name: wall_a, x: 4, y: 0.9, length: 6, width: 0.2}
  - {type: box, name: wall_b, x: 4, y: -0.9, length: 6, width: 0.2}
  - {type: person, name: walker, motion: {path: [[7, 0.1], [1, 0.1]], mode: back-and-forth, start: 1}}
  - {type: box, name: cart, length: 0.8, width: 0.6, motion: {path: [[4, 3], [4, 1.4]], speed: 0.4, start: 2}}
"""


def strip_times(records):
    return [{k: v for k, v in r.items() if k != "wall_time"} for r in records]


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    (pytester.path / "scenarios").mkdir()
    seed = (ROOT / "scenarios" / "person-crossing.yaml").read_text()
    (pytester.path / "scenarios" / "person-crossing.yaml").write_text(seed)
    (pytester.path / "scenarios" / "oncoming.yaml").write_text(ONCOMING)
    return pytester


def test_moving_obstacles_give_the_same_results_on_zero_and_two_workers(project):
    serial = project.runpytest_subprocess(*PLUGIN, "scenarios", "--nav-results=r0.jsonl", "-n", "0",
                                          "-p", "xdist.plugin", "--nav-html=report.html")
    parallel = project.runpytest_subprocess(*PLUGIN, "scenarios", "--nav-results=r2.jsonl", "-n", "2",
                                            "-p", "xdist.plugin")
    r0, r2 = read_results(project.path / "r0.jsonl"), read_results(project.path / "r2.jsonl")
    assert len(r0) == 2 and strip_times(r0) == strip_times(r2)
    crossing = next(r for r in r0 if r["scenario"] == "person-crossing")
    assert crossing["outcome"] == "success"         # the seed passes as written
    oncoming = next(r for r in r0 if r["scenario"] == "oncoming")
    assert oncoming["outcome"] != "success", oncoming["message"]
    # the HTML report's viewer of the failure has the obstacles' offsets, to move them with the slider
    html = (project.path / "report.html").read_text()
    view = html[html.index('"mov":'):]
    assert view.startswith('"mov":[{"i":2,"dx":[') and '{"i":3,"dx":[' in view


def test_frozen_failures_with_a_moving_obstacle_fail_again_the_same_way(project):
    result = project.runpytest_subprocess(*PLUGIN, "--navsearch", "scenarios/person-crossing.yaml",
                                          "--budget", "12", "--navsearch-seed", "11",
                                          "--navsearch-shrink-budget", "4")
    assert result.ret == 0, result.stdout.str()
    frozen = sorted((project.path / "scenarios" / "regressions").rglob("person-crossing-*.yaml"))
    assert frozen, result.stdout.str()
    for path in frozen:
        sc = load_scenario(path)
        assert sc.obstacle("walker").motion is not None     # the frozen file keeps the motion
    again = project.runpytest_subprocess(*PLUGIN, "scenarios/regressions", "--nav-results=again.jsonl")
    again.assert_outcomes(failed=len(frozen))
    outcomes = {Path(r["path"]).name: r["outcome"] for r in read_results(project.path / "again.jsonl")}
    for path in frozen:
        assert outcomes[path.name] == load_scenario(path).provenance["outcome"], path.name
