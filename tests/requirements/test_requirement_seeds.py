"""Issue 34, the shipped seeds with requirements: dwa keeps each seed's requirements as written, and
a budget-100 search breaks each of them with a violation of a requirement (heavy: three searches)."""
from __future__ import annotations

from pathlib import Path

import pytest

from pytest_navscenario import load_scenario
from pytest_navscenario.harness.runner import run_scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
SEEDS = ("people-distance", "people-speed", "dock-tour")


@pytest.mark.parametrize("name", SEEDS)
def test_dwa_keeps_every_requirement_of_the_seed_as_written(name):
    seed = load_scenario(SCENARIOS / f"{name}.yaml")
    result = run_scenario(seed, "dwa")
    assert result.outcome.value == "success", result.message
    assert result.requirements and all(r.robustness > 0.05 for r in result.requirements), result.requirements


@pytest.mark.heavy
@pytest.mark.parametrize("name", SEEDS)
def test_a_budget_100_search_breaks_a_requirement_of_the_seed(name):
    from pytest_navscenario.search.engine import run_search
    from pytest_navscenario.subjects.loading import load_subject

    seed = load_scenario(SCENARIOS / f"{name}.yaml")
    report = run_search(seed, load_subject("dwa"), budget=100, seed_value=0, strategy="evolve", shrink_budget=0)
    broken = {f.found.signature[1] for f in report.failures if f.found.signature[0] == "requirement"}
    assert broken, [f.found.signature for f in report.failures]
    names = {f"requirement:{r.name}" for r in seed.requirements}
    assert broken <= names
    frozen = report.failures[0].found.scenario
    assert frozen.requirements == seed.requirements
