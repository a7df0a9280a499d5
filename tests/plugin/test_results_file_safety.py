"""Nothing lost in the results file (issue 26, item 1 and "Also"): a run that records no episode (a
search, a selection matching nothing) leaves the file as it was, and a second run writing the same
file is refused while the first one runs, instead of both saying "wrote N record(s)" and the file
keeping one run's. Real pytest runs, in this process and as subprocesses."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pytest_navscenario.report.results_file import read_results

SCENARIO = "version: 1\nmission: {{start: {{x: 0, y: 0}}, goal: {{x: {x}, y: 0}}, timeout: 10}}\n"
SEED = """version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 3, y: 0}, timeout: 10}
obstacles: [{type: box, name: crate, x: 1.5, y: 1.2, length: 0.4, width: 0.4}]
search: {obstacle_dx: 0.5, obstacle_dy: 0.5}
"""
HELD = '''
import os
import time


class Held:
    """Waits (up to 30 s) until the file "go" exists, then drives to the goal: the run stays busy
    for as long as the test needs it to."""
    def reset(self, scenario):
        deadline = time.monotonic() + 30
        while not os.path.exists("go") and time.monotonic() < deadline:
            time.sleep(0.02)

    def act(self, obs):
        return (0.8, 0.0, 0.0)
'''


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    (pytester.path / "scenarios").mkdir()
    for i in range(3):
        (pytester.path / "scenarios" / f"s{i}.yaml").write_text(SCENARIO.format(x=1 + i))
    (pytester.path / "seeds").mkdir()
    (pytester.path / "seeds" / "crate.yaml").write_text(SEED)
    # the docs' own example: the results file named in the ini file
    pytester.makeini("[pytest]\nnav_results = results.jsonl\nnav_scenario_paths = seeds\n")
    return pytester


def run(pytester: pytest.Pytester, *args: str) -> pytest.RunResult:
    return pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "--nav-plots=none", *args)


def test_a_search_leaves_the_results_file_of_the_suite_alone(project: pytest.Pytester):
    """Before: ``pytest scenarios`` wrote 3 records, then the search wrote "0 record(s)" over them."""
    assert run(project, "scenarios").ret == 0
    results = project.path / "results.jsonl"
    before = results.read_bytes()
    assert len(read_results(results)) == 3
    out = run(project, "--navsearch", "crate", "--budget", "3", "--navsearch-shrink-budget", "0")
    assert out.ret == 0, out.stdout.str()
    assert results.read_bytes() == before
    out.stdout.fnmatch_lines(["navscenario: a search records its simulations in its own log, not in the "
                              "results file; *results.jsonl was left as it was"])
    assert "record(s) to" not in out.stdout.str()


def test_a_run_that_recorded_no_episode_keeps_the_file(project: pytest.Pytester):
    assert run(project, "scenarios").ret == 0
    results = project.path / "results.jsonl"
    before = results.read_bytes()
    out = run(project, "scenarios", "-k", "matches_nothing")
    assert out.ret == pytest.ExitCode.NO_TESTS_COLLECTED
    assert results.read_bytes() == before
    out.stdout.fnmatch_lines(["navscenario: no episode ran, so the results file *results.jsonl was left as it was"])
    assert not list(project.path.glob(".results.jsonl*"))     # no lock file, no temporary file left


def start_run(folder: Path, *extra: str) -> subprocess.Popen:
    path = os.pathsep.join(p for p in (str(folder), os.environ.get("PYTHONPATH", "")) if p)
    env = dict(os.environ, PYTEST_DISABLE_PLUGIN_AUTOLOAD="1", PYTHONPATH=path)
    return subprocess.Popen(
        [sys.executable, "-m", "pytest", "-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider",
         "scenarios", "--nav-subject=held:Held", "--nav-results=out/r.jsonl", "--nav-plots=none", "-v",
         *extra], cwd=folder, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def wait_until_collected(proc: subprocess.Popen) -> None:
    """Until the run has started (its session start, where it takes the lock, is over)."""
    assert proc.stdout is not None
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if line.startswith("collect") or not line:
            return
    raise AssertionError("the first run did not start")


@pytest.fixture
def held(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    """A project whose planner holds a run until the test lets it go."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(held=HELD)
    pytester.syspathinsert()
    (pytester.path / "scenarios").mkdir()
    for i in range(4):
        (pytester.path / "scenarios" / f"s{i}.yaml").write_text(SCENARIO.format(x=0.5))
    return pytester


def run_here(pytester: pytest.Pytester) -> pytest.RunResult:
    """The same run as ``start_run``, in this process (one interpreter start-up less)."""
    return pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "scenarios", "--nav-subject=held:Held",
                                        "--nav-results=out/r.jsonl", "--nav-plots=none")


def test_a_second_run_writing_the_same_results_file_is_refused(held: pytest.Pytester):
    """Before: both runs said "wrote 4 record(s)" and the file kept only the last one's."""
    first = start_run(held.path)
    try:
        wait_until_collected(first)
        second = run_here(held)
        out = second.stdout.str()
        assert second.ret == pytest.ExitCode.USAGE_ERROR, out[-3000:]
        text = second.stderr.str()
        assert "another run is writing the results file" in text and f"pid {first.pid}" in text, text
        assert "--nav-results=r-2.jsonl" in text
        assert "PASSED" not in out
        (held.path / "go").write_text("")
        rest, _ = first.communicate(timeout=120)
    finally:
        if first.poll() is None:
            first.kill()
    assert first.returncode == 0, rest[-3000:]
    assert len(read_results(held.path / "out" / "r.jsonl")) == 4      # the first run's records, all of them
    assert [p.name for p in (held.path / "out").iterdir()] == ["r.jsonl"]   # its lock file is gone


def test_a_killed_writer_does_not_block_the_next_run(held: pytest.Pytester):
    """The lock dies with its holder (SIGKILL included): no stale lock to remove by hand."""
    first = start_run(held.path)
    wait_until_collected(first)
    first.send_signal(signal.SIGKILL)
    first.communicate(timeout=60)
    assert (held.path / "out" / ".r.jsonl.lock").exists()         # left behind by the killed run
    (held.path / "go").write_text("")
    again = run_here(held)
    assert again.ret == 0, again.stdout.str()[-3000:]
    assert len(read_results(held.path / "out" / "r.jsonl")) == 4
