"""Issue 34, the search: a requirement's violation is a failure, its cause signature names the
requirement, shrinking keeps the violation, and the frozen file keeps the requirements it was found
with (a shared file's too), so running it again fails the same way. The graded fitness is the
requirements' robustness, each over its scale. Real searches, real MuJoCo."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

import pytest_navscenario.plugin.payload  # noqa: F401  (numpy: in-process runs cannot import it afresh)
from pytest_navscenario import load_scenario, loads_scenario
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.search.fitness import Route, read_episode

ROOT = Path(__file__).resolve().parents[2]
CROSSING = (ROOT / "scenarios" / "person-crossing.yaml").read_text()
RULE = ("signals:\n  - {name: d_person, distance_to: walker}\n"
        "requirements:\n  - {name: keep-away-from-people, spec: \"always (d_person >= 0.8)\"}\n")
PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none", "--nav-artifacts=none"]


def test_the_fitness_of_an_episode_that_kept_its_requirements_is_their_scaled_robustness():
    seed = loads_scenario(CROSSING + RULE)
    res = run_scenario(seed, "dwa")
    reading, _ = read_episode(res, Route(seed))
    (req,) = res.requirements
    assert list(reading.margins) == ["requirement:keep-away-from-people"]
    assert reading.margins["requirement:keep-away-from-people"] == pytest.approx(req.robustness / req.span)
    scaled = loads_scenario(CROSSING + RULE.replace('0.8)"}', '0.8)", scale: 0.5}'))
    reading, _ = read_episode(run_scenario(scaled, "dwa"), Route(scaled))
    assert reading.margins["requirement:keep-away-from-people"] == pytest.approx(min(1.0, req.robustness / 0.5))


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "people.yaml").write_text(CROSSING + RULE)
    return pytester


def test_a_search_finds_shrinks_and_freezes_a_violation_that_keeps_its_requirement(project):
    result = project.runpytest(*PLUGIN, "--navsearch=people", "--budget=40", "--navsearch-seed=0",
                               "--navsearch-out=frozen", "--navsearch-hold=0")
    frozen = sorted((project.path / "frozen").rglob("*.yaml"))
    violations = [p for p in frozen if "requirement" in json.dumps(load_scenario(p).provenance or {})]
    assert violations, [load_scenario(p).provenance for p in frozen]
    scenario = load_scenario(violations[0])
    assert [r.name for r in scenario.requirements] == ["keep-away-from-people"]
    assert scenario.signals[0].distance_to == ("walker",)
    again = run_scenario(scenario, "dwa")
    assert again.outcome.value == "requirement" and "keep-away-from-people" in again.message
    assert "requirement:keep-away-from-people" in json.dumps(scenario.provenance)
    result.stdout.fnmatch_lines([f"*new  frozen/people/{violations[0].name}  requirement keep-away-from-people, "
                                 "clearance *"])


def test_a_shared_requirement_is_searched_and_frozen_into_the_file(project):
    (project.path / "scenarios" / "people.yaml").write_text(CROSSING + RULE.split("requirements:")[0])
    (project.path / "rules.yaml").write_text("requirements:\n  - {name: keep-away-from-people, "
                                             "spec: \"always (d_person >= 0.8)\"}\n")
    project.runpytest(*PLUGIN, "--navsearch=people", "--budget=40", "--navsearch-seed=0",
                      "--navsearch-out=frozen", "--navsearch-hold=0", "--nav-requirements=rules.yaml")
    frozen = [load_scenario(p) for p in sorted((project.path / "frozen").rglob("*.yaml"))]
    assert any(s.requirements and s.requirements[0].name == "keep-away-from-people" for s in frozen)
    assert any(run_scenario(s, "dwa").outcome.value == "requirement" for s in frozen[:3])


def test_a_success_with_requirements_is_told_apart_by_the_requirement_that_came_closest():
    tour = loads_scenario((ROOT / "scenarios" / "dock-tour.yaml").read_text())
    res = run_scenario(tour, "dwa")
    assert res.outcome.value == "success"
    reading, _ = read_episode(res, Route(tour))
    closest = min(res.requirements, key=lambda r: r.robustness / r.span)
    assert reading.signature[:2] == ("success", f"requirement:{closest.name}")
    assert reading.closest_margin == f"requirement:{closest.name}"
