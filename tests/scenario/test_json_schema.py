"""Issue 28: the JSON Schema of the scenario format (for editors and CI) says what the loader says.

Shipped seeds, examples and the docs' examples validate; broken files the loader refuses for a type,
a range, an enum or an unknown key are refused by the schema too; for every declared key, probes at
and beyond its limits, of wrong types and null get the same verdict from both; every set of keys
the loader reads is the schema's, with the same defaults; the schema the package ships, the
project's copy and ``navscenario schema`` are the same bytes; ``check-jsonschema`` (the CI command
the docs give) agrees."""
from __future__ import annotations

import json
import math
import shutil
import struct
import subprocess
import textwrap
from pathlib import Path
from typing import Any

import pytest
import yaml

jsonschema = pytest.importorskip("jsonschema", reason="the schema tests check it with the reference validator: "
                                                      "pip install -e '.[dev]'")

from pytest_navscenario import ScenarioError, dump_scenario, load_scenario, loads_scenario  # noqa: E402
from pytest_navscenario.scenario import keys as K  # noqa: E402
from pytest_navscenario.scenario import reading  # noqa: E402
from pytest_navscenario.scenario.format import SCENARIO  # noqa: E402
from pytest_navscenario.scenario.json_schema import SCHEMA_FILE, run_only_checks, scenario_schema, schema_text  # noqa: E402
from pytest_navscenario.scenario.modeline import PREFIX, modeline  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = scenario_schema()
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)


def editor_yaml(text: str) -> Any:
    """YAML as an editor's language server and check-jsonschema read it (YAML 1.2, ruamel)."""
    from ruamel.yaml import YAML
    return YAML(typ="safe", pure=True).load(text)


def schema_errors(data: Any) -> list[str]:
    return [f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in VALIDATOR.iter_errors(data)]


# ------------------------------------------------------------------ the schema itself, where it is kept

def test_the_schema_is_a_valid_draft_2020_12_schema():
    jsonschema.Draft202012Validator.check_schema(SCHEMA)
    assert SCHEMA["$schema"] == "https://json-schema.org/draft/2020-12/schema"


def test_the_package_the_project_and_the_command_hold_the_same_schema(tmp_path, capsys):
    from pytest_navscenario.cli.main import main as cli_main
    text = schema_text()
    assert (ROOT / "pytest_navscenario" / "scenario" / SCHEMA_FILE).read_text(encoding="utf-8") == text, \
        "run: navscenario schema -o pytest_navscenario/scenario/scenario-v1.json"
    assert (ROOT / ".navscenario" / SCHEMA_FILE).read_text(encoding="utf-8") == text, \
        "run: navscenario schema -o .navscenario/scenario-v1.json"
    assert cli_main(["schema", "-o", str(tmp_path / "sub" / "s.json")]) == 0
    assert "wrote the scenario schema" in capsys.readouterr().out
    assert (tmp_path / "sub" / "s.json").read_text(encoding="utf-8") == text
    assert cli_main(["schema"]) == 0 and capsys.readouterr().out == text


# ------------------------------------------------------------------ files that must validate

def shipped_files() -> list[Path]:
    return sorted((ROOT / "scenarios").glob("*.yaml")) + sorted((ROOT / "examples" / "scenarios").glob("*.yaml"))


