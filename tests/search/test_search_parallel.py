"""One search on every core: ``--navsearch NAME -n 2`` evaluates each generation on two local
worker processes and writes the files a serial run writes (same search seed); Ctrl-C or SIGTERM
under -n keeps every failure found before it."""
from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from straight_planner import Straight
from test_search import SEED_YAML
from test_search_loop import OPEN_YAML, _fingerprint
# Before pytester's in-process runs snapshot sys.modules: a worker pool pickles functions of
# concurrent.futures by reference, which fails if a later run re-imports that module.
import pytest_navscenario.dispatch.local  # noqa: E402,F401
from pytest_navscenario.dispatch.local import ProcessExecutor, SerialExecutor  # noqa: E402
from pytest_navscenario.scenario.loader import loads_scenario  # noqa: E402
from pytest_navscenario.search.engine import run_search  # noqa: E402
from pytest_navscenario.search.parallel import executor_evaluator  # noqa: E402

STRAIGHT = (Path(__file__).parent / "straight_planner.py").read_text()
SLOW = STRAIGHT + '''

class SlowStraight(Straight):
    """The straight driver, 5 ms per tick: a search of 300 lasts long enough to interrupt."""
    def act(self, obs):
        import time
        time.sleep(0.005)
        return super().act(obs)
'''
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def project(pytester: pytest.Pytester) -> pytest.Pytester:
    pytester.makepyfile(straight_planner=SLOW)
    pytester.syspathinsert()             # worker processes start with this process's sys.path
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "crate.yaml").write_text(SEED_YAML.replace("name: crate\n", ""))
    pytester.makeini("[pytest]\nnav_scenario_paths = scenarios\n")
    return pytester


