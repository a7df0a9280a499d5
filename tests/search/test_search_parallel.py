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

from test_search import SEED_YAML
# Before pytester's in-process runs snapshot sys.modules: a worker pool pickles functions of
# concurrent.futures by reference, which fails if a later run re-imports that module.
import pytest_navscenario.dispatch.local  # noqa: E402,F401

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
    """The search log with each simulation's measured wall time removed (it differs between any
    two runs, serial or not); everything else must match bit for bit."""
    rows = [json.loads(line) for line in data.decode().splitlines()]
    for row in rows:
        row.pop("wall_time", None)
    return rows


def test_one_search_on_two_processes_writes_what_a_serial_run_writes(project: pytest.Pytester):
    args = ["-p", "no:cacheprovider", "--nav-subject=straight_planner:Straight", "--navsearch", "crate",
            "--budget", "40", "--navsearch-seed", "5"]
    serial = project.runpytest(*args, "--navsearch-out", "serial")
    parallel = project.runpytest(*args, "-n", "2", "--navsearch-out", "parallel")
    assert serial.ret == parallel.ret == 0, parallel.stdout.str()
    assert "each search evaluates its candidates on 2 local worker process(es)" in parallel.stdout.str()
    a, b = files(project.path / "serial"), files(project.path / "parallel")
    assert sorted(a) == sorted(b) and len(a) >= 2          # the log and at least one frozen failure
    for name in a:
        if name.endswith("search-log.jsonl"):
            assert log_without_times(a[name]) == log_without_times(b[name])
        else:
            assert without_timestamps(a[name]) == without_timestamps(b[name]), name   # byte for byte
    line = re.compile(r"crate vs .*: 40/40 sims.*")
    assert line.search(serial.stdout.str()) and line.search(parallel.stdout.str())


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
    log = [json.loads(line) for line in (folder / "search-log.jsonl").read_text().splitlines()]
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
