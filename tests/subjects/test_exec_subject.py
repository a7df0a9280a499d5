"""External planners (``exec:`` subjects): the JSON Lines protocol end to end, and every way an
external program can misbehave, each ending as that episode's subject error with a clear message,
after which the next episode runs normally on a restarted program."""
from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import pytest

from pytest_navscenario import run_scenario
from pytest_navscenario.core.errors import SubjectLoadError
from pytest_navscenario.subjects.external import _PROCESSES
from pytest_navscenario.subjects.loading import load_subject
from pytest_navscenario.verdict.result import Outcome
from pytest_navscenario.scenario.model import BoxObstacle, Mission, Pose, Scenario

ROOT = Path(__file__).resolve().parents[2]
VECTOR_FIELD = ROOT / "examples" / "external" / "vector_field.py"


def open_field(name: str = "open", length: float = 3.0) -> Scenario:
    return Scenario(name=name, mission=Mission(start=Pose(0.0, 0.0, 90.0), goal=Pose(0.0, length, 90.0),
                                               timeout=15.0))


# One program for every misbehaviour: it behaves on scenarios whose name does not start with
# "bad-", and on "bad-<mode>" it misbehaves in that mode at tick 2.
MISBEHAVE = textwrap.dedent('''\
    import json, math, os, sys, time
    mode = None
    for line in sys.stdin:
        msg = json.loads(line)
        if msg["type"] == "reset":
            name = msg["scenario"].get("name", "")
            mode = name[4:] if name.startswith("bad-") else None
            if mode == "reset-crash":
                sys.exit(7)
            print(json.dumps({"type": "ready", "name": "misbehave", "version": "0"}), flush=True)
            continue
        if msg["type"] == "shutdown":
            break
        tick = msg["tick"]
        reply = {"type": "command", "vx": 0.8, "vy": 0.0, "wz": 0.0}
        if mode and tick == 2:
            if mode == "crash":
                print("about to fail: segfault imminent", file=sys.stderr, flush=True)
                raise RuntimeError("boom")
            if mode == "exit":
                sys.exit(0)
            if mode == "hang":
                time.sleep(3600)
            if mode == "garbage":
                print("hello from the planner", flush=True)
                continue
            if mode == "nan":
                reply["vx"] = float("nan")
            if mode == "wrongtype":
                reply["vx"] = "fast"
            if mode == "error":
                reply = {"type": "error", "message": "localisation lost"}
            if mode == "list":
                reply = [1, 2, 3]
            if mode == "deep":
                print("[" * 100000 + "]" * 100000, flush=True)
                continue
        print(json.dumps(reply), flush=True)
''')


@pytest.fixture(scope="module")
def misbehave(tmp_path_factory) -> str:
    script = tmp_path_factory.mktemp("exec") / "misbehave.py"
    script.write_text(MISBEHAVE)
    yield f"exec:{sys.executable} {script}"
    for proc in list(_PROCESSES.values()):
        proc.stop(grace=0.2)


def test_example_external_planner_reaches_the_goal():
    result = run_scenario(open_field(), f"exec:{sys.executable} {VECTOR_FIELD}")
    assert result.outcome is Outcome.SUCCESS, result.message
    assert result.subject == "vector-field (external)" and result.subject_version == "1.0"


def test_example_external_planner_avoids_a_box():
    scenario = Scenario(name="box-ahead", mission=Mission(start=Pose(0.0, 0.0, 90.0), goal=Pose(0.0, 6.0, 90.0),
                                                          timeout=30.0),
                        obstacles=(BoxObstacle("crate", 0.0, 3.0, 1.0, 1.0),))
    result = run_scenario(scenario, f"exec:{sys.executable} {VECTOR_FIELD}")
    assert result.outcome is Outcome.SUCCESS, result.message
    assert result.metrics.min_clearance > 0.0


