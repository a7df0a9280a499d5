"""--nav-ray on a real two-node Ray cluster on this machine (``ray.cluster_utils.Cluster``, one per
module): episodes spread over both nodes, a worker killed mid-episode loses and duplicates
nothing, and nodes that cannot load the subject are named before any episode runs."""
from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time
from pathlib import Path

import pytest

from ray_fixtures import RAY_MISSING

ray = pytest.importorskip("ray", reason=RAY_MISSING)

# A two-node cluster is a whole workflow (~15 s quiet, most of it starting the cluster): heavy.
# The default run covers --nav-ray on a local instance (test_ray_local.py).
pytestmark = pytest.mark.heavy

# Imported here, before pytester's in-process runs snapshot sys.modules (numpy cannot load twice).
import pytest_navscenario.dispatch.on_ray  # noqa: E402,F401
import pytest_navscenario.harness.runner  # noqa: E402,F401
from ray_fixtures import SUITE, item_lines, planners_on_worker_path, restore_pythonpath, write_suite  # noqa: E402


SEARCH_DIR = Path(__file__).resolve().parents[1] / "search"
sys.path.insert(0, str(SEARCH_DIR))   # test_search, test_search_parallel


@pytest.fixture(scope="module")
def cluster(tmp_path_factory: pytest.TempPathFactory):
    from ray.cluster_utils import Cluster

    folder = tmp_path_factory.mktemp("cluster-planners")
    old = planners_on_worker_path(folder)
    (folder / "straight_planner.py").write_text((SEARCH_DIR / "straight_planner.py").read_text())
    nodes = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
    try:
        nodes.add_node(num_cpus=1)
        nodes.wait_for_nodes()
        ray.init(address=nodes.address, log_to_driver=False)
        yield nodes.address, folder
    finally:
        ray.shutdown()
        nodes.shutdown()
        restore_pythonpath(old)


def records(path: Path) -> list[dict]:
    return [{k: v for k, v in json.loads(line).items() if k != "wall_time"}
            for line in path.read_text().splitlines()]


def test_two_nodes_and_a_killed_worker_give_the_serial_results(pytester: pytest.Pytester, cluster, monkeypatch):
    address, folder = cluster
    write_suite(pytester.path / "suite")   # the subject is importable on the nodes only
    killed: list[int] = []
    done = threading.Event()

    def kill_the_victim() -> None:   # the victim episode sleeps in reset until killed
        marker = folder / "victim.pid"
        while not marker.exists() and not done.wait(0.05):
            pass
        if marker.exists():
            os.kill(int(marker.read_text()), signal.SIGKILL)
            killed.append(int(marker.read_text()))

    killer = threading.Thread(target=kill_the_victim)
    killer.start()
    common = ["suite", "-v", "-p", "no:cacheprovider", "--nav-subject=killable:Planner", "--nav-plots=none"]
    try:
        on_ray = pytester.runpytest(*common, f"--nav-ray={address}", "--nav-results=r.jsonl")
    finally:
        done.set()
        killer.join()
    assert killed, "the victim episode never started on the cluster"
    on_ray.assert_outcomes(passed=len(SUITE))
    assert "2 node(s), 2 CPU(s)" in on_ray.stdout.str()
    resets = [line.split() for line in (folder / "resets.log").read_text().splitlines()]
    assert len({node for _, _, node in resets}) == 2, resets          # both nodes ran episodes
    victim = [pid for pid, name, _ in resets if name == "victim"]
    assert victim[0] == str(killed[0]) and len(victim) == 2, resets   # killed once, run once more
    assert sorted(name for _, name, _ in resets) == sorted([n for n, _ in SUITE] + ["victim"])

    monkeypatch.syspath_prepend(str(folder))      # the serial run loads the subject here
    serial = pytester.runpytest(*common, "--nav-results=s.jsonl")
    serial.assert_outcomes(passed=len(SUITE))
    assert item_lines(on_ray.outlines) == item_lines(serial.outlines)
    got = records(pytester.path / "r.jsonl")
    assert [r["nodeid"] for r in got] == [f"suite/{n}.yaml::{n}" for n, _ in sorted(SUITE)]   # once each
    assert got == records(pytester.path / "s.jsonl")


def test_nodes_that_cannot_load_the_subject_are_named_before_any_episode(pytester: pytest.Pytester, cluster):
    address, folder = cluster
    write_suite(pytester.path / "suite")
    pytester.makepyfile(only_here="from killable import Planner\n")   # importable here, not on the nodes
    pytester.syspathinsert()
    before = (folder / "resets.log").read_text() if (folder / "resets.log").exists() else ""
    result = pytester.runpytest("suite", "-p", "no:cacheprovider", "--nav-subject=only_here:Planner",
                                f"--nav-ray={address}")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    err = result.stderr.str()
    lines = [line for line in err.splitlines() if "cannot load the subject 'only_here:Planner'" in line]
    assert len(lines) == 2 and all("No module named 'only_here'" in line for line in lines), err
    assert len({line.split("node id ")[1][:8] for line in lines}) == 2    # each node named
    assert "pip install it on each node" in err
    after = (folder / "resets.log").read_text() if (folder / "resets.log").exists() else ""
    assert after == before                                                 # no episode ran


def test_a_search_on_two_nodes_writes_what_a_serial_run_writes(pytester: pytest.Pytester, cluster, monkeypatch):
    from test_search import SEED_YAML
    from test_search_parallel import assert_same_search_output
    address, folder = cluster
    monkeypatch.syspath_prepend(str(folder))       # the serial run loads the subject here
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "crate.yaml").write_text(SEED_YAML.replace("name: crate\n", ""))
    pytester.makeini("[pytest]\nnav_scenario_paths = scenarios\n")
    args = ["-p", "no:cacheprovider", "--nav-subject=straight_planner:Straight", "--navsearch", "crate",
            "--budget", "24", "--navsearch-seed", "2"]
    serial = pytester.runpytest(*args, "--navsearch-out", "serial")
    on_ray = pytester.runpytest(*args, f"--nav-ray={address}", "--navsearch-out", "ray")
    assert serial.ret == on_ray.ret == 0, on_ray.stdout.str()
    assert_same_search_output(pytester.path / "serial", pytester.path / "ray")
