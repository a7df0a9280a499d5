"""The JSON Schema refuses the file paths the loader refuses (issue 38, part 7): an absolute path or
a '..' part in robot.body.file, terrain[].file and a mesh's file (an editor said nothing, the run
refused them); paths inside the folder stay valid."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from pytest_navscenario import ScenarioError, loads_scenario

jsonschema = pytest.importorskip("jsonschema")
SCHEMA = json.loads((Path(__file__).parents[2] / "pytest_navscenario" / "scenario" / "scenario-v1.json").read_text())
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)
BASE = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 5, y: 0}}\n"
MJCF = "robot: {{drive: diff, body: {{type: mjcf, file: '{f}', controller: 'a:B'}}}}"
HFIELD = "robot: {{drive: diff, body: {{type: wheeled}}}}\nterrain:\n  - {{type: heightfield, x: 3, y: 9, file: '{f}', length: 2, width: 2}}"
MESH = "obstacles:\n  - {{type: mesh, x: 3, y: 9, file: '{f}'}}"


@pytest.mark.parametrize("where", [MJCF, HFIELD, MESH], ids=["robot.body.file", "terrain.file", "mesh.file"])
@pytest.mark.parametrize("path", ["/etc/x.xml", "../x.xml", "sub/../../x.xml", "..\\x.xml"])
def test_a_path_out_of_the_folder_is_refused_by_the_schema_as_by_the_loader(tmp_path, where, path):
    text = BASE + where.format(f=path) + "\n"
    assert not VALIDATOR.is_valid(yaml.safe_load(text))
    if "\\" not in path:
        with pytest.raises(ScenarioError):
            loads_scenario(text, str(tmp_path / "s.yaml"))


@pytest.mark.parametrize("where", [MJCF, HFIELD, MESH], ids=["robot.body.file", "terrain.file", "mesh.file"])
def test_a_path_inside_the_folder_is_valid(where):
    assert VALIDATOR.is_valid(yaml.safe_load(BASE + where.format(f="parts/..thing.xml") + "\n"))
