"""Local executors: a batch of episodes on worker processes gives, in job order, the same bits as
running them here; an episode's exception comes back as itself; a killed worker loses nothing."""
from __future__ import annotations

import dataclasses
import os
import signal
import sys
import threading
import time
from pathlib import Path

import pytest

from dispatch_helpers import KILLABLE_PLANNER, assert_same_bits, scenario_text
from pytest_navscenario.core.errors import SubjectLoadError
from pytest_navscenario.dispatch.jobs import EpisodeJob
from pytest_navscenario.dispatch.local import ProcessExecutor, SerialExecutor
from pytest_navscenario.scenario.loader import load_scenario, loads_scenario

ROOT = Path(__file__).resolve().parents[2]


def shipped_jobs(keep: str = "all") -> list[EpisodeJob]:
    jobs = [EpisodeJob(load_scenario(p), "dwa", tick_limit=None, keep_trajectory=keep)
            for p in sorted((ROOT / "scenarios").glob("*.yaml"))[:3]]
    # a base seed mixes into the sensor noise; another subject; a mission too short: a timeout
    jobs.append(EpisodeJob(jobs[0].scenario, "dwa", seed=7, keep_trajectory=keep))
    jobs.append(EpisodeJob(jobs[1].scenario, "potential-field", keep_trajectory=keep))
    short = dataclasses.replace(jobs[2].scenario, mission=dataclasses.replace(jobs[2].scenario.mission, timeout=1.5))
    jobs.append(EpisodeJob(short, "dwa", keep_trajectory=keep))
    return jobs


def test_process_pool_gives_the_serial_bits_in_job_order():
    jobs = shipped_jobs()
    serial = SerialExecutor().map(jobs)
    pool = ProcessExecutor(2)
    try:
        pending = pool.submit(jobs)
        parallel = [p.result() for p in reversed(pending)][::-1]   # asked for out of order
    finally:
        pool.close()
    assert len(parallel) == len(jobs)
    for job, a, b in zip(jobs, serial, parallel):
        assert_same_bits(a, b)
        assert b.scenario is job.scenario   # the worker does not send the scenario back
        assert len(b.trajectory.t) > 10     # keep_trajectory="all"


def test_trajectories_travel_only_when_asked_for():
    jobs = shipped_jobs(keep="failed")
    pool = ProcessExecutor(2)
    try:
        results = pool.map(jobs)
    finally:
        pool.close()
    assert {r.passed for r in results} == {True, False}
    for r in results:
        assert (len(r.trajectory.t) > 0) == (not r.passed)


def test_an_episode_error_is_raised_as_itself_and_the_batch_goes_on(tmp_path: Path):
    good = shipped_jobs()[0]
    bad = EpisodeJob(good.scenario, "no_such_module_xyz:Planner")
    with pytest.raises(SubjectLoadError) as serial:
        SerialExecutor().map([bad])
    pool = ProcessExecutor(2)
    try:
        first, second = pool.submit([bad, good])
        with pytest.raises(SubjectLoadError) as remote:
            first.result()
        assert second.result().passed
    finally:
        pool.close()
    assert str(remote.value) == str(serial.value)
    assert "no_such_module_xyz" in str(remote.value)


