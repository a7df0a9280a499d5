"""Parts of the plugin others build on: the report.nav payload, trajectory requests, artifact folder
names, the summary table; plus an interrupted run and the README's example command."""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.core.files import folder_name
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.plugin.payload import episode_from_payload, episode_to_payload, request_trajectories, trajectories_requested
from pytest_navscenario.report.results_file import read_results
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.report.summary import format_summary

ROOT = Path(__file__).resolve().parents[2]

WALL_SCENARIO = """
version: 1
family: walls
mission: {start: {x: 0, y: 0}, goal: {x: 4, y: 0}, timeout: 10}
robot: {safety: {enabled: false}}
obstacles: [{type: box, name: wall, x: 2, y: 0, length: 0.4, width: 2}]
"""


class Straight:
    name = "straight"

    def reset(self, scenario):
        pass

    def act(self, obs):
        return 1.0, 0.0, 0.0


@pytest.fixture(scope="module")
def crash():
    return run_scenario(loads_scenario(WALL_SCENARIO, source="walls/crash.yaml"), Straight)


def test_payload_survives_json_and_rebuilds_the_episode(crash):
    payload = episode_to_payload(crash, nodeid="walls/crash.yaml::crash", path="walls/crash.yaml",
                                 with_trajectory=True)
    back = episode_from_payload(json.loads(json.dumps(payload)))  # plain data: crosses xdist
    assert back.outcome == crash.outcome and back.message == crash.message
    assert back.collision == crash.collision and back.seed == crash.seed
    assert back.scenario == crash.scenario and back.scenario.source == "walls/crash.yaml"
    np.testing.assert_array_equal(back.trajectory.pose, crash.trajectory.pose)
    for key, value in crash.metrics.as_dict().items():
        got = getattr(back.metrics, key)  # exact, inf and nan included
        assert got == value or (isinstance(value, float) and math.isnan(value) and math.isnan(got)), key
    assert payload["record"]["nodeid"] == "walls/crash.yaml::crash"
    assert payload["events"]["collision"]["obstacle"] == "wall"


def test_payload_without_trajectory_gives_an_empty_one(crash):
    payload = episode_to_payload(crash, nodeid="n", path="p", with_trajectory=False)
    assert payload["trajectory"] is None
    assert len(episode_from_payload(payload).trajectory.t) == 0


def test_trajectory_requests_only_widen(pytestconfig):
    class Cfg:  # a fresh stash; the session's config must not be changed by this test
        stash = pytest.Stash()

    cfg = Cfg()
    assert trajectories_requested(cfg) == "none"
    request_trajectories(cfg, "all")
    request_trajectories(cfg, "failed")
    assert trajectories_requested(cfg) == "all"
    with pytest.raises(ValueError, match="'failed' or 'all'"):
        request_trajectories(cfg, "some")


@pytest.mark.parametrize("nodeid", ["../../etc/passwd::x", "a/b.yaml::..", "/abs/x.yaml::x", "::", "a b\x00c"])
def test_artifact_folder_names_stay_inside_the_folder(nodeid):
    name = folder_name(nodeid)
    assert "/" not in name and "\\" not in name and not name.startswith(".")
    assert (Path("/art") / name).parent == Path("/art")
    assert folder_name(nodeid) == name and folder_name(nodeid + "1") != name


def test_summary_counts_rates_and_metrics():
    recs = [{"family": "f", "outcome": o, "metrics": {"min_clearance": c, "path_efficiency": None,
                                                      "duration": 2.0}}
            for o, c in [("success", 0.5), ("success", 0.3), ("timeout", 0.1), ("safety-stop", 0.2)]]
    text = format_summary(recs)
    row = next(line for line in text.splitlines() if line.startswith("f "))
    assert row.split()[:3] == ["f", "4", "50.0%"]
    assert "0.10 / 0.28 / 0.50" in text and "n/a" in text and "subject-error" not in text


def test_interrupted_run_still_writes_the_results_of_what_ran(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    # A real Ctrl-C (SIGINT to this process) while the planner runs; since issue 15 a planner that
    # raises KeyboardInterrupt itself only ends its episode (tests/plugin/test_planner_exit.py).
    pytester.makepyfile(stopper="""
        import os, signal, time

        class Stopper:
            def reset(self, scenario):
                self.stop = scenario.name == "b"
            def act(self, obs):
                if self.stop:
                    os.kill(os.getpid(), signal.SIGINT)
                    time.sleep(5)
                return 1.0, 0.0, 0.0
    """)
    pytester.syspathinsert()
    text = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1, y: 0}}\n"
    pytester.makefile(".yaml", a=text, b=text, c=text)
    result = pytester.runpytest("-p", "pytest_navscenario.plugin", "--nav-subject=stopper:Stopper", "--nav-plots=none",
                                "--nav-results=r.jsonl", no_reraise_ctrlc=True)
    assert result.ret == pytest.ExitCode.INTERRUPTED
    assert [r["scenario"] for r in read_results(pytester.path / "r.jsonl")] == ["a"]


def test_readme_example_command_runs_the_users_planner(tmp_path):
    env = dict(os.environ, PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "pytest_navscenario.plugin", "examples/scenarios",
         "examples/test_mynav.py", "--nav-subject=examples.mynav:Planner", f"--nav-results={tmp_path / 'r.jsonl'}",
         f"--nav-artifacts={tmp_path / 'art'}", "--nav-plots=none", "-p", "no:cacheprovider"],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert "6 passed, 2 xfailed" in proc.stdout, proc.stdout + proc.stderr
    assert {r["subject"] for r in read_results(tmp_path / "r.jsonl")} == {"mynav"}
