"""Scenario YAML loading, validation and dumping: the behaviour users and other modules rely on."""
from __future__ import annotations

import dataclasses
import datetime
import math
import textwrap

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pytest_navscenario import ScenarioError, dump_scenario, load_scenario, loads_scenario
from pytest_navscenario.scenario.loader import SCENARIO_LIMITS, check_scenario, looks_like_scenario, resolve_path, scenario_from_dict
from pytest_navscenario.scenario.dump import save_scenario, scenario_to_dict
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle, Footprint, GoalTolerance, Lidar, Limits, Mark, Mission, Pose, Reference, Robot, Safety, Scenario, Simulation

GOOD = textwrap.dedent("""\
    version: 1
    description: two boxes across the path
    marks: [slow, {xfail: {reason: "known"}}, {skip: "why"}, {mymark: [arg1, 2]}]
    robot:
      footprint: {shape: box, length: 0.9, width: 0.5}
      drive: diff
      lidar: {beams: 36, noise_sigma: 0.01, dropout: 0.1}
    mission:
      start: {x: 0, y: 0, yaw: 90}
      goal: {x: 0, y: 10, yaw: 90}
      waypoints:
        - {x: 0, y: 5}
      goal_tolerance: {position: 0.25, yaw: 10}
      timeout: 40
    obstacles:
      - {type: box, x: -1.5, y: 5, length: 1, width: 1}
      - {type: box, x: 1.5, y: 5, length: 1, width: 1, yaw: 1e1}
      - {type: cylinder, name: box2, x: 4, y: 5, radius: 0.5}
      - {type: box, x: 7, y: 5, length: 1, width: 1}
    simulation: {timestep: 0.01, control_rate: 20, seed: 3}
    reference: {file: runs/boxes1.csv}
    search: {obstacle_dx: 0.5, motion_speed: [-0.2, 0.3], frozen: [box2], insert: 1}
    """)


@pytest.fixture
def good_file(tmp_path):
    path = tmp_path / "paper" / "boxes1.yaml"
    path.parent.mkdir()
    path.write_text(GOOD)
    return path


def test_load_reads_every_section_with_defaults_and_yaml_units(good_file):
    s = load_scenario(good_file)
    assert (s.name, s.family, s.source) == ("boxes1", "paper", str(good_file))
    assert s.robot.drive == "diff" and s.robot.lidar == Lidar(beams=36, noise_sigma=0.01, dropout=0.1)
    assert s.robot.limits == Limits() and s.robot.safety == Safety()
    assert s.mission.start == Pose(0.0, 0.0, 90.0) and s.mission.waypoints == (Pose(0.0, 5.0),)
    assert s.mission.goal_tolerance == GoalTolerance(0.25, 10.0) and s.mission.timeout == 40.0
    assert all(type(v) is float for v in (s.mission.start.x, s.obstacles[0].length, s.mission.timeout))
    assert s.obstacles[1].yaw == 10.0  # unquoted 1e1 is a number, although YAML 1.1 calls it a string
    assert s.simulation == Simulation(0.01, 20.0, 3)
    assert s.reference == Reference(file="runs/boxes1.csv")
    assert resolve_path(s, s.reference.file) == good_file.parent / "runs" / "boxes1.csv"
    assert s.search == {"obstacle_dx": 0.5, "motion_speed": [-0.2, 0.3], "frozen": ["box2"], "insert": 1}
    assert s.marks == (Mark("slow"), Mark("xfail", kwargs={"reason": "known"}), Mark("skip", ("why",)),
                       Mark("mymark", ("arg1", 2)))


def test_unnamed_obstacles_get_stable_names_that_never_clash(good_file):
    s = load_scenario(good_file)
    # box1, then box2 is taken by the named cylinder, so the next boxes are box3 and box4
    assert [o.name for o in s.obstacles] == ["box1", "box3", "box2", "box4"]
    assert s.obstacle("box2") == CylinderObstacle("box2", 4.0, 5.0, 0.5)


