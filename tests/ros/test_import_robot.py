"""Issue 24, the importers' robot and timeout: ``import sdf``, ``import aerialist`` and ``from-map`` take
the robot from ``--robot FILE`` / ``--footprint`` / ``--drive`` instead of always the default 0.9 x
0.5 m box, and derive the timeout from the route's length and the robot's speed (a 53 m mission
no longer keeps the 30 s default that every planner fails)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.cli import main
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.scenario.model import Footprint

DATA = Path(__file__).resolve().parents[1] / "data"
SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def _map(folder: Path) -> Path:
    img = np.full((40, 60), 254, np.uint8)
    img[0, :] = img[-1, :] = img[:, 0] = img[:, -1] = 0
    (folder / "m.pgm").write_bytes(b"P5\n60 40\n255\n" + img.tobytes())
    path = folder / "map.yaml"
    path.write_text("image: m.pgm\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\noccupied_thresh: 0.65\nnegate: 0\n")
    return path


def test_footprint_and_drive_options(tmp_path, capsys):
    out = tmp_path / "barn.yaml"
    assert main(["import", "sdf", str(DATA / "barn_world_0.world"), "--start=-2.25,3,90", "--goal=-2.25,13,90",
                 "--footprint", "box:0.5x0.43", "--drive", "diff", "-o", str(out)]) == 0
    robot = load_scenario(out).robot
    assert robot.footprint == Footprint(shape="box", length=0.5, width=0.43) and robot.drive == "diff"
    assert "robot: a 0.5 x 0.43 m box, diff drive, top speed 1 m/s, from --footprint box:0.5x0.43 and --drive diff" \
        in capsys.readouterr().out


def test_the_robot_of_a_scenario_file(tmp_path, capsys):
    out = tmp_path / "room.yaml"
    assert main(["from-map", str(_map(tmp_path)), "--start=1,1,0", "--goal=5,3,0", "--robot",
                 str(SCENARIOS / "boxes1.yaml"), "--footprint", "circle:0.2", "-o", str(out)]) == 0
    want = load_scenario(SCENARIOS / "boxes1.yaml").robot
    got = load_scenario(out).robot
    assert got.footprint == Footprint(shape="circle", radius=0.2)
    assert (got.drive, got.limits, got.lidar) == (want.drive, want.limits, want.lidar)
    assert "the robot: section of" in capsys.readouterr().out


def test_a_robot_file_error_names_the_users_file_and_line(tmp_path, capsys):
    robot = tmp_path / "jackal.yaml"
    robot.write_text("robot:\n  footprint: {shape: box, length: 0.5, width: 0.43}\n  limits:\n    max_speed: -2\n")
    rc = main(["from-map", str(_map(tmp_path)), "--start=1,1,0", "--goal=5,3,0", "--robot", str(robot),
               "-o", str(tmp_path / "out.yaml")])
    err = capsys.readouterr().err
    assert rc == 2 and f"{robot}:4: robot.limits.max_speed" in err and "/tmp/tmp" not in err


@pytest.mark.parametrize("text", ["square:1", "circle:-1", "box:1", "box:axb", "circle:nan"])
def test_a_bad_footprint_is_a_clear_error(tmp_path, capsys, text):
    rc = main(["from-map", str(_map(tmp_path)), "--start=1,1,0", "--goal=5,3,0", "--footprint", text,
               "-o", str(tmp_path / "out.yaml")])
    err = capsys.readouterr().err
    assert rc == 2 and f"--footprint {text!r}: expected circle:RADIUS or box:LENGTHxWIDTH" in err


def test_a_long_aerialist_mission_gets_a_timeout_it_can_be_driven_in(tmp_path, capsys):
    """A 53 m mission: before, the 30 s default (every planner failed it); now twice the driving time
    at the robot's speed plus 10 s, and the output says so."""
    out = tmp_path / "long.yaml"
    assert main(["import", "aerialist", str(DATA / "aerialist_mission1.yaml"), "--start=0,0,90", "--goal=0,53,90",
                 "-o", str(out)]) == 0
    text = capsys.readouterr().out
    seed = load_scenario(out)
    assert seed.mission.timeout == 116.0
    assert "timeout 116 s: the shortest collision-free route is 53.0 m, 53.0 s at the robot's 1 m/s; 2 times " \
           "that plus 10 s (--timeout to set it)" in text
    assert main(["import", "aerialist", str(DATA / "aerialist_mission1.yaml"), "--start=0,0,90", "--goal=0,53,90",
                 "--timeout", "80", "-o", str(tmp_path / "given.yaml")]) == 0
    assert load_scenario(tmp_path / "given.yaml").mission.timeout == 80.0


