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
def test_dwa_passes_the_seed_as_written(name):
    seed = load_scenario(SCENARIOS / f"{name}.yaml")
    result = run_scenario(seed, "dwa")
    assert result.outcome.value == "success", result.message


# workshop-irregular's search is heavy (~9 s quiet: a convex decomposition and mesh per candidate);
# the default run searches polygons and meshes in tests/sim/test_irregular.py.
@pytest.mark.parametrize("name", [pytest.param(name, marks=pytest.mark.heavy) if name == "workshop-irregular"
                                  else name for name in SEEDS])
def test_a_small_search_around_the_seed_breaks_dwa(name):
    seed = load_scenario(SCENARIOS / f"{name}.yaml")
    report = run_search(seed, load_subject("dwa"), budget=30, seed_value=11, shrink_budget=0)
    assert report.failures, f"no failure in 30 simulations around {name}"