def test_name_and_family_in_yaml_win_over_file_defaults(tmp_path):
    path = tmp_path / "f.yaml"
    path.write_text(GOOD + "name: mine\nfamily: fam\n")
    s = load_scenario(path)
    assert (s.name, s.family) == ("mine", "fam")
    assert loads_scenario(GOOD, name="n", family="f").name == "n"
    assert loads_scenario(GOOD + "name:\n", name="n").name == "n"  # an empty value counts as absent


def test_dump_round_trip_is_exact_and_dump_is_stable(good_file, tmp_path):
    s = load_scenario(good_file)
    text = dump_scenario(s)
    again = loads_scenario(text, str(good_file))
    assert again == s
    assert dump_scenario(again) == text
    assert "!!" not in text and text.startswith("version: 1\nname: boxes1\nfamily: paper\n")
    out = tmp_path / "out" / "copy.yaml"
    save_scenario(s, out)
    assert load_scenario(out) == s
    assert [p.name for p in out.parent.iterdir()] == ["copy.yaml"]  # no temporary file left behind


def test_dump_key_order_and_plain_types():
    s = loads_scenario(GOOD, name="x")
    d = scenario_to_dict(s)
    assert list(d) == ["version", "name", "description", "marks", "robot", "mission", "obstacles",
                       "simulation", "reference", "search"]
    assert list(d["obstacles"][0]) == ["type", "name", "x", "y", "length", "width", "yaw", "height"]
    assert yaml.safe_load(dump_scenario(s)) == d


def test_dump_accepts_numpy_numbers_from_generated_scenarios():
    s = Scenario(mission=Mission(start=Pose(np.float64(0.1), np.float64(0.2)), goal=Pose(0, 10)),
                 obstacles=(BoxObstacle("b", np.float64(3.0), np.float32(4.5), 1.0, 1.0),),
                 provenance={"clearance": np.float64(0.125), "seed": np.int64(7), "offsets": np.array([0.5, 1.0]),
                             "date": datetime.date(2026, 11, 21)})
    back = loads_scenario(dump_scenario(s))
    assert type(back.mission.start.x) is float and back.obstacles == s.obstacles
    assert back.provenance == {"clearance": 0.125, "seed": 7, "offsets": [0.5, 1.0], "date": "2026-11-21"}


def test_from_dict_and_to_dict_are_inverse():
    s = loads_scenario(GOOD)
    assert scenario_from_dict(scenario_to_dict(s)) == s


def test_check_scenario_catches_problems_in_scenarios_built_in_code():
    base = Scenario(mission=Mission(start=Pose(0, 0), goal=Pose(0, 10)))
    check_scenario(base)
    blocked = dataclasses.replace(base, obstacles=(CylinderObstacle("pillar", 0.1, 10.0, 0.5),))
    with pytest.raises(ScenarioError, match="goal .* overlaps obstacle 'pillar'"):
        check_scenario(blocked)


def test_looks_like_scenario():
    assert looks_like_scenario(GOOD) and looks_like_scenario(GOOD.encode())
    assert looks_like_scenario({"version": 1, "mission": {}})
    assert not looks_like_scenario("name: ci\non: push\njobs: {}\n")
    assert not looks_like_scenario({"version": 1})
    assert not looks_like_scenario("  version: 1\n  mission: {}\n")  # nested, not top level
    assert not looks_like_scenario("version: '3'\nservices: {}\n")  # docker-compose and friends
    # a scenario with a typo is still recognised, so the collector reports it instead of skipping it
    assert looks_like_scenario("version: 1\nmision:\n  start: {x: 0, y: 0}\n")


# ------------------------------------------------------------------ bad input: file, line, field, fix

BASE = textwrap.dedent("""\
    version: 1
    mission:
      start: {x: 0, y: 0, yaw: 90}
      goal: {x: 0, y: 10, yaw: 90}
    obstacles:
      - {type: box, name: wall, x: 3, y: 5, length: 1, width: 1}
    """)