@pytest.mark.parametrize("path", shipped_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_shipped_seeds_and_examples_validate_and_name_the_schema(path):
    text = path.read_text(encoding="utf-8")
    assert schema_errors(editor_yaml(text)) == []
    assert text.splitlines()[0] == modeline(path)          # ../.navscenario/scenario-v1.json
    target = (path.parent / text.splitlines()[0][len(PREFIX):]).resolve()
    assert target == (ROOT / ".navscenario" / SCHEMA_FILE).resolve() and target.is_file()
    load_scenario(path)


def docs_examples() -> dict[str, str]:
    page = (ROOT / "docs" / "reference" / "scenario-format.md").read_text(encoding="utf-8")
    complete = page.split("## A complete example", 1)[1].split("```yaml\n", 1)[1].split("```", 1)[0]
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("<!-- section:scenario-example -->", 1)[1].split("<!-- /section:scenario-example -->")[0]
    return {"scenario-format complete example": complete,
            "README scenario": section.split("```yaml\n", 1)[1].split("```", 1)[0]}


@pytest.mark.parametrize("name", sorted(docs_examples()))
def test_the_docs_examples_validate(name):
    assert schema_errors(editor_yaml(docs_examples()[name])) == []


def test_files_the_search_freezes_and_the_importers_write_validate(tmp_path):
    """A frozen failure (with moving, polygon and mesh obstacles and inserted boxes), a generated
    suite case and imported seeds (a Gazebo world, an Aerialist test): each starts with the
    modeline, validates, and its project gets the schema the modeline names."""
    from pytest_navscenario.cli.main import main as cli_main
    from pytest_navscenario.search.freeze import save_standalone, standalone_scenario
    from pytest_navscenario.search.space import SearchSpace

    project = tmp_path / "project"
    (project / "scenarios" / "meshes").mkdir(parents=True)
    (project / "pyproject.toml").write_text("[project]\nname = 'p'\n")
    shutil.copy(ROOT / "scenarios" / "meshes" / "lathe.stl", project / "scenarios" / "meshes")
    seed_text = (ROOT / "scenarios" / "workshop-irregular.yaml").read_text(encoding="utf-8")
    (project / "scenarios" / "workshop.yaml").write_text(seed_text)
    seed = load_scenario(project / "scenarios" / "workshop.yaml")
    space = SearchSpace(seed, {"insert": 2, "motion_speed": 0.5})
    offsets = [p.hi if p.kind == "flag" else (p.lo + p.hi) / 3 for p in space.params]
    frozen = standalone_scenario(space.apply(offsets), seed, name="frozen-1", description="a frozen failure",
                                 provenance={"seed": seed.name, "offsets": space.as_mapping(offsets)})
    written = project / "navsearch" / "workshop" / "frozen-1.yaml"
    save_standalone(frozen, seed, written)
    assert cli_main(["import", "sdf", str(ROOT / "tests" / "data" / "barn_world_0.world"), "-o",
                     str(project / "imported" / "barn.yaml"), "--start=-2.25,3,90", "--goal=-2.25,13,90"]) == 0
    assert cli_main(["import", "aerialist", str(ROOT / "tests" / "data" / "aerialist_mission1.yaml"), "-o",
                     str(project / "imported" / "aerialist.yaml")]) == 0
    files = [written, project / "imported" / "barn.yaml", project / "imported" / "aerialist.yaml"]
    for path in files:
        text = path.read_text(encoding="utf-8")
        assert text.startswith(PREFIX), path
        assert schema_errors(editor_yaml(text)) == [], path
        target = (path.parent / text.splitlines()[0][len(PREFIX):]).resolve()
        assert target == project / ".navscenario" / SCHEMA_FILE
        assert target.read_text(encoding="utf-8") == schema_text()
        assert load_scenario(path) is not None
    from pytest_navscenario.scenario.model import content_hash
    assert content_hash(load_scenario(written)) == content_hash(frozen)     # the modeline changes nothing


# ------------------------------------------------------------------ broken files: refused by both

BASE = textwrap.dedent("""\
    version: 1
    mission:
      start: {x: 0, y: 0, yaw: 90}
      goal: {x: 0, y: 10, yaw: 90}
    obstacles:
      - {type: box, name: wall, x: 3, y: 5, length: 1, width: 1}
    """)
BROKEN = {
    # type
    "string for a number": BASE.replace("length: 1,", "length: abc,"),
    "quoted number": BASE.replace("x: 3,", "x: '3',"),
    "boolean for a number": BASE.replace("x: 3,", "x: true,"),
    "fractional beams": BASE + "robot: {lidar: {beams: 7.5}}\n",
    "list for a section": BASE + "robot: [1, 2]\n",
    "string for a flag": BASE + "robot: {safety: {enabled: 'no'}}\n",
    "mapping for obstacles": BASE.replace("obstacles:\n  - {type: box, name: wall, x: 3, y: 5, length: 1, width: 1}\n",
                                          "obstacles: {a: 1}\n"),
    "a point of three numbers": BASE + "  - {type: person, motion: {velocity: [1, 2, 3]}, x: 5, y: 5}\n",
    # range
    "negative size": BASE.replace("width: 1}", "width: -1}"),
    "zero size": BASE.replace("length: 1,", "length: 0,"),
    "dropout above 1": BASE + "robot: {lidar: {dropout: 1.5}}\n",
    "no beams": BASE + "robot: {lidar: {beams: 0}}\n",
    "absurd magnitude": BASE.replace("x: 3,", "x: 1.0e+308,"),
    "yaw tolerance above 180": BASE.replace("  goal: {x: 0, y: 10, yaw: 90}\n",
                                            "  goal: {x: 0, y: 10, yaw: 90}\n  goal_tolerance: {yaw: 200}\n"),
    "inverted search range": BASE + "search: {motion_speed: [0.5, -0.5]}\n",
    "search range past its limit": BASE + "search: {obstacle_dx: 5000}\n",
    "too many inserted boxes": BASE + "search: {insert: 100000000}\n",
    "mesh scale of a million": BASE + "  - {type: mesh, file: part.stl, scale: 1000000}\n",
    "a long name": BASE + f"name: {'n' * 201}\n",
    "a polygon of two points": BASE + "  - {type: polygon, points: [[9, 9], [10, 9]]}\n",
    # enum
    "unknown drive": BASE + "robot: {drive: differential}\n",
    "unknown footprint shape": BASE + "robot: {footprint: {shape: circel}}\n",
    "unknown obstacle type": BASE + "  - {type: cylindre, x: 9, y: 9, radius: 1}\n",
    "unknown version": BASE.replace("version: 1", "version: 2"),
    "unknown motion mode": BASE + "  - {type: person, motion: {path: [[5, 5], [6, 6]], mode: pingpong}}\n",
    "unknown compare": BASE + "reference: {file: a.csv, compare: space}\n",
    # unknown or misplaced keys
    "unknown top-level key": BASE + "obstacels: []\n",
    "unknown nested key": BASE + "robot: {lidar: {beam: 3}}\n",
    "key of another obstacle type": BASE + "  - {type: cylinder, x: 9, y: 9, radius: 1, yaw: 3}\n",
    "key of another shape": BASE + "robot: {footprint: {shape: box, radius: 0.3}}\n",
    "unknown search key": BASE + "search: {obstacle_yw: 5}\n",
    "unknown terrain key": BASE + "terrain: [{type: ramp, x: 5, y: 0, length: 2, width: 1, rise: 0.2, slope: 3}]\n",
    "x beside a motion path": BASE + "  - {type: person, x: 1, motion: {path: [[5, 5], [6, 6]]}}\n",
    "velocity with a path": BASE + "  - {type: person, motion: {path: [[5, 5], [6, 6]], velocity: [1, 0]}}\n",
    "reference with file and points": BASE + "reference: {file: a.csv, points: [[0, 0, 0]]}\n",
    # missing
    "no mission": "version: 1\n",
    "no goal": BASE.replace("  goal: {x: 0, y: 10, yaw: 90}\n", ""),
    "box without a length": BASE.replace("length: 1, ", ""),
    "an obstacle without a type": BASE + "  - {x: 9, y: 9, radius: 1}\n",
}


@pytest.mark.parametrize("name", sorted(BROKEN))
def test_a_file_the_loader_refuses_the_schema_refuses_too(tmp_path, name):
    _write_part(tmp_path / "part.stl")
    path = tmp_path / "broken.yaml"
    path.write_text(BROKEN[name])
    with pytest.raises(ScenarioError):
        load_scenario(path)
    assert schema_errors(editor_yaml(BROKEN[name])), f"the schema accepts what the loader refuses: {name}"


def test_check_jsonschema_refuses_them_in_ci_as_the_docs_say(tmp_path):
    """The docs' one-line CI command, run for real: shipped files pass, a broken one fails with
    its file and the field."""
    exe = shutil.which("check-jsonschema")
    if exe is None:
        pytest.skip("check-jsonschema is not installed (pip install check-jsonschema; it is in the dev extra)")
    schema = ROOT / ".navscenario" / SCHEMA_FILE
    ok = subprocess.run([exe, "--schemafile", str(schema), *map(str, shipped_files())], capture_output=True, text=True)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    (tmp_path / "bad.yaml").write_text(BROKEN["unknown nested key"])
    bad = subprocess.run([exe, "--schemafile", str(schema), str(tmp_path / "bad.yaml")], capture_output=True, text=True)
    assert bad.returncode == 1 and "bad.yaml" in bad.stdout and "'beam' was unexpected" in bad.stdout


def _write_part(path: Path) -> None:
    """The files the probes name, beside the probe: a tetrahedron STL (``path``), the small MJCF
    robot of the body tests as robot.xml, and the heightfield file their heightfield elements read
    (the declared example's path)."""
    (path.parent / "robot.xml").write_text((Path(__file__).parents[1] / "data" / "mjcf" / "cart.xml").read_text())
    import numpy as np
    from PIL import Image
    for grid in (path.parent / "ground" / "yard.png", path.parent / "ground.png"):
        grid.parent.mkdir(exist_ok=True)
        Image.fromarray(np.arange(25, dtype=np.uint8).reshape(5, 5)).save(grid)
    v = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    faces = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (2, 0, 3)]
    with open(path, "wb") as fh:
        fh.write(b"\0" * 80 + struct.pack("<I", len(faces)))
        for a, b, c in faces:
            fh.write(struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *v[i]) for i in (a, b, c)) + b"\0\0")
    # an MJCF body's file (robot.body.file: the loader reads its bytes; MuJoCo reads it at run time)
    (path.parent / "robot.xml").write_text("<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body>"
                                           "</worldbody></mujoco>\n")


