"""The terrain seeds of issue 25 in scenarios/ (a loading dock beside the route, a ramp between two
levels, stairs a wheeled robot must go round, a threshold, a rough yard): the built-in dwa passes
each as written, and a budget-100 search breaks each, at least once by its terrain."""
from __future__ import annotations

from pathlib import Path

import pytest

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.search.engine import run_search
from pytest_navscenario.subjects.loading import load_subject

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
TERRAIN_SEEDS = ("loading-dock", "ramp-levels", "stairs-around", "threshold", "rough-yard")
PAPER_AND_ISSUE_12 = ("L-corridor", "boxes1", "boxes2", "corridor", "cylinders", "forklift-aisle", "glass-door",
                      "person-crossing", "workshop-irregular")


@pytest.mark.parametrize("name", TERRAIN_SEEDS)
def test_dwa_passes_each_terrain_seed_as_written(name):
    seed = load_scenario(SCENARIOS / f"{name}.yaml")
    assert seed.terrain and seed.robot.body.kind == "wheeled"
    result = run_scenario(seed, "dwa")
    assert result.outcome.value == "success", result.message


def test_the_nine_older_seeds_have_no_terrain_and_the_planar_body():
    for name in PAPER_AND_ISSUE_12:
        seed = load_scenario(SCENARIOS / f"{name}.yaml")
        assert seed.terrain == () and seed.robot.body.kind == "planar", name


@pytest.mark.heavy
@pytest.mark.parametrize("name", TERRAIN_SEEDS)
def test_a_budget_100_search_breaks_each_terrain_seed_by_its_terrain(name):
    seed = load_scenario(SCENARIOS / f"{name}.yaml")
    report = run_search(seed, load_subject("dwa"), budget=100, seed_value=0, shrink_budget=0, subject="dwa")
    culprits = [f.found.culprit for f in report.failures]
    assert any(c.startswith("terrain:") for c in culprits), (name, culprits)