BAD = [
    # (id, text, line, field, fragments of the message)
    ("syntax", BASE + "robot: {drive: omni\n", 8, None, ["invalid YAML", "column"]),
    ("top-level-list", "- 1\n- 2\n", 1, None, ["top level must be a mapping", "a list"]),
    ("top-level-scalar", "hello\n", 1, None, ["top level must be a mapping", "'hello'"]),
    ("empty", "", 1, None, ["empty", "version: 1"]),
    ("comments-only", "# nothing\n\n", 1, None, ["empty"]),
    ("version", BASE.replace("version: 1", "version: 2"), 1, "version",
     ["unsupported version 2", "reads version(s) 1"]),
    ("no-version", BASE.replace("version: 1\n", ""), 1, "version", ["missing required field 'version'"]),
    ("unknown-top", BASE + "obstacels: []\n", 7, "obstacels", ["unknown key", "did you mean 'obstacles'?"]),
    ("unknown-nested", BASE + "robot:\n  lidar: {beam: 3}\n", 8, "robot.lidar.beam",
     ["unknown key 'beam'", "did you mean 'beams'?"]),
    ("wrong-type", BASE.replace("length: 1,", "length: abc,"), 6, "obstacles[0].length",
     ["expected a number, got 'abc'"]),
    ("quoted-number", BASE.replace("x: 3,", "x: '3',"), 6, "obstacles[0].x", ["expected a number, got '3'"]),
    ("bool-number", BASE.replace("x: 3,", "x: true,"), 6, "obstacles[0].x", ["expected a number, got true"]),
    ("missing-goal", BASE.replace("  goal: {x: 0, y: 10, yaw: 90}\n", ""), 2, "mission.goal",
     ["missing required field 'goal'"]),
    ("missing-mission", "version: 1\n", 1, "mission", ["missing required field 'mission'"]),
    ("missing-x", BASE.replace("start: {x: 0, ", "start: {"), 3, "mission.start.x", ["missing required field 'x'"]),
    ("negative-size", BASE.replace("width: 1}", "width: -1}"), 6, "obstacles[0].width", ["must be > 0, got -1.0"]),
    ("zero-size", BASE.replace("length: 1,", "length: 0,"), 6, "obstacles[0].length", ["must be > 0"]),
    ("nan", BASE.replace("x: 3,", "x: .nan,"), 6, "obstacles[0].x", ["finite", ".nan"]),
    ("inf", BASE.replace("yaw: 90}\nobstacles", "yaw: 90}\n  timeout: .inf\nobstacles"), 5, "mission.timeout",
     ["finite", ".inf"]),
    ("absurd", BASE.replace("x: 3,", "x: 1.0e+308,"), 6, "obstacles[0].x", ["beyond the supported magnitude"]),
    ("start-in-obstacle", BASE.replace("x: 3, y: 5", "x: 0.2, y: 0.4"), 3, "mission.start",
     ["start", "overlaps obstacle 'wall'", "move the start"]),
    ("goal-in-obstacle", BASE.replace("x: 3, y: 5", "x: 0, y: 9.5"), 4, "mission.goal",
     ["goal", "overlaps obstacle 'wall'"]),
    ("waypoint-in-obstacle", BASE.replace("  goal:", "  waypoints: [{x: 0, y: 1}, {x: 3.2, y: 5}]\n  goal:"), 4,
     "mission.waypoints[1]", ["waypoint 1", "overlaps obstacle 'wall'"]),
    ("steps", BASE + "simulation:\n  timestep: 0.01\n  control_rate: 30\n", 9, "simulation.control_rate",
     ["3.333 physics steps", "whole number", "control_rate: 33.3333"]),
    ("beams", BASE + "robot:\n  lidar:\n    beams: 0\n", 9, "robot.lidar.beams", ["between 1 and"]),
    ("beams-float", BASE + "robot:\n  lidar:\n    beams: 7.5\n", 9, "robot.lidar.beams", ["whole number"]),
    ("dropout", BASE + "robot:\n  lidar:\n    dropout: 1.5\n", 9, "robot.lidar.dropout", ["must be <= 1"]),
    ("drive", BASE + "robot:\n  drive: differential\n", 8, "robot.drive", ["unknown drive", "did you mean 'diff'?"]),
    ("shape", BASE + "robot:\n  footprint: {shape: circel}\n", 8, "robot.footprint.shape",
     ["unknown shape", "did you mean 'circle'?"]),
    ("shape-key", BASE + "robot:\n  footprint: {shape: box, radius: 0.3}\n", 8, "robot.footprint.radius",
     ["'radius' does not apply to shape: box"]),
    ("obstacle-type", BASE + "  - {type: cylindre, x: 9, y: 9, radius: 1}\n", 7, "obstacles[1].type",
     ["unknown obstacle type 'cylindre'", "did you mean 'cylinder'?"]),
    ("obstacle-key", BASE + "  - {type: cylinder, x: 9, y: 9, radius: 1, yaw: 3}\n", 7, "obstacles[1].yaw",
     ["'yaw' does not apply to type: cylinder", "set type: box"]),
    ("obstacle-typo", BASE + "  - {type: cylinder, x: 9, y: 9, radius: 1, hieght: 3}\n", 7, "obstacles[1].hieght",
     ["unknown key 'hieght'", "did you mean 'height'?"]),
    ("duplicate-name", BASE + "  - {type: cylinder, name: wall, x: 9, y: 9, radius: 1}\n", 7, "obstacles[1].name",
     ["'wall' is already used by obstacles[0]", "unique"]),
    ("duplicate-key", BASE + "version: 1\n", 7, None, ["key 'version' is given twice (first on line 1)"]),
    ("range", BASE + "robot:\n  lidar: {range_min: 2, range_max: 1}\n", 8, "robot.lidar.range_max",
     ["greater than range_min"]),
    ("reference-both", BASE + "reference:\n  file: a.csv\n  points: [[0, 0, 0]]\n", 7, "reference",
     ["exactly one of 'file' or 'points'"]),
    ("reference-time", BASE + "reference:\n  points:\n  - [0, 0, 0]\n  - [0, 1, 1]\n", 10, "reference.points[1][0]",
     ["does not increase"]),
    ("reference-compare", BASE + "reference:\n  file: a.csv\n  compare: space\n", 9, "reference.compare",
     ["unknown compare 'space'", "use one of: time, path"]),
    ("mark", BASE + "marks: ['not valid']\n", 7, "marks[0]", ["not a valid Python identifier"]),
    ("name-path", BASE + "name: ../../etc/x\n", 7, "name", ["become file and folder names"]),
    ("family-path", BASE + "family: ..\n", 7, "family", ["become file and folder names"]),
    ("section-type", BASE + "robot: fast\n", 7, "robot", ["expected the robot settings", "'fast'"]),
    ("obstacles-type", BASE.replace("obstacles:\n  - {type: box, name: wall, x: 3, y: 5, length: 1, width: 1}\n",
                                    "obstacles: {a: 1}\n"), 5, "obstacles", ["expected a list of obstacles"]),
    ("date-in-free-data", BASE + "provenance:\n  found: 2024-01-31\n", 8, "provenance.found",
     ["a date value is not supported in free-form data", "quote it"]),
    ("python-tag", BASE + "search: !!python/object/apply:os.system ['true']\n", 7, None, ["unsupported YAML tag"]),
    ("two-documents", BASE + "---\nversion: 1\n", 7, None, ["more than one YAML document"]),
    ("tab", BASE + "robot:\n\tdrive: omni\n", 8, None, ["invalid YAML", "tabs for indentation"]),
    ("misplaced-key", BASE + "robot:\n  beams: 36\n", 8, "robot.beams", ["belongs under 'robot.lidar'"]),
]