# ------------------------------------------------------------------ every key: the same verdict

# A valid document for each section, with a place to put one key: (section path, document, where).
def _sample(key: K.Key, folder: Path) -> Any:
    """A value the loader accepts for ``key`` in an otherwise valid scenario."""
    if isinstance(key, K.Number):
        low, high = key.span
        return min(max(1.0, low + 1.0 if key.low_open else low), high) if not key.example else \
            float(key.example.split(":")[1])
    if isinstance(key, K.Integer):
        return max(key.ge, min(3, key.le))
    if isinstance(key, K.Choice):
        return key.options[-1]
    if isinstance(key, K.Text):
        if key.path:
            return "part.stl" if key.example.endswith(".stl") else "ground.png" if ".png" in key.example else \
                "robot.xml" if ".xml" in key.example else "a.csv"
        return "mypkg.mod:Controller" if key.name == "controller" else "label"
    if isinstance(key, K.Flag):
        return False
    if isinstance(key, K.Points):
        return [[5.0, 5.0], [6.0, 5.0], [6.0, 6.0]][:max(key.min, 2)]
    if isinstance(key, K.Point):
        return [0.5, 0.0]
    return None


def _section_doc(sec: K.Section, folder: Path, *, element: str | None = None) -> dict[str, Any]:
    doc: dict[str, Any] = {"type": element} if element else {}
    for key in sec.keys:
        if key.required:
            doc[key.name] = _sample(key, folder)
    return doc


