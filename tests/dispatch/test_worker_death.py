"""A planner that ends its own process (issue 26, item 4): under -n 2 only the item whose episode
killed the worker is charged, never the item that happened to run beside it; serially, with
--nav-isolate, the run survives, reports that item and writes every other result. Real pytest
runs in subprocesses with a real planner that calls os._exit."""
from __future__ import annotations

import pytest

from pytest_navscenario.report.results_file import read_results

# "doomed" ends its process in act, but only once its "bystander" episode is running on the other
# worker (a live pid in bystander.pid that is not its own): without that wait the bystander could
# finish first, and the test would not show who is charged for the death.
PLANNER = '''
import os
import time


class Killer:
    def reset(self, scenario):
        self.name = scenario.name
        if self.name == "bystander":
            with open("bystander.pid.tmp", "w") as fh:
                fh.write(str(os.getpid()))
            os.replace("bystander.pid.tmp", "bystander.pid")

    def act(self, obs):
        if self.name == "bystander":
            time.sleep(0.02)          # a long episode: it runs while "doomed" dies
        elif self.name == "doomed" and obs.tick == 2:
            deadline = time.monotonic() + (10 if os.environ.get("WAIT_FOR_BYSTANDER") else 0)
            while time.monotonic() < deadline and not _bystander_running():
                time.sleep(0.01)
            os._exit(3)
        return (0.8, 0.0, 0.0)


def _bystander_running():
    try:
        pid = int(open("bystander.pid").read())
        os.kill(pid, 0)
    except (OSError, ValueError):
        return False
    return pid != os.getpid()
'''
SCENARIO = "version: 1\nmission: {{start: {{x: 0, y: 0}}, goal: {{x: {x}, y: 0}}, timeout: 30}}\n"


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(killer=PLANNER)
    (pytester.path / "scenarios").mkdir()
    for name in ("a", "doomed", "e"):
        (pytester.path / "scenarios" / f"{name}.yaml").write_text(SCENARIO.format(x=1.5))
    (pytester.path / "scenarios" / "bystander.yaml").write_text(SCENARIO.format(x=2.5))
    pytester.makeini("[pytest]\npythonpath = .\n")
    return pytester


def run(pytester: pytest.Pytester, *args: str) -> pytest.RunResult:
    return pytester.runpytest_subprocess("-p", "pytest_navscenario.plugin", "-p", "xdist.plugin", "scenarios",
                                         "--nav-subject=killer:Killer", "--nav-results=r.jsonl",
                                         "--nav-plots=none", *args, timeout=300)


def test_only_the_item_whose_episode_killed_the_worker_is_charged(project: pytest.Pytester,
                                                                    monkeypatch: pytest.MonkeyPatch):
    """Before: the bystander, running on the other worker at each of the three deaths, was charged
    three attempts too and failed with "WorkerDied ... died 3 times"."""
    monkeypatch.setenv("WAIT_FOR_BYSTANDER", "1")
    result = run(project, "-n", "2")
    out = result.stdout.str()
    result.assert_outcomes(passed=3, failed=1)
    assert "scenarios/doomed.yaml::doomed - RemoteEpisodeError: WorkerDied" in out, out[-3000:]
    assert "died 3 times (last: exit code 3;" in out
    records = {r["scenario"]: r for r in read_results(project.path / "r.jsonl")}
    assert sorted(records) == ["a", "bystander", "doomed", "e"]
    assert all(records[n]["outcome"] == "success" for n in ("a", "bystander", "e"))
    assert_crash_recorded(records["doomed"], out)


def assert_crash_recorded(record: dict, out: str) -> None:
    """Issue 32: the item whose worker died has a record (before: none, and the summary's rate
    table read "n 3, success 100 %") saying what ended it, and it counts in the rates."""
    assert record["outcome"] == "subject-error" and record["error"] == "WorkerDied", record
    assert record["message"].startswith("the episode did not finish (WorkerDied): the worker process "
                                        "running this episode died 3 times"), record["message"]
    assert record["metrics"]["min_clearance"] is None and record["passed"] is False
    rates = out[out.index("outcome rates"):].splitlines()
    assert rates[1].split() == ["family", "n", "success", "safety-stop", "timeout", "collision",
                                "subject-error"], rates[:4]
    assert rates[3].split()[1:3] == ["4", "75.0%"], rates[:4]
    assert "wrote 4 record(s)" in out


def test_a_serial_run_survives_a_planner_that_ends_its_process_with_nav_isolate(project: pytest.Pytester):
    """Before (no such option): os._exit(3) ended pytest itself, with no report and no results file."""
    result = run(project, "--nav-isolate=yes")
    out = result.stdout.str()
    assert "episodes run on 1 local worker process(es)" in out and "(--nav-isolate)" in out
    result.assert_outcomes(passed=3, failed=1)
    assert "died 3 times (last: exit code 3;" in out, out[-3000:]
    records = {r["scenario"]: r for r in read_results(project.path / "r.jsonl")}
    assert len(records) == 4
    assert_crash_recorded(records["doomed"], out)


@pytest.mark.heavy
def test_without_nav_isolate_the_serial_run_ends_with_the_planner(project: pytest.Pytester):
    """What --nav-isolate is for: in this process nothing can outlive os._exit (documented)."""
    result = run(project)
    assert result.ret == 3 and "passed" not in result.stdout.str()
    assert not (project.path / "r.jsonl").exists()


QUICK_JOBS = """
from pytest_navscenario.dispatch.local import ProcessExecutor


class Quick:
    def run(self):
        return 1

    def restore(self, outcome):
        return outcome


if __name__ == "__main__":
    pool = ProcessExecutor(2)
    print(sum(pool.map([Quick() for _ in range(6000)])))
    pool.close()
"""


def test_a_pool_runs_thousands_of_jobs_without_hanging(tmp_path):
    """Before: each job's "started" message waited in a pipe nobody read until a worker died; after
    ~4000 of them the pipe was full, every worker blocked on its next one and the run hung for good
    (a suite or search of a few thousand episodes on -n 2)."""
    import os
    import subprocess
    import sys

    (tmp_path / "quick.py").write_text(QUICK_JOBS)
    done = subprocess.run([sys.executable, "quick.py"], cwd=tmp_path, capture_output=True, text=True,
                          timeout=120, env=dict(os.environ))
    assert done.returncode == 0 and done.stdout.strip() == "6000", done.stderr[-2000:]


def test_an_item_whose_xdist_worker_died_has_a_record_and_counts(project: pytest.Pytester):
    """Under xdist's own distribution (``--dist load``, or a run with Python tests beside the
    scenarios) the planner's os._exit ends the xdist worker itself: before, xdist's crash report
    carried no record, so the results file had 3 records for 4 items and the rates left it out."""
    result = run(project, "-n", "2", "--dist", "load")
    out = result.stdout.str()
    result.assert_outcomes(passed=3, failed=1)
    records = {r["scenario"]: r for r in read_results(project.path / "r.jsonl")}
    assert sorted(records) == ["a", "bystander", "doomed", "e"], out[-3000:]
    doomed = records["doomed"]
    assert doomed["outcome"] == "subject-error" and doomed["error"] == "WorkerCrashed", doomed
    assert doomed["nodeid"] == "scenarios/doomed.yaml::doomed" and doomed["family"] == "scenarios"
    assert doomed["message"].startswith("the episode did not finish (WorkerCrashed): the pytest-xdist worker")
    assert "wrote 4 record(s)" in out