@pytest.mark.parametrize("text,line,field,fragments", [case[1:] for case in BAD], ids=[case[0] for case in BAD])
def test_bad_input_names_file_line_field_and_fix(tmp_path, text, line, field, fragments):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    err = info.value
    message = str(err)
    assert (err.path, err.line, err.field) == (str(path), line, field), message
    assert message.startswith(f"{path}:{line}: " + (f"{field}: " if field else "")), message
    for fragment in fragments:
        assert fragment in message
    assert err.hint, f"no fix hint in: {message}"


def test_from_dict_errors_name_the_field():
    data = scenario_to_dict(loads_scenario(BASE))
    data["obstacles"][0]["length"] = "abc"
    with pytest.raises(ScenarioError, match=r"^obstacles\[0\]\.length: expected a number, got 'abc'"):
        scenario_from_dict(data)
    with pytest.raises(ScenarioError, match="expected a mapping"):
        scenario_from_dict([1, 2])  # type: ignore[arg-type]


def test_limits_are_documented_numbers():
    assert SCENARIO_LIMITS["max_obstacles"] == 5000 and SCENARIO_LIMITS["max_abs_value"] == 1e6
    with pytest.raises(TypeError):
        SCENARIO_LIMITS["max_obstacles"] = 1  # type: ignore[index]


