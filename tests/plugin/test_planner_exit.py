"""Issue 15 item 2: a planner whose own code calls sys.exit() or raises SystemExit or
KeyboardInterrupt in reset or act is that item's subject-error (with the planner's own frame);
the run goes on and every episode is in the results file. A real Ctrl-C still stops the run, and
an external (exec:) planner that exits is a subject error too. Real pytest runs in subprocesses."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pytest_navscenario.report.results_file import read_results

PLANNER = '''
import sys
import time


class Quitter:
    """Quits in the way its scenario's name says; drives to the goal otherwise."""
    def reset(self, scenario):
        self.how = scenario.name
        if self.how == "exit_in_reset":
            sys.exit("cannot find my map")

    def act(self, obs):
        if obs.tick == 2:
            if self.how == "exit_in_act":
                sys.exit(3)
            if self.how == "interrupt_in_act":
                raise KeyboardInterrupt("planner gives up")
            if self.how == "system_exit_in_act":
                raise SystemExit
        if self.how == "slow":
            time.sleep(0.02)
        return (0.8, 0.0, 0.0)
'''

SCENARIO = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1.5, y: 0}, timeout: 8}\n"
NAMES = ["exit_in_act", "exit_in_reset", "fine", "interrupt_in_act", "system_exit_in_act"]


def _env(root: Path) -> dict[str, str]:
    env = dict(os.environ, PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
    env["PYTHONPATH"] = os.pathsep.join([str(root), env.get("PYTHONPATH", "")])
    return env


def _pytest(root: Path, *args: str) -> list[str]:
    return [sys.executable, "-m", "pytest", "-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider",
            "--nav-plots=none", "--nav-subject=quitter:Quitter", "--nav-results=r.jsonl", *args]


@pytest.mark.parametrize("workers", [[], ["-p", "xdist.plugin", "-n", "2", "--dist", "load"],
                                     ["-p", "xdist.plugin", "-n", "2"]], ids=["serial", "xdist", "nav-workers"])
def test_planner_exit_is_a_subject_error_and_the_run_goes_on(tmp_path: Path, workers: list[str]):
    (tmp_path / "quitter.py").write_text(PLANNER)
    (tmp_path / "s").mkdir()
    for name in NAMES:
        (tmp_path / "s" / f"{name}.yaml").write_text(SCENARIO)
    proc = subprocess.run(_pytest(tmp_path, *workers, "s"), cwd=tmp_path, env=_env(tmp_path),
                          capture_output=True, text=True, timeout=180)
    out = proc.stdout + proc.stderr
    assert proc.returncode == pytest.ExitCode.TESTS_FAILED, out[-3000:]
    assert "4 failed, 1 passed" in out
    assert "INTERNALERROR" not in out and "pluggy/_callers" not in out
    records = {r["nodeid"].split("::")[1]: r for r in read_results(tmp_path / "r.jsonl")}
    assert sorted(records) == NAMES
    assert records["fine"]["outcome"] == "success"
    for name in NAMES:
        if name != "fine":
            assert records[name]["outcome"] == "subject-error", records[name]
    assert "SystemExit: 3" in out and "KeyboardInterrupt: planner gives up" in out
    assert "SystemExit: cannot find my map" in out
    assert 'quitter.py", line 16, in act' in out and 'quitter.py", line 11, in reset' in out


def test_a_real_ctrl_c_still_stops_the_run(tmp_path: Path):
    (tmp_path / "quitter.py").write_text(PLANNER)
    (tmp_path / "s").mkdir()
    for i in range(30):
        (tmp_path / "s" / f"slow{i:02d}.yaml").write_text("name: slow\n" + SCENARIO)
    proc = subprocess.Popen(_pytest(tmp_path, "s", "-v"), cwd=tmp_path, env=_env(tmp_path),
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert proc.stdout is not None
    seen, deadline = 0, time.monotonic() + 60
    while seen < 2 and time.monotonic() < deadline:
        seen += " PASSED" in proc.stdout.readline()
    time.sleep(0.1)                     # inside a planner's sleep most of the time
    proc.send_signal(signal.SIGINT)
    out, _ = proc.communicate(timeout=60)
    assert proc.returncode == pytest.ExitCode.INTERRUPTED, out[-2000:]
    assert "subject-error" not in out
    assert 2 <= len(read_results(tmp_path / "r.jsonl")) < 30


def test_an_external_planner_that_exits_is_a_subject_error(tmp_path: Path):
    program = tmp_path / "quits.py"
    program.write_text("import sys, json\nline = sys.stdin.readline()\nprint('bye', file=sys.stderr)\nsys.exit(3)\n")
    (tmp_path / "s").mkdir()
    for name in ("a", "b"):
        (tmp_path / "s" / f"{name}.yaml").write_text(SCENARIO)
    args = [a if not a.startswith("--nav-subject") else f"--nav-subject=exec:{sys.executable} {program}"
            for a in _pytest(tmp_path, "s")]
    proc = subprocess.run(args, cwd=tmp_path, env=_env(tmp_path), capture_output=True, text=True, timeout=120)
    out = proc.stdout + proc.stderr
    assert proc.returncode == pytest.ExitCode.TESTS_FAILED, out[-3000:]
    assert "external planner exited with status 3 while handling reset; its stderr ended with: bye" in out
    assert [r["outcome"] for r in read_results(tmp_path / "r.jsonl")] == ["subject-error"] * 2