def _places(folder: Path):
    """(label, section, build) for every section: ``build({key: value})`` is a scenario (plain
    data) holding that section with its required keys sampled, plus ``{key: value}``."""
    def top(extra: dict[str, Any]) -> dict[str, Any]:
        return {"version": 1, "mission": {"start": {"x": 0, "y": 0}, "goal": {"x": 0, "y": 10}},
                "simulation": {"timestep": 0.001}, **extra}

    from pytest_navscenario.scenario.model import (FOOTPRINT, GOAL_TOLERANCE, LATENCY, LIDAR, LIMITS, LOCALISATION,
                                                   MISSION, MOTION, OBSTACLES, POSE, REFERENCE, SAFETY, SIMULATION)
    from pytest_navscenario.scenario.search_keys import SEARCH
    from pytest_navscenario.scenario.terrain import BODY, LIDAR3D, TERRAIN

    def place(label, sec, wrap, element=None, exclusive=(), **extra):
        base = {**_section_doc(sec, folder, element=element), **extra}

        def build(d):       # of keys that exclude each other, the probed one replaces the base's
            kept = {k: v for k, v in base.items() if not (k in exclusive and set(exclusive) & set(d))}
            return wrap({**kept, **d})
        return label, sec, build

    start_goal = {"start": {"x": 0, "y": 0}, "goal": {"x": 0, "y": 10}}
    yield "top", SCENARIO, lambda d: {**top({}), **d}
    for name, sec in (("footprint", FOOTPRINT), ("limits", LIMITS), ("lidar", LIDAR), ("safety", SAFETY),
                      ("localisation", LOCALISATION), ("latency", LATENCY), ("lidar3d", LIDAR3D)):
        yield place(f"robot.{name}", sec, (lambda name: lambda d: top({"robot": {name: d}}))(name))
    yield place("robot", SCENARIO["robot"].section, lambda d: top({"robot": d}))
    yield place("mission", MISSION, lambda d: top({"mission": {**start_goal, **d}}), **start_goal)
    yield place("mission.start", POSE, lambda d: top({"mission": {"start": d, "goal": {"x": 0, "y": 10}}}))
    yield place("mission.goal_tolerance", GOAL_TOLERANCE, lambda d: top({"mission": {**start_goal, "goal_tolerance": d}}))
    yield place("simulation", SIMULATION, lambda d: top({"simulation": d}), timestep=0.001)
    yield place("reference", REFERENCE, lambda d: top({"reference": d}), exclusive=("file", "points"), file="a.csv")
    yield place("search", SEARCH, lambda d: top({"obstacles": [{"type": "box", "name": "crate", "x": 50, "y": 5,
                                                                  "length": 1, "width": 1}], "search": d}))
    for element in OBSTACLES.types:
        extra = {"x": 50.0, "y": 50.0} if "x" in element.section.names else {}
        yield place(f"obstacles[] ({element.type})", element.section, lambda d: top({"obstacles": [d]}),
                    element=element.type, **extra)
    yield place("obstacles[].motion", MOTION, lambda d: top({"obstacles": [{"type": "box", "length": 1, "width": 1,
                                                                             "motion": d}]}),
                path=[[50, 50], [60, 50]])
    for element in TERRAIN.types:
        yield place(f"terrain[] ({element.type})", element.section,
                    lambda d: top({"terrain": [d], "robot": {"body": {"type": "legged"}}}),
                    element=element.type, x=50.0, y=50.0)
    for element in BODY.types:
        yield place(f"robot.body ({element.type})", element.section,
                    lambda d: top({"robot": {"body": d, "drive": "diff"}}), element=element.type)