# ------------------------------------------------------------------ Hypothesis round trip

finite = st.floats(-1000, 1000, allow_nan=False, allow_subnormal=False)
positive = st.floats(0.001, 100, allow_nan=False, allow_subnormal=False)
names = st.text(st.characters(codec="utf-8", categories=("L", "N", "P", "S", "Zs")), min_size=1,
                max_size=12).filter(str.strip)
file_names = names.filter(lambda t: not set(t) & set("/\\") and t.strip() not in (".", ".."))


@st.composite
def scenarios(draw):
    box = st.builds(BoxObstacle, name=st.just(""), x=st.floats(300, 500, allow_subnormal=False), y=finite,
                    length=positive, width=positive, yaw=finite, height=positive)
    cyl = st.builds(CylinderObstacle, name=st.just(""), x=st.floats(300, 500, allow_subnormal=False), y=finite,
                    radius=positive, height=positive)
    obstacles = draw(st.lists(st.one_of(box, cyl), max_size=4))
    obstacles = tuple(dataclasses.replace(o, name=f"o{i}") for i, o in enumerate(obstacles))
    pose = st.builds(Pose, st.floats(-20, 20, allow_subnormal=False), finite, finite)
    footprint = st.one_of(st.builds(Footprint, st.just("box"), positive, positive),
                          st.builds(Footprint, st.just("circle"), radius=positive))
    dt = draw(st.sampled_from([0.01, 0.005, 0.002, 0.001]))
    steps = draw(st.integers(1, 50))
    mark = st.one_of(st.builds(Mark, st.sampled_from(["slow", "nav", "x_1"])),
                     st.builds(Mark, st.just("skip"), st.tuples(names)),
                     st.builds(Mark, st.just("xfail"), kwargs=st.fixed_dictionaries({"reason": names})))
    plain = st.recursive(st.none() | st.booleans() | st.integers(-10**6, 10**6) | finite | names,
                         lambda inner: st.lists(inner, max_size=3) | st.dictionaries(names, inner, max_size=3),
                         max_leaves=8)
    return Scenario(
        version=1, name=draw(file_names), family=draw(st.just("") | file_names), description=draw(st.just("") | names),
        marks=tuple(draw(st.lists(mark, max_size=3))),
        robot=Robot(footprint=draw(footprint), drive=draw(st.sampled_from(["omni", "diff"])),
                    limits=draw(st.builds(Limits, positive, positive, positive, positive, positive)),
                    lidar=Lidar(beams=draw(st.integers(1, 1000)), fov=draw(st.floats(0.5, 360)),
                                range_min=0.05, range_max=draw(st.floats(0.1, 100)),
                                noise_sigma=draw(st.floats(0, 1)), dropout=draw(st.floats(0, 1))),
                    safety=draw(st.builds(Safety, st.booleans(), positive, st.floats(0, 1)))),
        mission=Mission(start=draw(pose), goal=draw(pose), waypoints=tuple(draw(st.lists(pose, max_size=3))),
                        goal_tolerance=GoalTolerance(draw(positive), draw(st.none() | st.floats(1, 180))),
                        waypoint_tolerance=draw(positive), timeout=draw(st.floats(1, 1000))),
        obstacles=obstacles,
        simulation=Simulation(timestep=dt, control_rate=1.0 / (dt * steps), seed=draw(st.integers(0, 2**63 - 1))),
        reference=draw(st.none() | st.builds(Reference, file=names)
                       | st.builds(Reference, points=st.lists(st.tuples(finite, finite), max_size=3).map(
                           lambda rows: tuple((float(i), x, y) for i, (x, y) in enumerate(rows))))),
        search=draw(st.none() | st.fixed_dictionaries({}, optional={   # search: is checked when loaded
            "obstacle_dx": st.floats(0, 5, allow_subnormal=False), "insert": st.integers(0, 5),
            "motion_speed": st.tuples(st.floats(-1, 0, allow_subnormal=False),
                                      st.floats(0, 1, allow_subnormal=False)).map(list),
            "frozen": st.just(["start", "goal"]), "min_size": positive})),
        provenance=draw(st.none() | st.dictionaries(names, plain, max_size=3)),
    )


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenarios())
def test_round_trip_of_generated_scenarios_is_exact(s):
    text = dump_scenario(s)
    back = loads_scenario(text)
    assert back == s
    assert dump_scenario(back) == text
    for a, b in zip(back.obstacles, s.obstacles):  # exact bits, not just ==
        assert math.copysign(1, a.x) == math.copysign(1, b.x) and a.x.hex() == float(b.x).hex()


