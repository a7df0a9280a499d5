"""The ``navscenario`` parser as a user meets it: negative poses typed without '=', and help
that says what the tool and each command and argument do."""
from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.cli import SUBCOMMANDS, build_parser, main
from pytest_navscenario.scenario.loader import load_scenario

DATA = Path(__file__).resolve().parents[1] / "data"
BARN = DATA / "barn_world_0.world"          # BARN world 0 (MIT, see tests/data/LICENSES)
TB3 = DATA / "fuse_turtlebot3.bag"          # TurtleBot3 bag (BSD-3-Clause)


def _map(folder: Path) -> Path:
    """A 6 m x 6 m walled room, origin (-3, -3): the map frame has negative coordinates."""
    img = np.full((60, 60), 254, np.uint8)
    img[0, :] = img[-1, :] = img[:, 0] = img[:, -1] = 0
    img[30, 10:40] = 0
    (folder / "room.pgm").write_bytes(b"P5\n60 60\n255\n" + img.tobytes())
    path = folder / "room.yaml"
    path.write_text("image: room.pgm\nresolution: 0.1\norigin: [-3.0, -3.0, 0.0]\n"
                    "occupied_thresh: 0.65\nfree_thresh: 0.196\nnegate: 0\n")
    return path


# ------------------------------------------------------------------ negative numbers as values

def test_import_sdf_takes_negative_poses_as_typed(tmp_path, capsys):
    out = tmp_path / "barn.yaml"
    code = main(["import", "sdf", str(BARN), "--start", "-2.25,3,90", "--goal", "-2.25,13,90",
                 "-o", str(out)])
    assert code == 0, capsys.readouterr().err
    mission = load_scenario(out).mission
    assert (mission.start.x, mission.start.y, mission.start.yaw) == (-2.25, 3.0, 90.0)
    assert (mission.goal.x, mission.goal.y, mission.goal.yaw) == (-2.25, 13.0, 90.0)


def test_from_map_takes_negative_poses_as_typed(tmp_path, capsys):
    out = tmp_path / "room_seed.yaml"
    code = main(["from-map", str(_map(tmp_path)), "--start", "-2,-1.5,45", "--goal", "-.5,2,-90",
                 "-o", str(out), "--timeout", "20"])
    assert code == 0, capsys.readouterr().err
    mission = load_scenario(out).mission
    assert (mission.start.x, mission.start.y, mission.start.yaw) == (-2.0, -1.5, 45.0)
    assert (mission.goal.x, mission.goal.y, mission.goal.yaw) == (-0.5, 2.0, -90.0)


def test_from_bag_takes_a_negative_laser_pose_as_typed(tmp_path, capsys):
    out = tmp_path / "tb3.yaml"
    code = main(["from-bag", str(TB3), "--laser-pose", "-0.064,-0,0", "--end", "10", "-o", str(out)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "x=-0.064 y=" in captured.out and "yaw=0.0 deg" in captured.out and "from --laser-pose" in captured.out
    assert load_scenario(out).obstacles


def test_a_negative_number_list_is_a_value_and_real_options_still_work():
    args = build_parser("import").parse_args(
        ["import", "sdf", "w.world", "-o", "out.yaml", "--start", "-1.5", "--goal", "-1e-3, -2,+3"])
    assert (args.start, args.goal, args.output) == ("-1.5", "-1e-3, -2,+3", "out.yaml")
    # an unknown option is still an error, and an option still cannot be swallowed as a value
    for argv in (["import", "sdf", "w.world", "-o", "x.yaml", "--start", "-x"],
                 ["import", "sdf", "w.world", "-o", "x.yaml", "--start", "--force"],
                 ["import", "sdf", "w.world", "-o", "x.yaml", "--bogus", "1"]):
        with pytest.raises(SystemExit) as exc:
            build_parser("import").parse_args(argv)
        assert exc.value.code == 2


def test_a_malformed_negative_pose_names_the_option(tmp_path, capsys):
    code = main(["import", "sdf", str(BARN), "--start", "-2.25,3,90,7", "--goal", "0,1,2",
                 "-o", str(tmp_path / "x.yaml")])
    assert code == 2 and "--start '-2.25,3,90,7': expected x,y,yaw" in capsys.readouterr().err


# ------------------------------------------------------------------ help

def test_top_level_help_says_what_the_tool_does_and_lists_each_command():
    out = subprocess.run([sys.executable, "-m", "pytest_navscenario.cli.main", "--help"],
                         capture_output=True, text=True, check=True).stdout
    lines = out.splitlines()
    description = " ".join(lines[2:lines.index("", 2)])
    assert description.startswith("Test mobile-robot navigation planners")
    assert description.count(". ") == 0 and description.endswith(".")     # one sentence
    assert "console script" not in out and "imported only" not in out     # no docstring fragment
    for name, (_, purpose) in SUBCOMMANDS.items():
        assert name in out and " ".join(purpose.split()[:4]) in " ".join(out.split())
    assert "(see check_planner)" not in out
    check = SUBCOMMANDS["check-planner"][1]
    assert "protocol" in check and "signatures" in check and "determinism" in check


def _arguments(parser: argparse.ArgumentParser):
    for action in parser._actions:
        if isinstance(action, (argparse._HelpAction, argparse._VersionAction)):
            continue
        yield action


@pytest.mark.parametrize("name", list(SUBCOMMANDS))
def test_every_command_and_argument_is_described(name):
    parser = build_parser(name)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[name]
    assert sub.description and len(sub.description) > 40
    assert "see " not in sub.description.lower()[:20]
    for action in _arguments(sub):
        label = action.option_strings[-1] if action.option_strings else action.dest
        assert action.help and len(action.help) > 10, f"{name} {label}: no help text"
        if action.nargs == 0:          # a flag: takes no value, needs no metavar
            continue
        if action.choices:             # shown as {a,b,c}: the accepted values
            assert action.metavar is None, f"{name} {label}: choices hidden behind a metavar"
            continue
        assert action.metavar, f"{name} {label}: no metavar (shows the bare dest name)"
        assert action.metavar not in (action.dest, action.dest.upper()), \
            f"{name} {label}: metavar {action.metavar} is the bare dest name"
    # the rendered help never breaks an option or a built-in name across lines
    text = sub.format_help()
    assert not any(line.rstrip().endswith("-") and not line.rstrip().endswith(" -")
                   for line in text.splitlines()), text