# Refusals by rules across keys, which no schema can say (each is listed by run_only_checks(),
# and the reference page's "checks that need a run"): the loader's messages for them.
RUN_ONLY = ("must be greater than", "must not be below", "physics steps", "whole number of control periods",
            "not shorter than the timeout", "overlaps obstacle", "so at most that many can be removed",
            "could pass the limit", "or mission part of this seed", "has no length",
            "does not increase", "does not exist", "unknown mesh format", "leaves the scenario's folder",
            "is an absolute path", "is not a file", "cannot be read",
            "is faster than the simulation can follow",   # a mover's speed against its size, the robot's, the timestep
            # a heightfield's file and its stretch, a rough patch's grid (scenario/ground/heightmap.py)
            "unknown heightfield format", "in the proportion of its columns and rows", "needs a grid of",
            # a wheeled body's wheels against its footprint, its mass centre against its limits (scenario/ground/chassis.py)
            "leave no track", "stick out of", "no room for ball casters", "do not fit one behind the other",
            "would tip over", "would roll over",
            # an obstacle's z against the ground under it (scenario/ground.obstacle_problem)
            "above the ground under it", "lies under the ground", "the planar body's world is a flat floor",
            # a 3D lidar's rays a scan and its record over the episode (loader._check_lidar3d)
            "rays a scan, more than the limit", "ranges (float32) would record")


def _probes(key: K.Key) -> list[Any]:
    """Values at and beyond the key's limits, of other types, and null."""
    wrong = ["abc", True, [1.5], {"a": 1}, None]
    if isinstance(key, K.Number):
        low, high = key.span
        out = [low, high, high + 1.0, 2e6, -2e6, 3]
        out += [low - 1e-3] if not key.low_open else [low + 1e-3]
        return out + wrong
    if isinstance(key, K.Integer):
        return [key.ge, key.le, key.ge - 1, key.le + 1, 2.5, 3.0, "3"] + wrong
    if isinstance(key, K.Choice):
        return list(key.options) + ["nope", 1] + wrong
    if isinstance(key, K.Flag):
        return [True, False, 1, "true", None]
    if isinstance(key, K.Text):
        return ["", "  ", "ok_name", "n" * 201, "a\nb", "a/b", "..", "a\x00b", 5, None, ["x"]]
    if isinstance(key, K.Range):
        return [0, 0.5, key.limit, key.limit + 1, -1, [-0.5, 0.5], [0, 0], [0.5, -0.5], [0.1, 0.5], [-key.limit, 0],
                [-key.limit - 1, 0], [1, 2, 3], "x", None]
    if isinstance(key, K.SizeRange):
        return [0.5, [0.3, 1.0], [0, 1], key.le, key.le + 1, [1, 2, 3], "x", None]
    if isinstance(key, K.Points):
        return [[[5, 5], [6, 5], [6, 6]], [[5, 5]], [[5, 5], [6]], "x", None]
    if isinstance(key, K.Point):
        return [[0.5, 0], [1, 2, 3], [1], "x", None]
    if isinstance(key, K.Scale):
        return [0.5, [1, 1, 2], [1, 1], key.le, key.le + 1, 0, None, "x"]
    if isinstance(key, K.Names):
        return [["start"], "goal", [], 3, None]
    if isinstance(key, K.Rows):
        return [[[0, 0, 0], [1, 1, 1]], [[0, 0]], "x", None]
    if isinstance(key, (K.Sub, K.Variant)):
        return [{}, None, "x", 3, {"zz_unknown": 1}]
    if isinstance(key, (K.Listed, K.Elements, K.Marks)):
        return [[], None, "x"]
    if isinstance(key, K.Free):
        return [{}, {"a": [1, "b"]}, None, "x", [1]]
    return [None]


