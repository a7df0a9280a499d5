"""Issue 34, the verdict: every episode is checked against its requirements; a violated one fails
the item with a message naming the requirement, the formula, the first time it was violated and
the robustness in the signal's units; the results file and the JUnit properties carry every
requirement's robustness; a shared file (--nav-requirements, ini nav_requirements) applies to
every scenario. Real MuJoCo, real pytest runs."""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import pytest_navscenario.plugin.payload  # noqa: F401  (numpy: in-process runs cannot import it afresh)
from pytest_navscenario import load_scenario, loads_scenario
from pytest_navscenario.harness.runner import run_scenario

ROOT = Path(__file__).resolve().parents[2]
CROSSING = (ROOT / "scenarios" / "person-crossing.yaml").read_text().split("search:")[0]
SIGNALS = "signals:\n  - {name: d_walker, distance_to: walker}\n"
KEEPS = '  - {name: keep-away, spec: "always (d_walker >= 0.5)"}\n'
BREAKS = '  - {name: slow-near-people, spec: "always ((d_walker < 1.5) implies (speed <= 0.3))"}\n'
PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none", "--nav-artifacts=none"]


def crossing(*requirements: str) -> str:
    return CROSSING + SIGNALS + ("requirements:\n" + "".join(requirements) if requirements else "")


def test_a_violated_requirement_is_the_outcome_with_its_name_formula_time_and_robustness():
    result = run_scenario(loads_scenario(crossing(KEEPS, BREAKS)), "dwa")
    assert result.outcome.value == "requirement"
    keep, slow = result.requirements
    assert not keep.violated and keep.robustness > 0 and keep.unit == "m"
    assert slow.violated and slow.first_violation is not None and 3.0 < slow.first_violation < 10.0
    assert result.message.startswith("requirement 'slow-near-people' violated: "
                                     "always ((d_walker < 1.5) implies (speed <= 0.3)) first at t=")
    assert f"robustness {slow.robustness:.3g}" in result.message


def test_the_distance_signal_is_the_footprints_distance_to_where_the_person_is():
    from pytest_navscenario.verdict.signals import episode_signals
    scenario = loads_scenario(crossing(KEEPS))
    result = run_scenario(scenario, "dwa")
    values = episode_signals(scenario, result.trajectory, ["d_walker", "clearance", "time", "speed"])
    assert len(values["time"]) == int(result.trajectory.duration * 10 + 1e-6) + 1
    assert np.all(values["clearance"] <= values["d_walker"] + 1e-12)
    # at its closest, the walker is the nearest obstacle: the metric's minimum clearance over all
    # physics steps is at most the per-tick one
    assert result.metrics.min_clearance <= values["clearance"].min() + 1e-9
    assert abs(values["d_walker"].min() - keep_robustness(result) - 0.5) < 1e-9


def keep_robustness(result) -> float:
    return result.requirements[0].robustness


def test_requirements_that_hold_leave_the_outcome_as_it_was():
    plain = run_scenario(loads_scenario(crossing()), "dwa")
    held = run_scenario(loads_scenario(crossing(KEEPS)), "dwa")
    assert plain.outcome == held.outcome and plain.message == held.message
    assert np.array_equal(plain.trajectory.pose, held.trajectory.pose)


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "crossing.yaml").write_text(crossing(KEEPS, BREAKS))
    (pytester.path / "scenarios" / "kept.yaml").write_text(crossing(KEEPS))
    return pytester


def test_the_item_fails_and_the_results_file_and_junit_carry_each_robustness(project):
    result = project.runpytest(*PLUGIN, "--nav-results=r.jsonl", "--junitxml=j.xml", "scenarios")
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(["*requirement 'slow-near-people' violated: always ((d_walker < 1.5) "
                                 "implies (speed <= 0.3)) first at t=*robustness -*"])
    records = {r["scenario"]: r for r in map(json.loads, (project.path / "r.jsonl").read_text().splitlines())}
    failed = records["crossing"]
    assert failed["outcome"] == "requirement" and not failed["passed"]
    by_name = {r["name"]: r for r in failed["requirements"]}
    assert by_name["slow-near-people"]["violated"] and by_name["slow-near-people"]["robustness"] < 0
    assert by_name["keep-away"]["unit"] == "m" and by_name["keep-away"]["first_violation"] is None
    assert [r["name"] for r in records["kept"]["requirements"]] == ["keep-away"]
    props = {p.get("name"): p.get("value") for p in ET.parse(project.path / "j.xml").iter("property")}
    assert float(props["nav_requirement_slow-near-people"]) < 0
    assert float(props["nav_requirement_keep-away"]) > 0


def test_a_shared_requirements_file_applies_to_every_scenario_and_has_an_ini_twin(project):
    (project.path / "rules.yaml").write_text('requirements:\n  - {name: gentle, spec: "always (speed <= 0.5)"}\n')
    result = project.runpytest(*PLUGIN, "--nav-requirements=rules.yaml", "--nav-results=r.jsonl", "scenarios")
    result.assert_outcomes(failed=2)
    result.stdout.fnmatch_lines(["*requirement 'gentle' violated: always (speed <= 0.5) first at t=*m/s*"])
    project.makeini("[pytest]\nnav_requirements = rules.yaml\n")
    again = project.runpytest(*PLUGIN, "scenarios")
    again.assert_outcomes(failed=2)
    (project.path / "rules.yaml").write_text('requirements:\n  - {name: gentle, spec: "always (speed <= "}\n')
    bad = project.runpytest(*PLUGIN, "scenarios")
    bad.stderr.fnmatch_lines(["*ini option nav_requirements: *rules.yaml:2: requirements[[]0[]].spec: *"])
