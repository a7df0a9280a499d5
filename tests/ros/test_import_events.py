"""Issue 17, the moment: a 20 s bag from a known world with a goal 6 m ahead, in which the robot
stops halfway (its command drops to zero), backs up, turns a full circle in place, then drives on
and brushes past a pillar. ``--list-events`` finds each with its time; ``--at`` cuts the seed
before the stop, with the recorded goal."""
from __future__ import annotations

import math

import numpy as np
import pytest
from ros_synthetic import World, pose_msg, robot_bag, stamp

from pytest_navscenario.cli import main
from pytest_navscenario.ros.bag_import import scenario_from_bag
from pytest_navscenario.ros.bag_import.events import bag_events

WORLD = World(pillars=[(4.0, 0.28, 0.1, 1.0), (1.0, -1.5, 0.3, 1.0)])
TURN = 2 * math.pi / 5


def _timeline():
    """(t, x, yaw, v, w) every 0.1 s: drive 0-4 s, stop 4-8, back up 8-9, turn 9-14, drive 14-21."""
    rows = []
    x = yaw = 0.0
    for i in range(211):
        t = 0.1 * i
        v, w = (0.5, 0.0) if t < 4 else (0.0, 0.0) if t < 8 else (-0.5, 0.0) if t < 9 else \
            (0.0, TURN) if t < 14 else (0.5, 0.0)
        rows.append((t, x, yaw, v, w))
        x += v * 0.1
        yaw += w * 0.1
    return np.array(rows)


def _event_bag(folder, **sensor):
    tl = _timeline()
    truth = np.stack([tl[:, 0], tl[:, 1], 0 * tl[:, 0], tl[:, 2]], 1)
    drift = np.stack([0.03 * tl[:, 0], 0.01 * tl[:, 0], np.radians(0.5 * tl[:, 0])], 1)

    def extra(bag):
        bag.write("/goal_pose", "geometry_msgs/msg/PoseStamped", 0.5,
                  {"header": {"stamp": stamp(0.5), "frame_id": "map"}, "pose": pose_msg(6.0, 0.0, 0.0)})
        for t, _, _, v, w in tl:
            bag.write("/cmd_vel", "geometry_msgs/msg/Twist", t, {"linear": {"x": v}, "angular": {"z": w}})
    return robot_bag(folder / "ev", WORLD, truth, drift=drift, extra=extra, **sensor)


@pytest.fixture(scope="module")
def event_bag(tmp_path_factory):
    return _event_bag(tmp_path_factory.mktemp("ev"))


@pytest.fixture(scope="module")
def cloud_event_bag(tmp_path_factory):
    """The same drive seen by a 3D lidar (16 rings, 0.6 m up) instead of a laser."""
    cloud = {"azimuths": np.radians(np.arange(-180.0, 180.0, 1.0)),
             "elevations": np.radians(np.arange(-15.0, 16.0, 2.0))}
    return _event_bag(tmp_path_factory.mktemp("evc"), scans=False, laser=(0.0, 0.0, 0.6), cloud=cloud)


@pytest.mark.parametrize("sensor", ["laser", "3D lidar"])
def test_list_events_finds_each_moment(event_bag, cloud_event_bag, sensor):
    events, notes = bag_events(event_bag if sensor == "laser" else cloud_event_bag)
    kinds = {e.kind: e for e in events}
    assert sorted(kinds) == ["close", "cmd-zero", "reversed", "stopped", "turned"], events
    assert kinds["stopped"].t == pytest.approx(4.0, abs=0.5) and kinds["stopped"].duration > 3
    assert "4.0 m from the goal" in kinds["stopped"].text
    assert kinds["cmd-zero"].t == pytest.approx(4.0, abs=0.01) and "4.0 m from the active goal" in kinds["cmd-zero"].text
    assert kinds["reversed"].t == pytest.approx(8.0, abs=0.4) and "0.5 m" in kinds["reversed"].text
    assert kinds["turned"].t == pytest.approx(9.0, abs=0.4)
    assert float(kinds["turned"].text.split("place ")[1].split(" deg")[0]) == pytest.approx(360, abs=20)
    assert kinds["close"].t == pytest.approx(19.0, abs=0.3)     # x = 4 at 14 + 2.5 / 0.5 s
    assert len(events) == 5
    assert any("world frame: map" in n for n in notes)


