"""A user's MJCF controller that hangs, raises, interrupts itself or leaves processes behind, through
real pytest runs and real ``navscenario run`` commands: a subject error of its own item with a
record in the results file, the tick limit bounding it (with and without --nav-isolate), the next
item run; ``navscenario run`` calls the controller's or planner's own KeyboardInterrupt a subject
error and ends the processes it left running, saying so (issue 38, part 3)."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pytest_navscenario.report.results_file import read_results

ROOT = Path(__file__).resolve().parents[2]
PLUGIN = ["-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider",
          "--nav-subject=tests.search.straight_planner:Straight", "--nav-plots=none"]
HEAD = "version: 1\nmission: {{start: {{x: 0, y: 0}}, goal: {{x: 3, y: 0}}, timeout: 8}}\nrobot:\n  drive: diff\n  body: {body}\n"
CONTROLLER = (ROOT / "tests" / "sim" / "cart_controller.py").read_text()


def body(name: str) -> str:
    return HEAD.format(body=f'{{type: mjcf, file: cart.xml, controller: "my_cart:{name}"}}')


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    folder = pytester.path / "scenarios"
    folder.mkdir()
    shutil.copy(ROOT / "tests" / "data" / "mjcf" / "cart.xml", folder / "cart.xml")
    (pytester.path / "my_cart.py").write_text(CONTROLLER)
    for name in ("Sleeps", "Raises", "Cart"):
        (folder / f"a-{name.lower()}.yaml").write_text(body(name))
    return pytester


@pytest.mark.parametrize("isolate", ["no", "yes"])
def test_a_hanging_or_raising_controller_is_a_subject_error_with_a_record(project, isolate):
    t0 = time.monotonic()
    result = project.runpytest_subprocess(*PLUGIN, "scenarios", "--nav-results=r.jsonl", "--nav-tick-limit=0.3",
                                          f"--nav-isolate={isolate}", timeout=120)
    assert time.monotonic() - t0 < 60, "the sleeping controller was not cut at the tick limit"
    out = result.stdout.str()
    records = {r["scenario"]: r for r in read_results(project.path / "r.jsonl")}
    assert set(records) == {"a-sleeps", "a-raises", "a-cart"}, out[-3000:]
    assert records["a-sleeps"]["outcome"] == "subject-error"
    assert "per-tick limit of 0.3 s" in records["a-sleeps"]["message"]
    assert records["a-raises"]["outcome"] == "subject-error"
    assert "motor driver offline" in records["a-raises"]["message"]
    assert records["a-cart"]["outcome"] == "success"


def navscenario(cwd: Path, *args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(cwd)]))
    return subprocess.run([sys.executable, "-c", "import sys; from pytest_navscenario.cli.main import main; "
                           "sys.exit(main())", "run", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout)


def test_run_calls_a_controllers_own_keyboard_interrupt_a_subject_error(project):
    (project.path / "scenarios" / "own-interrupt.yaml").write_text(body("Interrupts"))
    done = navscenario(project.path, "scenarios/own-interrupt.yaml", "-s", "tests.search.straight_planner:Straight")
    assert done.returncode == 1, done.stdout + done.stderr          # a failing outcome, not 130 "interrupted"
    assert "outcome: subject-error" in done.stdout and "KeyboardInterrupt: my own" in done.stdout
    assert "interrupted" not in done.stderr


def test_run_calls_a_planners_own_keyboard_interrupt_a_subject_error(project):
    (project.path / "ctrlc_planner.py").write_text(
        "class P:\n    def reset(self, scenario):\n        pass\n"
        "    def act(self, obs):\n        raise KeyboardInterrupt('planner own')\n")
    (project.path / "plain.yaml").write_text(
        "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 3, y: 0}, timeout: 8}\n")
    done = navscenario(project.path, "plain.yaml", "-s", "ctrlc_planner:P")
    assert done.returncode == 1, done.stdout + done.stderr
    assert "outcome: subject-error" in done.stdout and "planner own" in done.stdout


def test_run_ends_and_reports_the_processes_a_controller_left(project):
    (project.path / "scenarios" / "forks.yaml").write_text(body("Forks"))
    done = navscenario(project.path, "scenarios/forks.yaml", "-s", "tests.search.straight_planner:Straight")
    assert "ended 1 process(es) the planner or controller had left running" in done.stderr, done.stderr
    pid = int(done.stderr.split("pid ")[1].split(":")[0])
    assert not Path(f"/proc/{pid}").exists() or "Z" in Path(f"/proc/{pid}/stat").read_text().split(")")[1][:3]