def _loader_verdict(data: dict[str, Any], folder: Path) -> tuple[bool, str | None]:
    path = folder / "probe.yaml"
    path.write_text(yaml.safe_dump(data, allow_unicode=True))
    try:
        load_scenario(path)
    except ScenarioError as exc:
        return False, str(exc)
    return True, ""


def test_for_every_key_the_schema_and_the_loader_give_the_same_verdict(tmp_path):
    """Each declared key of each section, probed in an otherwise valid scenario: accepted by the
    loader if and only if accepted by the schema. A probe the loader refuses by a rule across keys
    (RUN_ONLY: timestep × control_rate, a mesh file that is not there ...) is what needs a run, not
    the key's own verdict, and is left out; they must stay a minority."""
    _write_part(tmp_path / "part.stl")
    disagreements, probed, across = [], 0, 0
    for label, sec, build in _places(tmp_path):
        if label == "top":
            continue        # the top level's keys are probed below through their sections
        for key in sec.keys:
            for value in _probes(key):
                data = build({key.name: value})
                ok, message = _loader_verdict(data, tmp_path)
                if not ok and any(fragment in message for fragment in RUN_ONLY):
                    across += 1
                    continue
                probed += 1
                schema_ok = not schema_errors(json.loads(json.dumps(data)))
                if schema_ok != ok:
                    disagreements.append(f"{label}.{key.name} = {value!r}: loader {'accepts' if ok else 'refuses'}"
                                         f", schema {'accepts' if schema_ok else 'refuses'}")
        unknown = build({"zz_unknown_key": 1})
        assert not _loader_verdict(unknown, tmp_path)[0] and schema_errors(unknown), f"{label}: unknown key"
    assert not disagreements, "\n".join(disagreements)
    assert probed > 1500 and across < probed / 10, (probed, across)


def _schema_node(node: dict[str, Any]) -> dict[str, Any]:
    while "$ref" in node:
        node = SCHEMA["$defs"][node["$ref"].rsplit("/", 1)[1]]
    for branch in node.get("anyOf", []):
        if branch.get("type") != "null":
            return _schema_node(branch)
    return node


def _schema_object(path: str, data: dict[str, Any]) -> dict[str, Any]:
    """The schema object that describes the mapping at ``path`` (``robot.lidar``,
    ``obstacles[0].motion``) of ``data``, following $refs and typed branches."""
    node, value = _schema_node(SCHEMA), data
    for part in path.replace("]", "").replace("[", ".").split(".") if path else []:
        if part.isdigit():
            node, value = _schema_node(node["items"]), value[int(part)]
        else:
            node, value = _schema_node(node["properties"][part]), value[part]
        if "allOf" in node and isinstance(value, dict) and "type" in value and "properties" in node and \
                list(node["properties"]) == ["type"]:
            branch = next(b for b in node["allOf"] if b["if"]["properties"]["type"]["const"] == value["type"])
            node = _schema_node(branch["then"])
    return node