def test_docs_complete_example_loads_and_round_trips():
    """The complete example of the scenario-format reference page is a valid scenario."""
    from pathlib import Path
    page = Path(__file__).resolve().parents[2] / "docs" / "reference" / "scenario-format.md"
    section = page.read_text(encoding="utf-8").split("## A complete example", 1)[1].split("\n## ", 1)[0]
    example = section.split("```yaml\n", 1)[1].split("```", 1)[0]
    s = loads_scenario(example, str(page))
    assert s.name == "boxes1" and [o.name for o in s.obstacles] == ["left", "cyl1"]
    assert s.mission.goal_tolerance.yaw == 15.0 and s.marks[1].kwargs == {"reason": "known bug #12"}
    assert loads_scenario(dump_scenario(s)) == s


def test_readme_scenario_loads_and_passes_with_the_default_planner():
    """The README's one scenario is valid and, as the README says, the built-in planner passes it."""
    from pathlib import Path
    from pytest_navscenario import Outcome, run_scenario
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
    section = readme.split("<!-- section:scenario-example -->", 1)[1].split("<!-- /section:scenario-example -->")[0]
    example = section.split("```yaml\n", 1)[1].split("```", 1)[0]
    s = loads_scenario(example, "README.md", name="readme")
    assert [o.name for o in s.obstacles] == ["box_left", "box_right"]
    assert loads_scenario(dump_scenario(s)) == s
    assert run_scenario(s).outcome is Outcome.SUCCESS


def test_pure_python_parser_gives_the_same_results(monkeypatch, good_file):
    """Without libyaml (some platforms), the pure-Python parser feeds the same composer."""
    from pytest_navscenario.scenario import yaml_tree
    with_c = load_scenario(good_file)
    monkeypatch.setattr(yaml_tree, "_Loader", yaml.SafeLoader)
    assert load_scenario(good_file) == with_c
    for _, text, line, field, fragments in BAD[:12]:
        with pytest.raises(ScenarioError) as info:
            loads_scenario(text, "bad.yaml")
        assert (info.value.line, info.value.field) == (line, field) and fragments[0] in str(info.value)
    with pytest.raises(ScenarioError, match="levels deep"):
        loads_scenario("version: 1\nmission: " + "[" * 5000 + "]" * 5000)


def test_reference_compare_path_round_trips():
    text = BASE + "reference:\n  points: [[0, 0, 0], [1, 0, 1]]\n  compare: path\n"
    s = loads_scenario(text)
    assert s.reference.compare == "path"
    assert loads_scenario(dump_scenario(s)).reference == s.reference
    plain = loads_scenario(BASE + "reference: {file: a.csv}\n")
    assert plain.reference.compare == "time" and "compare" not in dump_scenario(plain)