@pytest.fixture(scope="module")
def own_bag(tmp_path_factory):
    """A bag this tool wrote (--nav-bag's writer) of dwa on boxes2: its /navscenario/scenario holds
    the run's robot, a 0.9 x 0.5 m box with an omnidirectional drive."""
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.ros.bag_writer import write_episode_bag

    result = run_scenario(load_scenario(SCENARIOS / "boxes2.yaml"), "dwa")
    return write_episode_bag(result, tmp_path_factory.mktemp("own") / "ep"), result.scenario.robot


def test_from_bag_of_a_bag_of_ours_keeps_the_robot_it_ran(own_bag, tmp_path, capsys):
    """Issue 32: the seed had the default 0.15 m circle and a differential drive."""
    bag, robot = own_bag
    assert robot.footprint == Footprint(shape="box", length=0.9, width=0.5) and robot.drive == "omni"
    out = tmp_path / "seed.yaml"
    assert main(["from-bag", str(bag), "-o", str(out), "--no-plot"]) == 0
    seed = load_scenario(out)
    assert seed.robot.footprint == robot.footprint and seed.robot.drive == "omni"
    assert seed.robot.limits == robot.limits and seed.robot.lidar == robot.lidar
    text = capsys.readouterr().out
    assert "footprint: the scenario the bag recorded (/navscenario/scenario: a 0.9 x 0.5 m box, omni drive)" in text


def test_from_bag_takes_robot_footprint_and_drive_as_the_other_importers(own_bag, tmp_path, capsys):
    bag, _ = own_bag
    out = tmp_path / "seed.yaml"
    assert main(["from-bag", str(bag), "-o", str(out), "--no-plot", "--footprint", "circle:0.3",
                 "--drive", "diff"]) == 0
    seed = load_scenario(out)
    assert seed.robot.footprint == Footprint(shape="circle", radius=0.3) and seed.robot.drive == "diff"
    robot_file = tmp_path / "robot.yaml"
    robot_file.write_text("robot:\n  footprint: {shape: box, length: 0.6, width: 0.4}\n  drive: diff\n"
                          "  limits: {max_speed: 0.7}\n")
    out2 = tmp_path / "seed2.yaml"
    assert main(["from-bag", str(bag), "-o", str(out2), "--no-plot", "--robot", str(robot_file)]) == 0
    seed2 = load_scenario(out2)
    assert seed2.robot.footprint == Footprint(shape="box", length=0.6, width=0.4)
    assert (seed2.robot.drive, seed2.robot.limits.max_speed) == ("diff", 0.7)
    capsys.readouterr()
    assert main(["from-bag", str(bag), "-o", str(tmp_path / "x.yaml"), "--footprint", "circle:0.3",
                 "--robot-radius", "0.2"]) != 0
    assert "give one (--robot-radius R is --footprint circle:R)" in capsys.readouterr().err


def test_an_import_into_a_folder_with_no_project_writes_the_schema_its_modeline_names(tmp_path):
    """Issue 32: the seed's first line named .navscenario/scenario-v1.json, which nobody wrote."""
    from pytest_navscenario.scenario.json_schema import schema_text
    from pytest_navscenario.scenario.modeline import PREFIX, project_root

    folder = tmp_path / "seeds"
    folder.mkdir()
    out = folder / "room.yaml"
    assert project_root(out) is None                                   # a bare folder
    assert main(["from-map", str(_map(tmp_path)), "--start=1,1,0", "--goal=5,3,0", "-o", str(out)]) == 0
    first = out.read_text().splitlines()[0]
    assert first.startswith(PREFIX)
    named = folder / first[len(PREFIX):]
    assert named.is_file() and named.read_text() == schema_text()