def test_every_set_of_keys_the_loader_reads_is_the_schemas_with_the_same_defaults(tmp_path, monkeypatch):
    """While every section is read (each with its keys at their defaults), each key set the loader
    accepts in a mapping is exactly the schema's set of properties there, and each value the loader
    fills in for an absent key is the schema's default."""
    _write_part(tmp_path / "part.stl")
    seen: list[tuple[str, tuple[str, ...]]] = []
    original = reading.SectionReader.__init__

    def record(self, ctx, node, path, keys, **kw):
        original(self, ctx, node, path, keys, **kw)
        seen.append((path, tuple(keys)))
    monkeypatch.setattr(reading.SectionReader, "__init__", record)
    checked = 0
    for label, sec, build in _places(tmp_path):
        seen.clear()
        data = build({})
        path = tmp_path / "probe.yaml"
        path.write_text(yaml.safe_dump(data))
        scenario = load_scenario(path)
        for where, keys in seen:
            node = _schema_object(where, data)
            allowed = set(node["properties"])
            assert set(keys) == allowed, f"{where}: loader {sorted(set(keys) - allowed)} / schema {sorted(allowed - set(keys))}"
            checked += 1
        if label in ("top", "search"):
            continue
        value = _loaded(scenario, label)
        for key in sec.keys:
            default = _schema_object_for(label, data)["properties"][key.name].get("default", "—")
            if default == "—" or key.name in data_of(label, data):
                continue
            got = getattr(value, key.field)
            got = list(got) if isinstance(got, tuple) else got
            assert got == default or (isinstance(got, float) and math.isclose(got, default)), \
                f"{label}.{key.name}: loaded {got!r}, schema default {default!r}"
    assert checked >= 25


def data_of(label: str, data: dict[str, Any]) -> dict[str, Any]:
    return _walk_data(label, data)


def _walk_data(label: str, data: dict[str, Any]) -> dict[str, Any]:
    route = {"robot": ("robot",), "mission": ("mission",), "mission.start": ("mission", "start"),
             "mission.goal_tolerance": ("mission", "goal_tolerance"), "simulation": ("simulation",),
             "reference": ("reference",), "obstacles[].motion": ("obstacles", 0, "motion")}
    if label.startswith("robot.body"):
        keys: tuple[Any, ...] = ("robot", "body")
    elif label.startswith("robot."):
        keys = ("robot", label.split(".")[1])
    elif label.startswith("obstacles[] ("):
        keys = ("obstacles", 0)
    elif label.startswith("terrain[] ("):
        keys = ("terrain", 0)
    else:
        keys = route[label]
    value: Any = data
    for k in keys:
        value = value[k]
    return value


def _schema_object_for(label: str, data: dict[str, Any]) -> dict[str, Any]:
    path = {"obstacles[].motion": "obstacles[0].motion"}.get(label)
    if path is None:
        path = ("obstacles[0]" if label.startswith("obstacles[] (") else "terrain[0]" if label.startswith("terrain[] (")
                else "robot.body" if label.startswith("robot.body") else label)
    return _schema_object(path, data)


def _loaded(scenario: Any, label: str) -> Any:
    if label.startswith("obstacles[] ("):
        return scenario.obstacles[0]
    if label == "obstacles[].motion":
        return scenario.obstacles[0].motion
    if label.startswith("terrain[] ("):
        return scenario.terrain[0]
    if label.startswith("robot.body"):
        return scenario.robot.body
    value = scenario
    for part in label.split("."):
        value = getattr(value, part)
    return value


def test_what_needs_a_run_is_listed_from_the_declarations():
    rules = [rule for _, rule in run_only_checks()]
    assert any("edges do not cross" in r for r in rules) and any("clear of obstacles" in r for r in rules)
    assert any("mesh file" in r for r in rules) and any("range_max is greater" in r for r in rules)


def test_the_modeline_changes_neither_meaning_nor_hash(tmp_path):
    from pytest_navscenario.scenario.dump import save_scenario
    from pytest_navscenario.scenario.model import content_hash
    s = loads_scenario(BASE, name="b", family=tmp_path.name)
    save_scenario(s, tmp_path / "b.yaml")
    text = (tmp_path / "b.yaml").read_text()
    assert text == modeline(tmp_path / "b.yaml") + "\n" + dump_scenario(s)
    assert text.startswith("# yaml-language-server: $schema=.navscenario/scenario-v1.json\n")  # no project: beside it
    back = load_scenario(tmp_path / "b.yaml")
    assert back == s and content_hash(back) == content_hash(s)
    assert not (tmp_path / ".navscenario").exists()         # the library writes no schema into a bare folder
