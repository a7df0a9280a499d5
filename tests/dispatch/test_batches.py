"""A worker's share of a suite in batches (--nav-batch, dispatch/batches.py): one batch job per
worker chunk, one result per item, the results and JUnit of an unbatched run; a planner that kills
its worker process fails its own episode only (issue 27)."""
from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

# Imported here, before pytester's in-process runs snapshot sys.modules (numpy cannot load twice).
import pytest_navscenario.dispatch.local  # noqa: F401
import pytest_navscenario.harness.runner  # noqa: F401
from dispatch_helpers import scenario_text
from ray_fixtures import SUITE, item_lines, write_suite
from pytest_navscenario.dispatch.batches import BatchJob, submit_batched
from pytest_navscenario.dispatch.jobs import EpisodeJob
from pytest_navscenario.dispatch.local import ProcessExecutor, SerialExecutor
from pytest_navscenario.harness.batch import Batching
from pytest_navscenario.scenario.loader import loads_scenario

COMMON = ["suite", "-v", "-p", "no:cacheprovider", "--nav-plots=none", "--nav-artifacts=none"]

# a batch planner that kills its worker process when it meets the scenario "victim"
CRASHING = '''
import math, os


class Planner:
    name = "crashing"

    def reset(self, scenario):
        if scenario.name == "victim":
            os._exit(3)

    def act(self, obs):
        x, y, yaw = obs.pose
        tx, ty = obs.target
        c, s = math.cos(yaw), math.sin(yaw)
        return (c * (tx - x) + s * (ty - y), -s * (tx - x) + c * (ty - y), 0.0)

    def reset_batch(self, scenarios):
        self.names = [s.name for s in scenarios]
        for s in scenarios:
            self.reset(s)

    def act_batch(self, ids, observations):
        return [self.act(o) for o in observations]
'''


def records(path: Path) -> list[dict]:
    return [{k: v for k, v in json.loads(line).items() if k != "wall_time"}
            for line in path.read_text().splitlines()]


def junit(path: Path) -> str:
    return re.sub(r'(time|timestamp|hostname)="[^"]*"', "", path.read_text())


def jobs(names=("a", "b", "c", "d", "e")) -> list[EpisodeJob]:
    return [EpisodeJob(loads_scenario(scenario_text(n, 1.0 + 0.1 * k), f"{n}.yaml"), "dwa", keep_trajectory="none")
            for k, n in enumerate(names)]


def test_batched_jobs_give_each_job_its_own_result():
    batching = Batching()
    pendings = submit_batched(SerialExecutor(), jobs(), 2, batching)
    alone = SerialExecutor().map(jobs())
    got = [p.result() for p in pendings]
    assert [(r.outcome, r.metrics, r.scenario.name) for r in got] == [(r.outcome, r.metrics, r.scenario.name) for r in alone]
    assert (batching.batched, batching.batches, batching.alone) == (4, 2, 1)
    exec_jobs = [EpisodeJob(j.scenario, "exec:python planner.py") for j in jobs()[:2]]
    assert not any(isinstance(j, BatchJob) for j in [p.job for p in submit_batched(SerialExecutor(), exec_jobs, 8)])


@pytest.mark.heavy
def test_a_batch_that_kills_its_worker_fails_only_that_episode(tmp_path, monkeypatch):
    (tmp_path / "crashing.py").write_text(CRASHING)
    monkeypatch.syspath_prepend(str(tmp_path))
    names = [n for n, _ in SUITE]
    work = [EpisodeJob(loads_scenario(scenario_text(n, x), f"{n}.yaml"), "crashing:Planner", keep_trajectory="none")
            for n, x in SUITE]
    pool = ProcessExecutor(2)
    batching = Batching()
    try:
        got = [p.outcome() for p in submit_batched(pool, work, 3, batching)]
    finally:
        pool.close(cancel=True)
    died = [n for n, g in zip(names, got) if getattr(g, "type_name", "") == "WorkerDied"]
    assert died == ["victim"]
    assert all(g.outcome.value == "success" for n, g in zip(names, got) if n != "victim")
    # the summary counts the dead batch's episodes, which ran alone (they were missing from it)
    assert (batching.batched, batching.batches) == (3, 1)
    assert batching.why_alone == {"their batch's worker process died, so they ran again one by one": 3}


def test_workers_run_their_share_in_batches_with_the_results_of_an_unbatched_run(pytester: pytest.Pytester):
    write_suite(pytester.path / "suite", short_timeout="1.6")
    off = pytester.runpytest(*COMMON, "--nav-workers", "2", "--nav-batch", "off", "--nav-results=off.jsonl",
                             "--junitxml=off.xml")
    on = pytester.runpytest(*COMMON, "--nav-workers", "2", "--nav-results=on.jsonl", "--junitxml=on.xml")
    off.assert_outcomes(passed=5, failed=1)
    on.assert_outcomes(passed=5, failed=1)
    assert item_lines(on.outlines) == item_lines(off.outlines)
    assert records(pytester.path / "on.jsonl") == records(pytester.path / "off.jsonl")
    assert junit(pytester.path / "on.xml") == junit(pytester.path / "off.xml")
    assert "navscenario: batches (--nav-batch 16): 6 episode(s) in 2 batch(es)" in on.stdout.str()
    assert "batches (--nav-batch" not in off.stdout.str()
