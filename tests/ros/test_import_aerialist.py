"""Issue 15 item 14: ``navscenario import aerialist`` carries over what has a meaning here (the
mission from the QGroundControl plan beside the test, trees as cylinders, a rotation written as
``angle``) and names, with file and line, every key it does not carry over.

tests/data/aerialist_flight.plan is hand-written in QGroundControl's plan format (the layout of
skhatiri/Aerialist's samples/flights/*.plan: takeoff, waypoints, a speed change, landing) around
PX4 SITL's default home."""
from __future__ import annotations

import math
import shutil
from pathlib import Path

import pytest

from pytest_navscenario.cli import main
from pytest_navscenario.ros.qgc_plan import read_plan
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle

DATA = Path(__file__).resolve().parents[1] / "data"
PLAN = DATA / "aerialist_flight.plan"

TEST = """\
robot:
  port: px4_ros
  params_file: samples/flights/mission1-params.csv
  mission_file: samples/flights/flight.plan

simulation:
  simulator: ros
  speed: 1
  headless: true
  obstacles:
  - size: {l: 5, w: 5, h: 5}
    position: {x: -8, y: 3, z: 0, angle: 30}
    shape: BOX
  - size: {l: 1.2, w: 1.2, h: 8}
    position: {x: 4, y: 9, z: 0, r: 0}
    shape: TREE
  - size: {l: 2, w: 1, h: 2}
    position: {x: 6, y: -4, z: 1.5, r: 10}
    colour: red

mission:
  commands_file: samples/flights/mission1-commands.csv

assertion:
  log_file: samples/flights/mission1.ulg
  variable: trajectory
"""


def _enu(lat, lon, lat0=47.3977419, lon0=8.5455938):
    """Local east, north metres by the flat-earth formula (independent of the importer's)."""
    r = 6371000.0
    return (math.radians(lon - lon0) * r * math.cos(math.radians(lat0)), math.radians(lat - lat0) * r)


def test_plan_positions_in_local_metres():
    plan = read_plan(PLAN)
    assert plan.home[:2] == (47.3977419, 8.5455938)
    import json
    items = json.loads(PLAN.read_text())["mission"]["items"]
    want = [_enu(i["params"][4], i["params"][5]) for i in items if i["command"] in (16, 21, 22)]
    assert [(round(x, 2), round(y, 2)) for x, y, _ in plan.points] == \
        [(pytest.approx(x, abs=0.02), pytest.approx(y, abs=0.02)) for x, y in want]
    assert [k for *_, k in plan.points] == ["TAKEOFF", "WAYPOINT", "WAYPOINT", "LAND"]
    assert "command 178" in plan.notes[0] and "command 530" in plan.notes[0]


def _import(tmp_path, capsys, text=TEST, *extra):
    src = tmp_path / "test.yaml"
    src.write_text(text)
    shutil.copy(PLAN, tmp_path / "flight.plan")
    out = tmp_path / "s.yaml"
    rc = main(["import", "aerialist", str(src), "-o", str(out), *extra])
    cap = capsys.readouterr()
    return rc, out, cap.out, cap.err, src


def test_mission_from_the_plan_beside_the_test(tmp_path, capsys):
    rc, out, text, err, src = _import(tmp_path, capsys)
    assert rc == 0, err
    s = load_scenario(out)
    assert (s.mission.start.x, s.mission.start.y) == (0.0, 0.0)
    assert (s.mission.goal.x, s.mission.goal.y) == (pytest.approx(0.0, abs=0.02), pytest.approx(18.0, abs=0.02))
    assert [(round(w.x), round(w.y)) for w in s.mission.waypoints] == [(1, 6), (-1, 12)]
    assert s.mission.start.yaw == pytest.approx(math.degrees(math.atan2(6, 1)), abs=0.5)  # towards waypoint 1
    assert "flight.plan" in text and "x east, y north" in text


