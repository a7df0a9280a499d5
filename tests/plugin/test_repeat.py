"""--nav-repeat: each scenario runs N times under different noise seeds; scenarios whose outcome
changes from run to run are reported as flaky, in the terminal and in the results file."""
from __future__ import annotations

import json

import pytest

from pytest_navscenario.plugin.collect import repeat_seed
from pytest_navscenario.report.flaky import annotate_repeats, format_flaky

# Decides once, from the (noisy) range straight ahead, whether to drive to the goal or stand still:
# with the lidar's noise the same scenario succeeds under some seeds and times out under others.
PLANNER = '''
import math
import numpy as np


class Hesitant:
    def reset(self, scenario):
        self.go = None

    def act(self, obs):
        if self.go is None:
            self.go = float(obs.ranges[np.argmin(np.abs(obs.angles))]) > 2.0
        if not self.go:
            return (0.0, 0.0, 0.0)
        x, y, yaw = obs.pose
        dx, dy = obs.goal[0] - x, obs.goal[1] - y
        c, s = math.cos(yaw), math.sin(yaw)
        return (0.8 * (c * dx + s * dy), 0.8 * (-s * dx + c * dy), 0.0)
'''

NOISY = """\
version: 1
robot: {lidar: {noise_sigma: 0.4}}
mission: {start: {x: 0, y: 0, yaw: 0}, goal: {x: 0, y: 2, yaw: 0}, timeout: 8}
obstacles: [{type: box, name: ahead, x: 3, y: 0, length: 1, width: 1}]
"""
QUIET = NOISY.replace("noise_sigma: 0.4", "noise_sigma: 0.0")


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(hesitant=PLANNER)
    pytester.mkdir("suite")
    (pytester.path / "suite" / "noisy.yaml").write_text(NOISY)
    (pytester.path / "suite" / "quiet.yaml").write_text(QUIET)
    return pytester


def run(project: pytest.Pytester, *args: str) -> pytest.RunResult:
    return project.runpytest_subprocess(
        "-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider", "suite", "--nav-plots=none",
        "--nav-artifacts=none", "--nav-subject=hesitant:Hesitant", "--nav-results=r.jsonl", *args)


def test_repeats_find_the_flaky_scenario_and_record_counts(project):
    result = run(project, "--nav-repeat=6", "-v")
    out = result.stdout.str()
    for r in range(6):
        assert f"suite/noisy.yaml::noisy[r{r}]" in out
    records = [json.loads(line) for line in (project.path / "r.jsonl").read_text().splitlines()]
    assert len(records) == 12
    noisy = [r for r in records if r["scenario"] == "noisy"]
    quiet = [r for r in records if r["scenario"] == "quiet"]
    assert sorted(r["repeat"] for r in noisy) == list(range(6))
    assert len({r["seed"] for r in noisy}) == 6                      # a different noise seed each run
    counts = noisy[0]["outcome_counts"]
    assert set(counts) == {"success", "timeout"} and sum(counts.values()) == 6
    assert all(r["flaky"] and r["runs"] == 6 and r["outcome_counts"] == counts for r in noisy)
    assert not any(r["flaky"] for r in quiet) and quiet[0]["outcome_counts"] == {"success": 6}
    assert "1 of 2 scenario(s) gave different outcomes" in out
    assert (f"suite/noisy.yaml::noisy: success {counts['success']}/6, timeout {counts['timeout']}/6" in out
            or f"suite/noisy.yaml::noisy: timeout {counts['timeout']}/6, success {counts['success']}/6" in out)
    # the failure report reproduces one repeat exactly
    assert "--nav-repeat=6" in out


def test_repeat_zero_is_the_plain_run_and_bad_values_are_usage_errors(project):
    plain = run(project)
    plain_records = [json.loads(line) for line in (project.path / "r.jsonl").read_text().splitlines()]
    run(project, "--nav-repeat=3")
    repeated = [json.loads(line) for line in (project.path / "r.jsonl").read_text().splitlines()]
    first = {r["scenario"]: (r["outcome"], r["seed"], r["metrics"]) for r in repeated if r["repeat"] == 0}
    assert first == {r["scenario"]: (r["outcome"], r["seed"], r["metrics"]) for r in plain_records}
    assert plain.ret in (0, 1)
    bad = run(project, "--nav-repeat=0")
    assert bad.ret == pytest.ExitCode.USAGE_ERROR
    assert "--nav-repeat: expected a whole number of runs per scenario from 1 to 10000, got '0'" in bad.stderr.str()


def test_repeat_seeds_are_stable_and_distinct():
    assert repeat_seed(5, 0) == 5
    seeds = [repeat_seed(5, r) for r in range(1, 50)]
    assert len(set(seeds)) == 49 and all(0 <= s < 2**63 for s in seeds)
    assert seeds == [repeat_seed(5, r) for r in range(1, 50)]
    assert repeat_seed(6, 1) != repeat_seed(5, 1)


def test_flaky_report_from_records():
    recs = [{"path": "a.yaml", "scenario": "a", "outcome": o} for o in ("success", "timeout", "success")]
    recs += [{"path": "b.yaml", "scenario": "b", "outcome": "success"}]
    annotated = annotate_repeats(recs)
    assert annotated[0]["outcome_counts"] == {"success": 2, "timeout": 1} and annotated[0]["flaky"]
    assert annotated[3]["flaky"] is False
    assert format_flaky(recs).splitlines()[1] == "  a.yaml::a: success 2/3, timeout 1/3"
    assert format_flaky(recs[3:]).startswith("no flaky scenarios")
