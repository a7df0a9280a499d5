"""Names that would drive a terminal (issue 38, part 6): a scenario, family, obstacle or terrain
name holding a control character (an ANSI escape, a bell, a C1 code) is refused by the loader at
its line with the fix, and by the JSON Schema an editor checks it with."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from pytest_navscenario import ScenarioError, load_scenario

jsonschema = pytest.importorskip("jsonschema")
SCHEMA = json.loads((Path(__file__).parents[2] / "pytest_navscenario" / "scenario" / "scenario-v1.json").read_text())

HOSTILE = r'"\e[2J\e[31mPWN\e]0;title\a"'
BASE = """version: 1
name: plain
mission: {start: {x: 0, y: 0}, goal: {x: 5, y: 0}}
robot: {drive: diff, body: {type: wheeled}}
obstacles:
  - {type: box, name: crate, x: 3, y: 2, length: 1, width: 1}
terrain:
  - {type: ramp, name: ramp, x: 2, y: -3, length: 2, width: 1, rise: 0.2}
"""


@pytest.mark.parametrize("where,field,line", [
    ("name: plain", "name", 2), ("name: crate", "obstacles[0].name", 6), ("name: ramp", "terrain[0].name", 8)])
@pytest.mark.parametrize("text", [HOSTILE, r'"bell\a"', r'"c1 \x9b code"', r'"del \x7f"'])
def test_a_name_with_a_control_character_is_refused_at_its_line(tmp_path, where, field, line, text):
    import yaml
    path = tmp_path / "s.yaml"
    path.write_text(BASE.replace(where, where.split(":")[0] + ": " + text))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert err.value.field == field and err.value.line == line
    message = str(err.value)
    assert "control character U+" in message and "fix: remove the control characters" in message
    assert "\x1b" not in message and "\x07" not in message           # printed escaped, never raw
    doc = yaml.safe_load(path.read_text())
    assert not jsonschema.Draft202012Validator(SCHEMA).is_valid(doc)


def test_the_family_too_and_plain_unicode_names_stay_accepted(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text(BASE + "family: \"fam\\e[0m\"\n")
    with pytest.raises(ScenarioError, match="family: .*control character U\\+001B"):
        load_scenario(path)
    path.write_text(BASE.replace("name: crate", "name: Kiste-ü-日本"))
    assert load_scenario(path).obstacles[0].name == "Kiste-ü-日本"
