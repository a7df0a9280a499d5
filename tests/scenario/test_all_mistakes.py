"""Issue 32 item 3: the loader reports every mistake it can find in a file in one pass (before:
only the first of 6, where check-jsonschema lists all 6), each with file:line, field and fix,
capped at reading.MAX_REPORTED."""
from __future__ import annotations

import json
import textwrap

import pytest

from pytest_navscenario import ScenarioError, load_scenario
from pytest_navscenario.core.errors import ScenarioErrors
from pytest_navscenario.scenario import reading
from pytest_navscenario.scenario.json_schema import scenario_schema

jsonschema = pytest.importorskip("jsonschema", reason="compared with the reference validator")
yaml = pytest.importorskip("yaml")

SIX = textwrap.dedent("""\
    version: 1
    robot:
      footprint: {shape: box, length: 0.6, widht: 0.4}
      drive: diferential
      limits: {max_speed: -1.0}
    mission:
      start: {x: 0, y: 0}
      goal: {x: 5, y: "far"}
      timeout: 30
    obstacles:
      - {type: box, name: a, x: 2, y: 0, length: 0.5, width: 0.5}
      - {type: cylinder, name: b, x: 3, y: 1, radius: -0.2}
    simulation: {timestep: 0.01, colour: red}
    """)

EXPECTED = [  # (line, field) in file order
    (3, "robot.footprint.widht"), (4, "robot.drive"), (5, "robot.limits.max_speed"),
    (8, "mission.goal.y"), (12, "obstacles[1].radius"), (13, "simulation.colour")]


def test_every_mistake_of_a_file_in_one_pass_as_check_jsonschema_finds_them(tmp_path):
    path = tmp_path / "six.yaml"
    path.write_text(SIX)
    with pytest.raises(ScenarioErrors) as info:
        load_scenario(path)
    errors = info.value.errors
    assert [(e.line, e.field) for e in errors] == EXPECTED
    assert all(e.hint and e.path == str(path) for e in errors)
    text = str(info.value)
    assert text.splitlines()[0] == f"{path}: 6 mistakes:"
    assert f"  {path}:4: robot.drive: unknown drive 'diferential' (a string) (fix: " in text
    assert f"  {path}:13: simulation.colour: unknown key 'colour' (fix: " in text
    # the reference validator (what check-jsonschema runs) finds the same six places
    found = jsonschema.Draft202012Validator(scenario_schema()).iter_errors(yaml.safe_load(SIX))
    assert sorted(_place(e) for e in found) == sorted(field for _, field in EXPECTED)
    assert isinstance(info.value, ScenarioError)       # callers that catch ScenarioError still do


def _place(error) -> str:
    """A jsonschema error's place as the loader names fields: robot.footprint.widht, obstacles[1]."""
    path = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in error.absolute_path).lstrip(".")
    if error.validator == "additionalProperties":
        path += "." + error.message.split("'")[1]
    return path


def test_one_mistake_reads_as_before(tmp_path):
    path = tmp_path / "one.yaml"
    path.write_text(SIX.splitlines()[0] + "\nmission: {start: {x: 0, y: 0}, goal: {x: 5, y: 0}, timout: 3}\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert not isinstance(info.value, ScenarioErrors)
    assert str(info.value) == f"{path}:2: mission.timout: unknown key 'timout' (fix: did you mean 'timeout'?)"


def test_the_report_is_capped(tmp_path):
    path = tmp_path / "many.yaml"
    keys = ", ".join(f"k{i}: 1" for i in range(30))
    path.write_text(f"version: 1\nmission: {{start: {{x: 0, y: 0}}, goal: {{x: 5, y: 0}}}}\n"
                    f"simulation: {{{keys}}}\n")
    with pytest.raises(ScenarioErrors) as info:
        load_scenario(path)
    assert len(info.value.errors) == reading.MAX_REPORTED == 20
    assert str(info.value).splitlines()[0] == (f"{path}: 20 mistakes (it stops looking at 20: fix these "
                                               f"and load it again):")