@pytest.mark.parametrize("mode, expected", [
    ("crash", "exited with status 1"),
    ("exit", "exited with status 0"),
    ("garbage", "not JSON"),
    ("nan", "nan"),
    ("wrongtype", "'vx' is 'fast', expected a number"),
    ("error", "localisation lost"),
    ("list", "expected a JSON object"),
    ("deep", "nested too deeply"),     # json.loads raised RecursionError, which ended the run
    ("reset-crash", "exited with status 7"),
])
def test_each_misbehaviour_is_a_subject_error_and_the_next_episode_runs(misbehave, mode, expected):
    bad = run_scenario(open_field(f"bad-{mode}"), misbehave)
    assert bad.outcome is Outcome.SUBJECT_ERROR
    failure = bad.subject_failure
    assert expected.lower() in failure.message.lower()
    if mode != "reset-crash":
        assert failure.tick == 2, failure
    good = run_scenario(open_field("fine"), misbehave)
    assert good.outcome is Outcome.SUCCESS, good.message


def test_crash_message_quotes_the_programs_stderr(misbehave):
    bad = run_scenario(open_field("bad-crash"), misbehave)
    assert "segfault imminent" in bad.subject_failure.message


def test_hanging_program_is_stopped_at_the_tick_limit_and_restarted(misbehave):
    bad = run_scenario(open_field("bad-hang"), misbehave, tick_limit=0.3)
    assert bad.outcome is Outcome.SUBJECT_ERROR
    assert bad.subject_failure.tick == 2
    assert "0.3" in bad.subject_failure.message
    assert run_scenario(open_field("fine"), misbehave).outcome is Outcome.SUCCESS


def test_one_process_serves_many_episodes(misbehave):
    run_scenario(open_field("fine"), misbehave)
    pids = {proc.proc.pid for proc in _PROCESSES.values() if proc.alive}
    run_scenario(open_field("fine"), misbehave)
    assert {proc.proc.pid for proc in _PROCESSES.values() if proc.alive} == pids


def test_missing_or_unusable_program_is_a_load_error(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SubjectLoadError, match="no such program"):
        load_subject("exec:./does/not/exist --flag")
    (tmp_path / "planner.sh").write_text("#!/bin/sh\n")
    with pytest.raises(SubjectLoadError, match="not executable"):
        load_subject("exec:./planner.sh")
    with pytest.raises(SubjectLoadError, match="names no program"):
        load_subject("exec:")


POINTS_CHECKER = textwrap.dedent('''\
    import json, sys
    for line in sys.stdin:
        msg = json.loads(line)
        if msg["type"] == "reset":
            print(json.dumps({"type": "ready"}), flush=True)
        elif msg["type"] == "shutdown":
            break
        else:
            roll, pitch = msg["attitude"]
            points = msg.get("points")
            wall = [p for p in points or [] if abs(p[1]) < 0.5 and p[2] > -0.4]
            if not wall or abs(min(p[0] for p in wall) - 2.0) > 0.01 or (roll, pitch) != (0.0, 0.0):
                print(json.dumps({"type": "error", "message": f"saw {len(points or [])} points"}), flush=True)
            else:
                print(json.dumps({"type": "command", "vx": 0.0, "vy": 0.0, "wz": 0.0}), flush=True)
''')


def test_an_external_planner_gets_the_attitude_and_the_3d_lidars_points(tmp_path):
    from dataclasses import replace

    from pytest_navscenario.scenario.terrain import Lidar3D

    script = tmp_path / "points.py"
    script.write_text(POINTS_CHECKER)
    scenario = Scenario(name="wall", mission=Mission(start=Pose(0.0, 0.0, 0.0), goal=Pose(5.0, 0.0, 0.0),
                                                     timeout=0.5),
                        obstacles=(BoxObstacle("wall", 2.5, 0.0, length=1.0, width=4.0, height=2.0),))
    scenario = replace(scenario, robot=replace(scenario.robot, lidar3d=Lidar3D(mount_z=0.4)))
    try:
        result = run_scenario(scenario, load_subject(f"exec:{sys.executable} {script}"))
        assert result.outcome is Outcome.TIMEOUT, result.message
        plain = run_scenario(replace(scenario, robot=replace(scenario.robot, lidar3d=None)),
                             load_subject(f"exec:{sys.executable} {script}"))
        assert plain.outcome is Outcome.SUBJECT_ERROR and "saw 0 points" in plain.message
    finally:
        for proc in list(_PROCESSES.values()):
            proc.stop()
