"""Interrupting a run (SIGTERM, as a cancelled CI job sends; Ctrl-C takes the same path) keeps
valid output: the results file holds exactly the episodes that finished, complete and parseable,
no temporary file is left behind, and the summary says the run was interrupted."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pytest_navscenario.report.results_file import read_results

SLOW_PLANNER = '''
import time


class Slow:
    """Drives to the goal, taking 20 ms per tick: each episode lasts about half a second."""
    def reset(self, scenario):
        pass

    def act(self, obs):
        time.sleep(0.02)
        return (0.0, 0.8, 0.0)
'''

SCENARIO = """version: 1
mission: {{start: {{x: 0, y: 0, yaw: 0}}, goal: {{x: 0, y: 2, yaw: 0}}, timeout: 6}}
obstacles: [{{type: box, name: crate, x: {x}, y: 1, length: 0.5, width: 0.5}}]
"""


# xdist's own workers are heavy (~5 s quiet): the results file is written by the same code as with
# the plugin's worker processes, which the default run interrupts.
@pytest.mark.parametrize("workers", [[], pytest.param(["-p", "xdist.plugin", "-n", "2", "--dist", "load"],
                                                      marks=pytest.mark.heavy),
                                     ["-p", "xdist.plugin", "-n", "2"]], ids=["serial", "xdist", "nav-workers"])
def test_sigterm_mid_run_keeps_a_valid_results_file(tmp_path: Path, workers: list[str]):
    (tmp_path / "slow.py").write_text(SLOW_PLANNER)
    suite = tmp_path / "suite"
    suite.mkdir()
    for i in range(40):
        (suite / f"s{i:02d}.yaml").write_text(SCENARIO.format(x=1.5 + i * 0.01))
    # tmp_path for the planner, then the caller's path (the checkout under test, when it is not installed)
    path = os.pathsep.join(p for p in (str(tmp_path), os.environ.get("PYTHONPATH", "")) if p)
    env = dict(os.environ, PYTEST_DISABLE_PLUGIN_AUTOLOAD="1", PYTHONPATH=path)
    proc = subprocess.Popen(
        [sys.executable, "-m", "pytest", "-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider",
         *workers, "suite", "--nav-subject=slow:Slow", "--nav-results=out/r.jsonl", "--nav-plots=none",
         "-v"],
        cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    seen = 0
    assert proc.stdout is not None
    deadline = time.monotonic() + 60
    while seen < 4 and time.monotonic() < deadline:   # wait until a few episodes have finished
        line = proc.stdout.readline()
        seen += " PASSED" in line or "] PASSED" in line
    proc.send_signal(signal.SIGTERM)
    out, _ = proc.communicate(timeout=60)
    assert proc.returncode == pytest.ExitCode.INTERRUPTED, out[-2000:]
    assert "KeyboardInterrupt" in out or "Interrupted" in out or "interrupted" in out
    records = read_results(tmp_path / "out" / "r.jsonl")    # parses and checks every record
    assert 4 <= len(records) < 40
    assert all(r["outcome"] == "success" for r in records)
    assert len({r["nodeid"] for r in records}) == len(records)
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["r.jsonl"]   # no temp file left
