"""yaml_tree: the composer's shortcuts (plain decimals, the shared scalar cache) give exactly what
``yaml.safe_load`` gives, type included."""
from __future__ import annotations

import math

import pytest
import yaml

from pytest_navscenario.scenario.yaml_tree import parse_yaml, to_plain

SCALARS = ["0", "-0", "+0", "7", "-12", "+12", "007", "08", "0x1f", "0o17", "0b101", "1_000", "1:30",
           "190:20:30", "1.5", "-1.5", "+1.5", "3.", "-0.0", "00.5", ".5", "-.5", "1.0e+3", "1e3", "1.0e3",
           "1_0.5", "6.8523015e+5", ".inf", "-.Inf", ".nan", "1" + "0" * 30, "1" + "0" * 39 + ".5",
           "true", "no", "On", "~", "null", "", "2001-12-14", "'1.5'", '"7"', "x",
           "4.1054657566818555", "12345678901234567890"]


@pytest.mark.parametrize("text", SCALARS)
def test_scalars_as_safe_load(text):
    doc = f"a: {text}\nb: [{text}]\nc:\n  - {text}\n"
    expected = yaml.safe_load(doc)
    for _ in range(2):    # the second time from the shared cache
        got = to_plain(parse_yaml(doc, "t.yaml", max_depth=10, max_nodes=100))
        assert got == expected or all(math.isnan(v) for v in (got["a"], expected["a"]))
        for key in ("a",):
            assert type(got[key]) is type(expected[key])
            if isinstance(expected[key], float) and not math.isnan(expected[key]):
                assert math.copysign(1.0, got[key]) == math.copysign(1.0, expected[key])
        assert [type(v) for v in got["b"] + got["c"]] == [type(v) for v in expected["b"] + expected["c"]]


def test_a_cached_value_is_not_shared_mutably():
    """A value is cached only if it cannot change in place: two files never share a mutable one."""
    doc = "a: !!binary aGVsbG8=\nb: 2001-12-14\n"
    first = to_plain(parse_yaml(doc, "t.yaml", max_depth=10, max_nodes=100))
    second = to_plain(parse_yaml(doc, "t.yaml", max_depth=10, max_nodes=100))
    assert first == second == yaml.safe_load(doc)


def test_duplicate_and_unhashable_keys_still_refused():
    from pytest_navscenario.core.errors import ScenarioError
    with pytest.raises(ScenarioError, match=r"key 'x' is given twice \(first on line 1\)") as err:
        parse_yaml("x: 1\ny: 2\nx: 3\n", "t.yaml", max_depth=10, max_nodes=100)
    assert err.value.line == 3
    with pytest.raises(ScenarioError, match="more than 3 values"):
        parse_yaml("x: 1\ny: 2\n", "t.yaml", max_depth=10, max_nodes=3)


def test_the_shared_cache_keeps_short_texts_only():
    """The cache lives as long as the process: a long value (a hostile file's 2-million-character
    string) must not stay in memory after its file is read."""
    from pytest_navscenario.scenario import yaml_tree
    long_text = "v" * 300
    got = to_plain(parse_yaml(f"a: {long_text}\nb: short-word\n", "t.yaml", max_depth=10, max_nodes=100))
    assert got == {"a": long_text, "b": "short-word"}
    cached = {key[0] for key in yaml_tree._SCALARS}
    assert "short-word" in cached and long_text not in cached


# -- issue 24: a key reported at its own line -----------------------------------------------------

@pytest.mark.parametrize("text, where", [
    ("version: 1\nmission:\n  - 1\n", "f.yaml:2: mission: expected the mission (a mapping), got a list"),
    ("version: 1\nmission:\n  start:\n    - 1\n  goal: {x: 5, y: 0}\n", "f.yaml:3: mission.start: expected the start"),
    ("version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 5, y: 0}}\nrobot:\n  limits:\n    - 3\n",
     "f.yaml:4: robot.limits: expected the velocity limits (a mapping)"),
])
def test_a_section_key_is_reported_at_its_own_line_not_its_childs(text, where):
    """Before: the line of the section's first child (``- 1``), not of the key that is wrong."""
    from pytest_navscenario.core.errors import ScenarioError
    from pytest_navscenario.scenario.loader import loads_scenario
    with pytest.raises(ScenarioError) as info:
        loads_scenario(text, "f.yaml")
    assert str(info.value).startswith(where)


def test_field_line_finds_a_keys_own_line_or_its_sections():
    from pytest_navscenario.scenario.yaml_tree import field_line
    text = ("version: 1\nmission:\n  start: {x: 0, y: 0}\n  goal: {x: 5, y: 0}\n  timeout: 3\nobstacles:\n"
            "  - {type: box, x: 3, y: 3, length: 1, width: 1}\n  - type: box\n    length: 1\n    width: 1\n"
            "    motion:\n      path: [[0, 0], [1, 1]]\n      speed: 1\n")
    assert field_line(text, "mission.timeout") == 5
    assert field_line(text, "mission.goal_tolerance") == 2          # a default: its section's key
    assert field_line(text, "obstacles[1].motion.path") == 12
    assert field_line(text, "robot.limits.max_speed") is None       # nothing of it written
    assert field_line("key: [unclosed", "key") is None
