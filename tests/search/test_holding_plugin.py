"""Failures that hold, from pytest (issue 29): ``--nav-sensor-model realistic`` searches a
noise-free seed under lidar noise, ``--navsearch-hold`` sets the threshold, the summary and the
HTML report give each failure's probability and interval, the frozen file records it, and
``pytest <frozen files> --nav-repeat N`` says which frozen failures no longer hold."""
from __future__ import annotations

import re
from pathlib import Path

import mujoco
import pytest

from test_search import SEED_YAML

import pytest_navscenario.dispatch.local  # noqa: E402,F401  (before pytester snapshots sys.modules)
from pytest_navscenario.scenario.loader import load_scenario

PLANNERS = (Path(__file__).parent / "straight_planner.py").read_text()


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(straight_planner=PLANNERS)
    pytester.syspathinsert()
    (pytester.path / "scenarios").mkdir()
    seed = SEED_YAML.replace("name: crate\n", "").replace("x: 1.2,", "x: 0.3,").replace("[-1.5, 0.5]", "[-0.1, 0.1]")
    (pytester.path / "scenarios" / "crate.yaml").write_text(seed)     # no noise: the model comes from the option
    pytester.makeini("[pytest]\nnav_scenario_paths = scenarios\n")
    return pytester


def run(pytester: pytest.Pytester, *args: str) -> pytest.RunResult:
    return pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider", *args)


def test_a_search_under_the_realistic_sensor_model_freezes_failures_that_hold(project: pytest.Pytester):
    result = run(project, "--nav-subject=straight_planner:Picky", "--navsearch", "crate", "--budget", "12",
                 "--navsearch-shrink-budget", "0", "--nav-sensor-model", "realistic", "--nav-html", "search.html")
    out = result.stdout.str()
    assert result.ret == 0, out
    assert "failures that hold (fail with probability >= 0.9 under lidar noise, lidar dropout, decided by a " \
           "sequential test): 1; 4 confirmation run(s), 4.0 per failure that holds" in out, out
    assert re.search(r"new  scenarios/regressions/crate/crate-\w+\.yaml  subject-error, clearance [\d.]+ m, "
                     r"fails in 4/4 runs \(95 % 0\.40-1\.00\)", out), out
    assert "12/12 sims" in out and "(4 of them confirming)" in out
    (frozen,) = (project.path / "scenarios" / "regressions" / "crate").glob("crate-*.yaml")
    scenario = load_scenario(frozen)
    assert (scenario.robot.lidar.noise_sigma, scenario.robot.lidar.dropout) == (0.02, 0.01)   # the model, written
    assert scenario.provenance["failure_probability"] == 1.0
    assert scenario.provenance["mujoco_version"] == mujoco.__version__          # the release that found it
    assert "crate.yaml" not in {p.name for p in (project.path / "scenarios").glob("*.yaml")} or \
        "noise_sigma" not in (project.path / "scenarios" / "crate.yaml").read_text()        # the seed unchanged
    html = (project.path / "search.html").read_text()
    assert "<th>fails in</th>" in html and "100%" in html and "[40&ndash;100]" in html

    held = run(project, "scenarios/regressions", "--nav-subject=straight_planner:Picky", "--nav-repeat", "5")
    text = held.stdout.str()
    assert "1 of 1 frozen failure(s) still hold:" in text and "fails in 5/5 runs" in text, text
    assert "the search measured 1.00 (0.40-1.00) over 4 run(s): holds" in text
    # found under another MuJoCo release: a failure that no longer holds says so
    frozen.write_text(re.sub(r"mujoco_version: .*", "mujoco_version: 3.9.0", frozen.read_text()))
    later = run(project, "scenarios/regressions", "--nav-subject=straight_planner:Careful", "--nav-repeat", "5")
    text = later.stdout.str()
    assert "0 of 1 frozen failure(s) still hold; 1 no longer hold" in text, text
    assert f"it was recorded under MuJoCo 3.9.0, this run simulates with MuJoCo {mujoco.__version__}" in text, text
    assert re.search(r"fails in [0-3]/5 runs .*: (NO LONGER HOLDS \(below the threshold 0\.9\)|FIXED)", text), text


@pytest.mark.parametrize("args, message", [
    (["--navsearch-hold", "1"], "--navsearch-hold: the hold threshold is a failure probability from 0 to below 1, got '1'"),
    (["--navsearch-hold", "x"], "got 'x' (e.g. 0.9, the default"),
    (["--nav-sensor-model", "perfect"], "--nav-sensor-model: unknown sensor model 'perfect': give realistic, none, "),
    (["--nav-sensor-model", "dropout=2"], "dropout must be a number from 0 to 1, got '2'"),
    (["-o", "nav_sensor_model=loud"], "ini option nav_sensor_model: unknown sensor model 'loud'"),
    (["-o", "navsearch_hold=2"], "ini option navsearch_hold: the hold threshold"),
])
def test_bad_hold_thresholds_and_sensor_models_are_usage_errors(project: pytest.Pytester, args, message):
    result = run(project, "--navsearch", "crate", "--budget", "2", *args)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert message in result.stderr.str(), result.stderr.str()


def test_the_sensor_model_applies_to_plain_runs_of_scenarios_without_noise(project: pytest.Pytester):
    (project.path / "suite").mkdir()
    (project.path / "suite" / "quiet.yaml").write_text("version: 1\nmission: {start: {x: 0, y: 0, yaw: 0}, "
                                                        "goal: {x: 2, y: 0, yaw: 0}}\n")
    (project.path / "suite" / "own.yaml").write_text("version: 1\nrobot: {lidar: {noise_sigma: 0.05}}\nmission: "
                                                      "{start: {x: 0, y: 0, yaw: 0}, goal: {x: 2, y: 0, yaw: 0}}\n")
    result = run(project, "suite", "--nav-sensor-model", "noise_sigma=0.03", "--nav-results", "r.jsonl")
    assert result.ret == 0, result.stdout.str()
    import json
    from pytest_navscenario.scenario.model import content_hash
    records = {json.loads(line)["scenario"]: json.loads(line) for line in (project.path / "r.jsonl").read_text().splitlines()}
    quiet = load_scenario(project.path / "suite" / "quiet.yaml")
    own = load_scenario(project.path / "suite" / "own.yaml")
    assert records["quiet"]["scenario_hash"] != content_hash(quiet)          # ran with the model's noise
    assert records["own"]["scenario_hash"] == content_hash(own)              # its own model kept