def files(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def without_timestamps(data: bytes) -> bytes:
    """A frozen file with its provenance time removed (when it was found: differs in any rerun)."""
    return re.sub(rb"'?\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d[^'\n]*'?", b"<time>", data)


def log_without_times(data: bytes) -> list[dict]:
    """The search log with each simulation's measured wall time, the search's id and its start
    date removed (they differ between any two runs, serial or not); everything else must match
    bit for bit."""
    rows = [json.loads(line) for line in data.decode().splitlines()]
    for row in rows:
        for key in ("wall_time", "search", "date"):
            row.pop(key, None)
    return rows


def assert_same_search_output(first: Path, second: Path) -> None:
    """Two runs' search output folders hold the same files: the log equal but for measured wall
    times, every frozen failure byte for byte but for its provenance time; at least one failure."""
    a, b = files(first), files(second)
    assert sorted(a) == sorted(b) and len(a) >= 2          # the log and at least one frozen failure
    for name in a:
        if name.endswith("search-log.jsonl"):
            assert log_without_times(a[name]) == log_without_times(b[name])
        else:
            assert without_timestamps(a[name]) == without_timestamps(b[name]), name   # byte for byte


def test_one_search_on_two_processes_writes_what_a_serial_run_writes(project: pytest.Pytester):
    args = ["-p", "no:cacheprovider", "--nav-subject=straight_planner:Straight", "--navsearch", "crate",
            "--budget", "40", "--navsearch-seed", "5"]
    serial = project.runpytest(*args, "--navsearch-out", "serial")
    parallel = project.runpytest(*args, "-n", "2", "--navsearch-out", "parallel")
    assert serial.ret == parallel.ret == 0, parallel.stdout.str()
    assert "each search evaluates its candidates on 2 local worker process(es)" in parallel.stdout.str()
    assert_same_search_output(project.path / "serial", project.path / "parallel")
    line = re.compile(r"crate vs .*: 40/40 sims.*")
    assert line.search(serial.stdout.str()) and line.search(parallel.stdout.str())
    assert "of them confirming" not in serial.stdout.str()


def test_a_search_under_noise_writes_the_same_files_serial_or_not_batched_or_not(project: pytest.Pytester):
    """Under sensor noise each failure is confirmed by runs under fresh noise seeds within the
    generation (search/holding.py), here by a planner whose failures are partly knife-edges (it
    reads its noisy first scan; PickyBatch): the same runs, decisions and files on two processes,
    with each worker's share in lockstep batches or not, as one episode at a time."""
    args = ["-p", "no:cacheprovider", "--nav-subject=straight_planner:PickyBatch", "--navsearch", "crate",
            "--budget", "40", "--navsearch-seed", "2", "--nav-sensor-model", "realistic"]
    runs = {name: project.runpytest(*args, *extra, "--navsearch-out", name) for name, extra in [
        ("serial", ["--nav-batch", "off"]), ("batched", []), ("parallel", ["-n", "2", "--nav-batch", "off"]),
        ("parallel-batched", ["-n", "2"])]}
    for name, result in runs.items():
        assert result.ret == 0, (name, result.stdout.str())
        assert re.search(r"crate vs .*: 40/40 sims.* searching \(\d+ of them confirming\)", result.stdout.str()), name
        assert ("batches (--nav-batch)" in result.stdout.str()) == name.endswith("batched"), name
        if name != "serial":
            assert_same_search_output(project.path / "serial", project.path / name)
    log = (project.path / "serial" / "crate" / "search-log.jsonl").read_text()
    assert '"status": "rejected"' in log or '"status": "unconfirmed"' in log   # not every failure held


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_interrupting_a_search_under_n2_keeps_what_it_found(project: pytest.Pytester, sig: int):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(project.path), str(ROOT),
                                                       os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-n", "2",
         "--nav-subject=straight_planner:SlowStraight", "--navsearch", "crate", "--budget", "300"],
        cwd=project.path, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        start_new_session=True)
    assert proc.stdout is not None
    deadline = time.monotonic() + 120
    seen = ""
    while time.monotonic() < deadline:   # progress lines: wait for the first failure found
        line = proc.stdout.readline()
        seen += line
        if re.search(r"navsearch crate: \d+/300 sims, [1-9]\d* distinct failure", line) or not line:
            break
    time.sleep(0.3)
    os.killpg(proc.pid, sig) if sig == signal.SIGINT else proc.send_signal(sig)   # Ctrl-C: the group
    out = seen + proc.communicate(timeout=120)[0]
    assert proc.returncode == pytest.ExitCode.INTERRUPTED, out[-3000:]
    assert "CUT SHORT: interrupted" in out, out[-3000:]
    sims = int(re.search(r"\): (\d+)/300 sims", out).group(1))
    assert 0 < sims < 300
    folder = project.path / "scenarios" / "regressions" / "crate"
    log = [r for r in map(json.loads, (folder / "search-log.jsonl").read_text().splitlines())
           if r["record"] == "candidate"]
    assert len([r for r in log if r["phase"] == "search"]) == sims
    assert any(r["outcome"] != "success" for r in log)
    frozen = sorted(folder.glob("crate-*.yaml"))
    assert frozen, out[-3000:]
    notes = [f.read_text() for f in frozen]
    assert any("not shrunk: the search was interrupted" in text for text in notes) or \
        any(r["phase"] == "shrink" for r in log)            # interrupted while shrinking: the rest are


def test_a_negative_worker_count_is_a_usage_error(project: pytest.Pytester):
    result = project.runpytest("-p", "no:cacheprovider", "--nav-subject=straight_planner:Straight",
                               "--navsearch", "crate", "-n", "-1")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert "-n -1: the number of worker processes must be 0 or more" in result.stderr.str()


# -- the evaluator in this process ----------------------------------------------------------------
class LoggingExecutor(SerialExecutor):
    """Runs each job here, when its result is asked for, and logs what was submitted when."""

    def __init__(self):
        self.log: list[str] = []

    def submit(self, jobs):
        self.log.extend(type(job).__name__ + ("+known" if getattr(job, "known", ()) else "") for job in jobs)
        return super().submit(jobs)


