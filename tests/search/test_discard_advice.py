"""Issue 32 item 6: a search that discards many candidates says why and what to change in the
seed's search: section, in the terminal summary and the HTML report (before: "220 discarded
(no-path 214, start-blocked 6)" and nothing else). The advice was measured: ramp-levels' search
at budget 30 discards 214 of 250 as no-path; with the keys the advice names set to 0 it discards 3
(start-blocked); person-crossing's 41 of 91 mover-through become 0 with obstacle_dx/dy 0.3."""
from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from pytest_navscenario import load_scenario
from pytest_navscenario.search.discards import discard_advice
from pytest_navscenario.search.space import SearchSpace

SEEDS = Path(__file__).resolve().parents[2] / "scenarios"


def test_a_person_walking_through_a_wall_names_the_person_and_the_keys():
    space = SearchSpace(load_scenario(SEEDS / "person-crossing.yaml"))
    (advice,) = discard_advice({"mover-through": 41}, 50, space)
    assert advice.line() == (
        "41 of 91 candidates discarded as mover-through: the search moves 'walker' so that its path crosses "
        "a static obstacle (a person walking through a wall); to search valid layouts instead, narrow "
        "obstacle_dx/obstacle_dy, which move its whole path (e.g. search: {obstacle_dx: 0.3, obstacle_dy: "
        "0.3}; 0 searches its timing only: motion_start, motion_speed)")


def test_few_discards_are_not_worth_a_word():
    space = SearchSpace(load_scenario(SEEDS / "boxes1.yaml"))
    assert discard_advice({"goal-blocked": 8, "start-blocked": 8}, 50, space) == []


def test_the_terrain_search_names_the_keys_that_break_its_joints(pytester: pytest.Pytester,
                                                                   monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    shutil.copytree(SEEDS, pytester.path / "scenarios", ignore=shutil.ignore_patterns("regressions"))
    result = pytester.runpytest_subprocess(
        "-p", "pytest_navscenario.plugin", "--navsearch", "ramp-levels", "--budget", "5",
        "--navsearch-shrink-budget", "0", "--nav-subject=dwa", "--nav-html=report.html",
        "--nav-plots=none", timeout=300)
    out = result.stdout.str()
    expected = ("candidates discarded as no-path: the search moves and reshapes terrain elements (ramp, "
                "mezzanine) one by one")
    assert expected in out, out[-3000:]
    assert "keep the joints: search: {terrain_dx: 0, terrain_rise: 0, terrain_slope: 0}" in out
    html = (pytester.path / "report.html").read_text()
    assert '<p class="advice">' in html and expected in html


def test_a_frozen_stop_names_the_clearance_to_what_it_stopped_for(pytester: pytest.Pytester,
                                                                  monkeypatch: pytest.MonkeyPatch):
    """Issue 32 item 5: person-crossing's summary said "safety-stop, clearance 0.750 m", the
    clearance to a wall; the stop was for the walker. The summary names the walker's."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    shutil.copytree(SEEDS, pytester.path / "scenarios", ignore=shutil.ignore_patterns("regressions"))
    result = pytester.runpytest_subprocess(
        "-p", "pytest_navscenario.plugin", "--navsearch", "person-crossing", "--budget", "50",
        "--navsearch-shrink-budget", "0", "--navsearch-seed", "4", "--nav-subject=dwa", "--nav-plots=none",
        timeout=300)   # search seed 4: a stop for the walker while a wall is nearer (0.750 m)
    out = result.stdout.str()
    assert re.search(r"person-crossing-[0-9a-f]{16}\.yaml  safety-stop, clearance to 'walker' \d\.\d{3} m "
                     r"\(min 0\.750 m\)", out), out[-3000:]
