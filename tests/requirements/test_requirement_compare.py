"""Issue 34, compare and the gate: per-requirement violation rates with intervals and McNemar
between two versions, and --nav-baseline failing a newer version that violates a requirement the
older one kept, even where the older one failed the scenario otherwise (so it was no "regression"
of the outcome). Real planners, real pytest runs."""
from __future__ import annotations

import json

import pytest

import pytest_navscenario.plugin.payload  # noqa: F401  (numpy: in-process runs cannot import it afresh)
from pytest_navscenario.report.compare import compare_files, format_comparison

PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none", "--nav-artifacts=none"]
PLANNERS = '''
import math

class Straight:
    """Drives at ``cruise`` m/s straight at the target."""
    name = "straight"
    cruise = 0.3

    def reset(self, scenario):
        pass

    def act(self, obs):
        x, y, yaw = (float(v) for v in obs.pose)
        dx, dy = float(obs.target[0]) - x, float(obs.target[1]) - y
        d = math.hypot(dx, dy)
        c, s = math.cos(yaw), math.sin(yaw)
        v = min(self.cruise, d)
        return ((c * dx + s * dy) / d * v, (-s * dx + c * dy) / d * v, 0.0) if d > 1e-6 else (0.0, 0.0, 0.0)

class Creep(Straight):
    version = "1.0"

class Rush(Straight):
    version = "2.0"
    cruise = 1.0
'''
SCENARIO = """\
version: 1
robot: {drive: omni}
mission: {start: {x: 0, y: 0}, goal: {x: 3, y: 0}, timeout: %s}
requirements:
  - {name: gentle, spec: "always (speed <= 0.5)"}
  - {name: near-goal-at-end, spec: "eventually (d_goal <= 1)"}
"""


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.syspathinsert()
    (pytester.path / "slowfast.py").write_text(PLANNERS)
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "short.yaml").write_text(SCENARIO % 8)     # Creep times out
    (pytester.path / "scenarios" / "long.yaml").write_text(SCENARIO % 30)     # Creep succeeds
    return pytester


def test_the_gate_fails_a_version_that_violates_a_requirement_the_older_one_kept(project):
    old = project.runpytest(*PLUGIN, "--nav-subject=slowfast:Creep", "--nav-results=a.jsonl", "scenarios")
    old.assert_outcomes(passed=1, failed=1)
    new = project.runpytest(*PLUGIN, "--nav-subject=slowfast:Rush", "--nav-results=b.jsonl",
                            "--nav-baseline=a.jsonl", "scenarios")
    assert new.ret != 0
    new.stdout.fnmatch_lines([
        "*gentle * 2 * 0   0.0% [[]0-*[]] * 2 100.0% [[]*-100[]] *2 *0 *",
        "*B violates a requirement A kept (2):*",
        "*FAILED the regression gate: 2 requirement(s) the baseline kept are violated now*",
    ])
    records = [json.loads(line) for line in (project.path / "b.jsonl").read_text().splitlines()]
    assert {r["outcome"] for r in records} == {"requirement"}


def test_compare_gives_each_requirements_rates_intervals_and_mcnemar(project):
    project.runpytest(*PLUGIN, "--nav-subject=slowfast:Creep", "--nav-results=a.jsonl", "scenarios")
    project.runpytest(*PLUGIN, "--nav-subject=slowfast:Rush", "--nav-results=b.jsonl", "scenarios")
    cmp = compare_files(project.path / "a.jsonl", project.path / "b.jsonl")
    rows = {r.name: r for r in cmp.requirements}
    assert rows["gentle"].n == 2 and rows["gentle"].a[0] == 0 and rows["gentle"].b[0] == 2
    assert rows["gentle"].mcnemar_p == pytest.approx(0.5)
    assert rows["near-goal-at-end"].b[0] == 0 and not rows["near-goal-at-end"].broke
    assert len(cmp.broke) == 1 and len(cmp.broke_requirements) == 2 and cmp.has_regressions
    assert "2 requirement(s) A kept that B violates" in format_comparison(cmp)