def test_tree_rotation_name_and_every_dropped_key_with_its_line(tmp_path, capsys):
    rc, out, text, err, src = _import(tmp_path, capsys)
    s = load_scenario(out)
    box, tree, box3 = s.obstacles
    assert isinstance(box, BoxObstacle) and box.yaw == 30.0           # written as position.angle
    assert tree == CylinderObstacle(name="tree2", x=4.0, y=9.0, radius=0.6, height=8.0)
    assert isinstance(box3, BoxObstacle) and box3.yaw == 10.0
    lines = TEST.splitlines()
    for key, why in [("robot.port", "PX4 connection"), ("robot.params_file", "parameters"),
                     ("simulation.simulator", "MuJoCo"), ("simulation.speed", ""), ("simulation.headless", ""),
                     ("mission.commands_file", ""), ("assertion.log_file", ".ulg"), ("assertion.variable", ""),
                     ("simulation.obstacles[2].colour", "unknown"), ("simulation.obstacles[2].position.z", "ground")]:
        leaf = key.split(".")[-1]
        line = next(i + 1 for i, ln in enumerate(lines) if ln.strip().startswith(f"{leaf}:")
                    or f"{leaf}:" in ln and leaf == "z" and "1.5" in ln)
        hit = [e for e in err.splitlines() if f"{src}:{line}: {key}" in e]
        assert hit and "not carried over" in hit[0] and why in hit[0], (key, line, err)
    assert "10 key(s)" in err
    # the mission file itself and the carried obstacle keys are not reported
    assert "mission_file" not in err and ".shape" not in err and "angle" not in err


def test_missing_plan_is_a_warning_with_the_default_mission(tmp_path, capsys):
    rc, out, text, err, src = _import(tmp_path, capsys, TEST.replace("flight.plan", "elsewhere.plan"))
    assert rc == 0
    assert f"{src}:4: robot.mission_file" in err and "not beside the test" in err
    assert "set --start/--goal" in text
    s = load_scenario(out)
    assert (s.mission.goal.x, s.mission.goal.y) == (0.0, 10.0)


def test_start_and_goal_options_win_over_the_plan(tmp_path, capsys):
    rc, out, *_ = _import(tmp_path, capsys, TEST, "--start=0,-2,90", "--goal=0,20,90")
    s = load_scenario(out)
    assert (s.mission.start.y, s.mission.goal.y, s.mission.waypoints) == (-2.0, 20.0, ())


def test_bad_plan_and_double_rotation(tmp_path, capsys):
    (tmp_path / "flight.plan").write_text("{\n  \"mission\": [\n")
    src = tmp_path / "test.yaml"
    src.write_text(TEST)
    assert main(["import", "aerialist", str(src), "-o", str(tmp_path / "s.yaml")]) == 2
    assert f"{tmp_path / 'flight.plan'}:3: not valid JSON" in capsys.readouterr().err
    src.write_text(TEST.replace("angle: 30", "angle: 30, r: 0"))
    shutil.copy(PLAN, tmp_path / "flight.plan")
    assert main(["import", "aerialist", str(src), "-o", str(tmp_path / "s.yaml")]) == 2
    err = capsys.readouterr().err
    assert f"{src}:12: simulation.obstacles[0].position: the rotation is given twice (r and angle)" in err


def test_home_position_moves_the_start(tmp_path, capsys):
    """simulation.home_position (where the drone starts) 2 m south of the plan's home: the start."""
    lat = 47.3977419 - math.degrees(2.0 / 6371000.0)
    text = TEST.replace("  headless: true\n", f"  headless: true\n  home_position: [{lat:.9f}, 8.5455938, 488.0]\n")
    rc, out, stdout, err, src = _import(tmp_path, capsys, text)
    assert rc == 0, err
    s = load_scenario(out)
    assert (s.mission.start.x, s.mission.start.y) == (pytest.approx(0.0, abs=0.01), pytest.approx(-2.0, abs=0.01))
    assert f"start from simulation.home_position ({src}:10)" in stdout
    assert "simulation.home_position" not in err
    # without a plan it cannot be placed: a warning with its line
    (tmp_path / "noplan").mkdir()
    rc, out, stdout, err, src = _import(tmp_path / "noplan", capsys, text.replace("flight.plan", "elsewhere.plan"))
    assert rc == 0 and f"{src}:10: simulation.home_position: not carried over" in err