def test_a_killed_worker_loses_nothing_and_duplicates_nothing(tmp_path: Path, monkeypatch):
    (tmp_path / "killable_local.py").write_text(KILLABLE_PLANNER.format(log_dir=str(tmp_path)))
    monkeypatch.syspath_prepend(str(tmp_path))          # workers get the parent's sys.path
    names = ["a", "b", "victim", "c", "d", "e"]
    jobs = [EpisodeJob(loads_scenario(scenario_text(n, 1.0 + i / 10)), "killable_local:Planner",
                       keep_trajectory="all") for i, n in enumerate(names)]
    killed = []

    def kill_the_victim() -> None:
        marker = tmp_path / "victim.pid"
        deadline = time.monotonic() + 60
        while not marker.exists() and time.monotonic() < deadline:
            time.sleep(0.02)
        pid = int(marker.read_text())
        os.kill(pid, signal.SIGKILL)
        killed.append(pid)

    killer = threading.Thread(target=kill_the_victim)
    killer.start()
    pool = ProcessExecutor(2)
    try:
        results = pool.map(jobs)
    finally:
        pool.close()
        killer.join()
    assert killed, "the victim episode never started"
    assert [r.scenario.name for r in results] == names
    serial = SerialExecutor().map(jobs)   # the marker exists now: no sleep
    for a, b in zip(serial, results):
        assert_same_bits(a, b)
    resets = [line.split() for line in (tmp_path / "resets.log").read_text().splitlines()]
    victim_pids = [row[0] for row in resets if row[1] == "victim"]
    assert str(killed[0]) in victim_pids and len(set(victim_pids)) >= 2, resets   # ran again elsewhere


def test_worker_count_and_subject_are_checked_before_any_episode():
    with pytest.raises(ValueError, match="at least one worker"):
        ProcessExecutor(0)
    with pytest.raises(ValueError, match="at least one worker"):
        ProcessExecutor(-2)
    pool = ProcessExecutor(2)
    with pytest.raises(ValueError, match="module-level class or function"):
        pool.check_picklable(lambda: None)
    pool.check_picklable("dwa")
    pool.close()   # never started: nothing to stop


def test_close_with_cancel_stops_running_workers_at_once(tmp_path: Path, monkeypatch):
    (tmp_path / "killable_cancel.py").write_text(KILLABLE_PLANNER.format(log_dir=str(tmp_path)))
    monkeypatch.syspath_prepend(str(tmp_path))
    job = EpisodeJob(loads_scenario(scenario_text("victim", 1.0)), "killable_cancel:Planner")
    pool = ProcessExecutor(1)
    pool.submit([job])
    marker = tmp_path / "victim.pid"
    deadline = time.monotonic() + 60
    while not marker.exists() and time.monotonic() < deadline:
        time.sleep(0.02)
    pid = int(marker.read_text())
    t0 = time.monotonic()
    pool.close(cancel=True)            # what Ctrl-C does: the sleeping episode is not waited for
    assert time.monotonic() - t0 < 10
    deadline = time.monotonic() + 10
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(pid)


def test_a_cancelled_job_that_has_not_started_never_runs(tmp_path: Path, monkeypatch):
    (tmp_path / "killable_skip.py").write_text(KILLABLE_PLANNER.format(log_dir=str(tmp_path)))
    monkeypatch.syspath_prepend(str(tmp_path))
    names = ["victim"] + [f"s{i}" for i in range(5)]
    jobs = [EpisodeJob(loads_scenario(scenario_text(name, 1.0 + i / 10)), "killable_skip:Planner")
            for i, name in enumerate(names)]
    pool = ProcessExecutor(1)
    try:
        pending = pool.submit(jobs)      # the one worker sleeps in the victim's reset
        for p in pending[2:]:
            p.cancel()                   # a search that stopped gives up what it no longer needs
        assert len(pool._open) == 2      # the cancelled ones are no longer the pool's
        marker = tmp_path / "victim.pid"
        deadline = time.monotonic() + 60
        while not marker.exists() and time.monotonic() < deadline:
            time.sleep(0.02)
        pending[1].cancel()
        assert pool._open and len(pool._open) == 1          # the victim, running: left to the pool
    finally:
        pool.close(cancel=True)
    ran = [line.split()[1] for line in (tmp_path / "resets.log").read_text().splitlines()]
    assert ran == ["victim"], ran     # the cancelled jobs never started


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    if sys.platform.startswith("linux"):   # a zombie is dead for our purpose
        try:
            return Path(f"/proc/{pid}/stat").read_text().split()[2] != "Z"
        except OSError:
            return False
    return True