def test_failures_start_shrinking_while_the_search_goes_on_and_nothing_changes():
    lane = loads_scenario(OPEN_YAML, "lane.yaml", name="lane")
    serial = run_search(lane, Straight, budget=40, seed_value=2, shrink_budget=6)
    executor = LoggingExecutor()
    via_jobs = run_search(lane, Straight, budget=40, seed_value=2, shrink_budget=6,
                          evaluator=executor_evaluator(executor))
    assert _fingerprint(via_jobs) == _fingerprint(serial)
    assert [f.note for f in via_jobs.failures] == [f.note for f in serial.failures]
    assert len(serial.failures) >= 2 and serial.shrink_sims > 0
    log = executor.log
    assert log.count("ShrinkJob") == len(serial.failures) and log.count("CandidateJob") == 40
    assert log.index("ShrinkJob") < len(log) - 1 - log[::-1].index("CandidateJob")   # before the search ended


@pytest.mark.parametrize("seed_yaml, search_seed", [("crate", 10), ("lane", 1)])
def test_a_shrink_begun_during_the_search_with_a_smaller_cap_is_continued_not_rerun(seed_yaml, search_seed):
    """The shrink budget as a share is shared out after the search; a failure's shrinking starts
    when it is found with the smallest cap the plan can give, and afterwards is continued with its
    planned cap (replaying what it simulated), kept (the same cap) or given up (no cap): the
    same log and files as a serial run. crate: 2 failures share 40 simulations (20 each; one is
    done after 10); lane: 6 failures, the 4 that matter most get 10 each."""
    seed = loads_scenario(SEED_YAML.replace("name: crate\n", ""), "crate.yaml", name="crate") \
        if seed_yaml == "crate" else loads_scenario(OPEN_YAML, "lane.yaml", name="lane")
    serial = run_search(seed, Straight, budget=40, seed_value=search_seed, shrink_budget="100%")
    executor = LoggingExecutor()
    via_jobs = run_search(seed, Straight, budget=40, seed_value=search_seed, shrink_budget="100%",
                          evaluator=executor_evaluator(executor))
    assert _fingerprint(via_jobs) == _fingerprint(serial)
    assert [(f.note, f.shrink_sims) for f in via_jobs.failures] == [(f.note, f.shrink_sims) for f in serial.failures]
    used = sorted(f.shrink_sims for f in serial.failures)
    log = executor.log
    end = len(log) - log[::-1].index("CandidateJob")          # the search's last candidate, + 1
    during, after = log[:end], log[end:]
    if seed_yaml == "crate":
        assert used == [10, 20], used
        assert during.count("ShrinkJob") == 2                 # each begun with the early cap of 10
        assert after == ["ShrinkJob+known"] * 2               # and continued with 20 each
    else:
        assert used == [0, 0, 10, 10, 10, 10], used
        assert during.count("ShrinkJob") == 4                 # the first 4 found: at most 40 // 10 get a cap
        assert after == ["ShrinkJob"]                         # one found later outranks one of them
    assert via_jobs.shrink_sims == serial.shrink_sims


def test_a_search_stopped_early_on_workers_leaves_no_job_behind():
    lane = loads_scenario(OPEN_YAML, "lane.yaml", name="lane")
    seen: list[int] = []
    pool = ProcessExecutor(2)
    try:
        report = run_search(lane, Straight, budget=300, seed_value=2, shrink_budget=40,
                            evaluator=executor_evaluator(pool), progress=lambda r: seen.append(len(r.failures)),
                            stop=lambda: bool(seen) and seen[-1] >= 2)
        assert pool._open == {}        # in-flight generations and shrink jobs given up, not left running
        assert report.interrupted and 0 < report.sims_used < 300 and len(report.failures) >= 2
        assert all(f.note == "not shrunk: the search was interrupted" for f in report.failures)
        again = run_search(lane, Straight, budget=8, seed_value=2, shrink_budget=0, evaluator=executor_evaluator(pool))
        assert again.sims_used == 8   # the same workers serve the next search
    finally:
        pool.close()
