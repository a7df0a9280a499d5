"""Issue 34, the scenario layer: ``signals:`` and ``requirements:`` load, dump back equal, are known
to the JSON Schema, and every mistake is an error at the file's line with a fix (a formula's
syntax, a signal the scenario does not have, an obstacle a signal names that is not there)."""
from __future__ import annotations

import textwrap

import pytest

from pytest_navscenario import ScenarioError, dump_scenario, load_scenario, loads_scenario

HEAD = """\
version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 8, y: 0}, waypoints: [{x: 4, y: -1}]}
obstacles:
  - {type: person, name: walker, x: 4, y: 2}
"""


def scenario_text(tail: str) -> str:
    return HEAD + textwrap.dedent(tail)


GOOD = scenario_text("""\
signals:
  - {name: d_walker, distance_to: walker}
  - {name: dock, inside: {x: 8, y: 0, radius: 1}}
  - {name: keepout, inside: {points: [[2, 1], [3, 1], [3, 2]]}}
  - {name: closing, speed_toward: "walk*"}
requirements:
  - {name: keep-away, spec: "always (d_walker >= 0.8)"}
  - {name: slow-near-people, spec: "always ((d_walker < 1.5) implies (speed <= 0.3))", scale: 0.5}
  - {name: reach-dock, spec: "eventually[0:60] (dock >= 0)"}
  - {name: via-waypoint, spec: "eventually (d_waypoint1 <= 0.5)"}
""")


def test_requirements_and_signals_load_and_dump_back_equal():
    s = loads_scenario(GOOD)
    assert [r.name for r in s.requirements] == ["keep-away", "slow-near-people", "reach-dock", "via-waypoint"]
    assert s.requirements[1].scale == 0.5
    assert s.signals[0].distance_to == ("walker",) and s.signals[1].inside.radius == 1.0
    assert s.signals[2].inside.points == ((2.0, 1.0), (3.0, 1.0), (3.0, 2.0))
    assert loads_scenario(dump_scenario(s)) == s


def test_requirements_do_not_change_the_layouts_hash():
    from pytest_navscenario.scenario.model import content_hash
    assert content_hash(loads_scenario(GOOD)) == content_hash(loads_scenario(HEAD))


def _error(text: str) -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        loads_scenario(text, "s.yaml")
    return info.value


def test_a_formula_that_is_not_stl_is_an_error_at_its_line_with_the_column_and_a_fix():
    err = _error(scenario_text("""\
        requirements:
          - {name: a, spec: "always (clearance >= 0.3)"}
          - {name: b, spec: "always ((clearance >= 0.3)"}
        """))
    assert err.line == 7 and err.field == "requirements[1].spec"
    assert "column" in err.message and err.hint
    assert str(err).startswith("s.yaml:7: requirements[1].spec:")


def test_an_unknown_signal_is_an_error_listing_the_known_ones():
    err = _error(scenario_text("""\
        requirements:
          - {name: a, spec: "always (d_walkr >= 0.8)"}
        signals:
          - {name: d_walker, distance_to: walker}
        """))
    assert err.field == "requirements[0].spec" and err.line == 6
    assert "'d_walkr'" in err.message and "d_walker" in err.message and "clearance" in err.message
    assert "d_waypoint1" in err.message
    assert "did you mean 'd_walker'" in err.hint


def test_a_signal_naming_no_obstacle_is_an_error_with_the_obstacles_named():
    err = _error(scenario_text("""\
        signals:
          - {name: d_walker, distance_to: walkr}
        """))
    assert err.field == "signals[0].distance_to" and err.line == 6 and "walker" in err.hint


@pytest.mark.parametrize("tail, field, words", [
    ('signals:\n  - {name: speed, distance_to: walker}\n', "signals[0].name", "built-in"),
    ('signals:\n  - {name: 2fast, distance_to: walker}\n', "signals[0].name", "cannot be named"),
    ('signals:\n  - {name: d, distance_to: walker, speed_toward: walker}\n', "signals[0]", "exactly one"),
    ('signals:\n  - {name: d, inside: {x: 1, y: 1}}\n', "signals[0].inside", "circle"),
    ('requirements:\n  - {name: a, spec: "always (speed <= 1)"}\n  - {name: a, spec: "always (speed <= 2)"}\n',
     "requirements[1].name", "twice"),
    ('requirements:\n  - {name: a, spec: "always (speed <= 1)", scale: 0}\n', "requirements[0].scale", "> 0"),
    ('requirements:\n  - {name: a}\n', "requirements[0].spec", "missing"),
    ('signals:\n  - {name: X, distance_to: walker}\n', "signals[0].name", "word of the formula language"),
    ('requirements:\n  - {name: a, spec: "always[0:0.25] (speed <= 1)"}\n', "requirements[0].spec",
     "sampling periods of 0.1 s"),
])
def test_other_mistakes_are_errors_at_their_field(tail, field, words):
    err = _error(HEAD + tail)
    assert err.field == field and err.line is not None and err.hint
    assert words in str(err)


def test_the_json_schema_knows_the_keys():
    jsonschema = pytest.importorskip("jsonschema")
    import yaml

    from pytest_navscenario.scenario.json_schema import scenario_schema
    validator = jsonschema.Draft202012Validator(scenario_schema())
    assert not list(validator.iter_errors(yaml.safe_load(GOOD)))
    bad = yaml.safe_load(HEAD + 'requirements:\n  - {name: a, spec: "always (speed <= 1)", scail: 1}\n')
    assert list(validator.iter_errors(bad))


def test_a_shared_file_is_merged_and_the_scenarios_own_requirement_wins(tmp_path):
    from pytest_navscenario.scenario.requirement_reading import load_shared, with_shared
    shared = tmp_path / "rules.yaml"
    shared.write_text('requirements:\n  - {name: keep-clear, spec: "always (clearance >= 0.3)"}\n'
                      '  - {name: keep-away, spec: "always (d_walker >= 2)"}\n')
    s = with_shared(loads_scenario(GOOD), load_shared(shared))
    assert [r.name for r in s.requirements][-1] == "keep-clear"
    assert next(r for r in s.requirements if r.name == "keep-away").spec == "always (d_walker >= 0.8)"
    bare = loads_scenario(HEAD, "bare.yaml")
    with pytest.raises(ScenarioError, match="'d_walker'.*does not have") as info:
        with_shared(bare, load_shared(shared))
    assert info.value.path == str(shared)
    shared.write_text('requirements:\n  - {name: x, spec: "always ((speed <= 1)"}\n')
    with pytest.raises(ScenarioError) as info:
        load_shared(shared)
    assert info.value.line == 2 and info.value.field == "requirements[0].spec"
