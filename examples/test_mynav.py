"""Your own assertions and parametrised tests on top of scenario files, with the ``nav_run`` fixture.

    pytest examples/scenarios examples/test_mynav.py --nav-subject=examples.mynav:Planner

``nav_run(scenario_or_path, planner=None, **overrides)`` runs the scenario (top-level fields replaced,
or mapped by a callable) against the session's subject and seed and returns the EpisodeResult.
"""
import dataclasses
from pathlib import Path

import pytest

from pytest_navscenario import Outcome

PILLAR = Path(__file__).parent / "scenarios" / "pillar.yaml"


def pillar_at(y):
    """An override: move every obstacle to lateral offset ``y`` (metres)."""
    return lambda obstacles: tuple(dataclasses.replace(o, y=y) for o in obstacles)


@pytest.mark.parametrize("offset", [
    pytest.param(0.0, marks=pytest.mark.xfail(
        strict=True, reason="pillar dead ahead: symmetric repulsion stalls a reactive planner")),
    0.05, 0.3, -0.4,
])
def test_swerves_around_the_pillar(nav_run, offset):
    result = nav_run(PILLAR, obstacles=pillar_at(offset))
    assert result.outcome is Outcome.SUCCESS, result.message
    assert result.metrics.min_clearance > 0.3


def test_open_field_is_driven_almost_straight(nav_run):
    result = nav_run(PILLAR, obstacles=())
    assert result.outcome is Outcome.SUCCESS
    assert result.metrics.path_efficiency > 0.95