def test_cli_lists_them_and_at_cuts_before_the_stop(event_bag, tmp_path, capsys):
    assert main(["from-bag", str(event_bag), "--list-events"]) == 0
    out = capsys.readouterr().out
    assert "5 candidate moment(s)" in out and "--at T" in out
    line = next(ln for ln in out.splitlines() if "stopped" in ln and "from the goal" in ln)
    t_stop = float(line.split("t=")[1].split()[0])
    seed_file = tmp_path / "stop.yaml"
    assert main(["from-bag", str(event_bag), "-o", str(seed_file), "--at", str(t_stop), "--window", "3"]) == 0
    seed = scenario_from_bag(event_bag, at=t_stop, window=3)
    m = seed.scenario.mission
    assert m.start.x == pytest.approx(0.5 * (t_stop - 3), abs=0.05)       # 3 s before the stop
    assert (m.goal.x, m.goal.y) == (6.0, 0.0)                                  # the recorded goal
    assert seed.path[-1, 0] == pytest.approx(3.0, abs=0.11)


@pytest.mark.parametrize("at", ["-1", "500"])
def test_at_outside_the_bag_is_an_error(event_bag, capsys, tmp_path, at):
    assert main(["from-bag", str(event_bag), "-o", str(tmp_path / "x.yaml"), f"--at={at}"]) == 2
    err = capsys.readouterr().err
    assert f"--at {float(at):g} is outside the bag: its odometry covers 0..21.0 s" in err


def test_at_with_start_or_a_bad_window_is_an_error(event_bag, capsys, tmp_path):
    out = str(tmp_path / "x.yaml")
    assert main(["from-bag", str(event_bag), "-o", out, "--at", "5", "--start", "1"]) == 2
    assert "--at cuts the window before a moment: give it without --start/--end" in capsys.readouterr().err
    assert main(["from-bag", str(event_bag), "-o", out, "--at", "5", "--window", "0"]) == 2
    assert "--window must be a positive number of seconds, got 0.0" in capsys.readouterr().err
    assert main(["from-bag", str(event_bag)]) == 2
    assert "-o/--output is required" in capsys.readouterr().err


def test_at_on_a_turn_in_place_holds_the_turn(event_bag):
    """Issue 24: --at at the moment the robot starts turning in place (9 s) runs the seed to the
    turn's end, so the seed holds the turn, and says so."""
    seed = scenario_from_bag(event_bag, at=9.1, window=5.0)
    note = [n for n in seed.notes if "falls on a turn in place" in n]
    assert len(note) == 1 and "so that it holds the turn in place" in note[0], seed.notes
    end = seed.path[-1, 0] + 4.1                                   # the window starts at 4.1 s
    assert end == pytest.approx(14.0, abs=0.4)


def test_at_whose_window_reaches_before_the_bag_says_it_was_cut(event_bag):
    seed = scenario_from_bag(event_bag, at=3.0, window=30.0)
    assert any(n.startswith("the window of 30 s before --at 3 would reach before the bag's start: cut there, "
                            "it covers 0..3 s") for n in seed.notes), seed.notes
    assert seed.path[-1, 0] == pytest.approx(3.0, abs=0.05)


def test_list_events_streams_the_scans(event_bag):
    """--list-events reads the scans in a second, streamed pass: the bag's data never holds them."""
    from pytest_navscenario.ros.bag_import.reading import PROBE, read_bag
    data = read_bag(event_bag)
    assert len(data.scan_probe) <= 2 * PROBE and not hasattr(data, "scan_ranges")
    events, _ = bag_events(event_bag)
    assert [e.kind for e in events].count("close") == 1


def test_a_relocalisation_jump_in_a_bag_without_scans_says_nothing_of_scans(tmp_path):
    """The note about scans on each side of a jump is left out when there are no scans."""
    t = np.arange(60) * 0.1
    truth = np.stack([t, 0.5 * t, 0 * t, 0 * t], 1)
    drift = np.zeros((60, 3))
    drift[30:, 0] = 0.5
    seed = scenario_from_bag(robot_bag(tmp_path / "jump", World(), truth, drift=drift, scans=False))
    jump = [n for n in seed.notes if n.startswith("relocalisation jump")]
    assert len(jump) == 1 and "scans" not in jump[0], jump
