"""Issue 15 item 6: an exec: subject whose program does not exist or cannot start is a usage error
at session start; the reset wait is an option (--nav-reset-timeout, ini nav_reset_timeout); after
the first item whose reset timed out, the other items of that subject fail fast with the same
message. Real pytest runs (subprocesses) with real external programs."""
from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pytest_navscenario.report.results_file import read_results

SCENARIO = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1.5, y: 0}, timeout: 8}\n"
SILENT = "import sys\nfor line in sys.stdin:\n    pass   # reads every message, never answers\n"


def _run(root: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "pytest_navscenario.plugin", "-p",
                           "no:cacheprovider", "--nav-plots=none", *args],
                          cwd=root, env=env, capture_output=True, text=True, timeout=120)


@pytest.fixture
def project(tmp_path: Path) -> Path:
    (tmp_path / "s").mkdir()
    for name in ("a", "b", "c"):
        (tmp_path / "s" / f"{name}.yaml").write_text(SCENARIO)
    return tmp_path


def _script(path: Path, text: str, mode: int = 0o755) -> Path:
    path.write_text(text)
    path.chmod(mode)
    return path


@pytest.mark.parametrize("make, message", [
    (lambda root: "no_such_planner_program_xyz --fast", "no such program 'no_such_planner_program_xyz' on PATH"),
    (lambda root: str(root / "missing.py"), "no such program"),
    (lambda root: str(_script(root / "noexec.py", "print()\n", 0o644)), "is not executable"),
    (lambda root: str(_script(root / "badshebang", "#!/no/such/interpreter\n")), "cannot start external planner"),
])
def test_a_program_that_cannot_start_is_a_usage_error_at_session_start(project, make, message):
    spec = make(project)
    proc = _run(project, "s", f"--nav-subject=exec:{spec}")
    assert proc.returncode == pytest.ExitCode.USAGE_ERROR, proc.stdout + proc.stderr
    assert message in proc.stderr and "ERROR: navscenario: " in proc.stderr
    assert "passed" not in proc.stdout and "failed" not in proc.stdout


@pytest.mark.parametrize("how", ["option", "ini"])
def test_reset_timeout_is_an_option_and_later_items_fail_fast(project, how):
    program = _script(project / "silent.py", "#!" + sys.executable + "\n" + SILENT)
    args = ["s", f"--nav-subject=exec:{program}", "--nav-results=r.jsonl"]
    if how == "option":
        args.append("--nav-reset-timeout=0.5")
    else:
        (project / "pytest.ini").write_text("[pytest]\nnav_reset_timeout = 0.5\n")
    t0 = time.monotonic()
    proc = _run(project, *args)
    took = time.monotonic() - t0
    out = proc.stdout
    assert proc.returncode == pytest.ExitCode.TESTS_FAILED, out + proc.stderr
    assert "3 failed" in out
    assert took < 10, f"{took:.1f} s: the later items did not fail fast"
    records = read_results(project / "r.jsonl")
    assert [r["outcome"] for r in records] == ["subject-error"] * 3
    messages = [r["message"] for r in records]
    assert all("external planner did not answer reset within 0.5 s" in m for m in messages)
    assert ["not retried: an earlier reset of this planner timed out" in m for m in messages] == \
        [False, True, True]


def test_bad_reset_timeout_is_a_usage_error(project):
    proc = _run(project, "s", "--nav-reset-timeout=-2")
    assert proc.returncode == pytest.ExitCode.USAGE_ERROR
    assert "--nav-reset-timeout: expected seconds > 0" in proc.stderr
