"""The seeds of issue 12 in scenarios/: a competent planner (the built-in dwa) passes each as written,
and a small search around it finds failures (what they are there for)."""
from __future__ import annotations

from pathlib import Path

import pytest

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.search.engine import run_search
from pytest_navscenario.subjects.loading import load_subject

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
SEEDS = ("person-crossing", "forklift-aisle", "workshop-irregular", "glass-door")


@pytest.mark.parametrize("name", SEEDS)
def test_dwa_passes_the_seed_as_written_and_a_search_breaks_it(name):
    seed = load_scenario(SCENARIOS / f"{name}.yaml")
    result = run_scenario(seed, "dwa")
    assert result.outcome.value == "success", result.message
    report = run_search(seed, load_subject("dwa"), budget=30, seed_value=11, shrink_budget=0)
    assert report.failures, f"no failure in 30 simulations around {name}"
