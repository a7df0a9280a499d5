"""Nothing a planner starts outlives the run (issue 26, item 12): an ``exec:`` planner that starts
children (as a launch file starts nodes) has its whole process group ended, and the processes an
in-process planner starts with Popen or fork and leaves running are reported with the item and
ended when the run ends. Real pytest runs in subprocesses, real forking planners; what is still
running afterwards is read from /proc (no psutil)."""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc (Linux)")

SCENARIO = "version: 1\nmission: {{start: {{x: 0, y: 0}}, goal: {{x: {x}, y: 0}}, timeout: 10}}\n"

# A helper process that sleeps for 5 minutes, with a marker in its command line.
HELPER = '["{python}", "-c", "import time; time.sleep(300)", "{marker}"]'

# An exec: planner in Python that starts two helpers in its own process group ("nodes") and
# answers the protocol by driving straight.
EXEC_PLANNER = '''#!{python}
import json, subprocess, sys
for _ in range(2):
    subprocess.Popen(HELPER)
for line in sys.stdin:
    msg = json.loads(line)
    if msg["type"] == "reset":
        print(json.dumps({{"type": "ready", "name": "spawner"}}), flush=True)
    elif msg["type"] == "observation":
        print(json.dumps({{"type": "command", "vx": 0.8, "vy": 0.0, "wz": 0.0}}), flush=True)
    elif msg["type"] == "shutdown":
        break
'''

# In-process planners: one starts a `sleep` with Popen in reset and never ends it; the other forks,
# and its child sleeps (a copy of pytest: recognised by the pid it writes down).
IN_PROCESS = '''
import os, subprocess, time


class Popener:
    def reset(self, scenario):
        self.helper = subprocess.Popen(HELPER)

    def act(self, obs):
        return (0.8, 0.0, 0.0)


class Forker:
    def reset(self, scenario):
        pid = os.fork()
        if pid == 0:
            time.sleep(300)
            os._exit(0)
        with open("forked.pids", "a") as fh:
            fh.write(f"{pid}\\n")

    def act(self, obs):
        return (0.8, 0.0, 0.0)
'''


def running_with(marker: str) -> list[int]:
    """Live (not zombie) processes whose command line holds ``marker``."""
    found = []
    for pid in (p for p in os.listdir("/proc") if p.isdigit()):
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if marker.encode() in cmd and state != "Z":
            found.append(int(pid))
    return found


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def settle(check, seconds: float = 5.0):
    """The processes need a moment to go after pytest has exited: poll ``check`` until it is falsy."""
    deadline = time.monotonic() + seconds
    value = check()
    while value and time.monotonic() < deadline:
        time.sleep(0.05)
        value = check()
    return value


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch, request) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    marker = f"navscenario-test-marker-{os.getpid()}-{request.node.name[-40:]}"
    pytester.marker = marker  # type: ignore[attr-defined]
    program = pytester.path / "spawner.py"
    helper = HELPER.format(python=sys.executable, marker=marker)
    program.write_text(EXEC_PLANNER.format(python=sys.executable).replace("HELPER", helper))
    program.chmod(0o755)
    pytester.makepyfile(inproc=IN_PROCESS.replace("HELPER", helper))
    (pytester.path / "scenarios").mkdir()
    for i in range(3):
        (pytester.path / "scenarios" / f"s{i}.yaml").write_text(SCENARIO.format(x=0.5 + i / 10))
    pytester.makeini("[pytest]\npythonpath = .\n")
    return pytester


def run(pytester: pytest.Pytester, *args: str) -> pytest.RunResult:
    return pytester.runpytest_subprocess("-p", "pytest_navscenario.plugin", "-p", "xdist.plugin", "scenarios",
                                         "--nav-plots=none", *args, timeout=300)


@pytest.mark.parametrize("workers", [[], ["-n", "2"]], ids=["serial", "n2"])
def test_an_exec_planners_children_end_with_it(project: pytest.Pytester, workers: list[str]):
    """Before: only the program itself was ended; its two helpers were left with parent 1."""
    result = run(project, "--nav-subject=exec:./spawner.py", *workers)
    result.assert_outcomes(passed=3)
    assert settle(lambda: running_with(project.marker)) == [], "the exec: planner's children outlived the run"


@pytest.mark.parametrize("workers", [[], ["-n", "2"]], ids=["serial", "n2"])
def test_processes_an_in_process_planner_leaves_are_reported_and_ended(project: pytest.Pytester,
                                                                       workers: list[str]):
    """Before: the three helpers (one per episode) were left running, and no word said so."""
    result = run(project, "--nav-subject=inproc:Popener", *workers)
    result.assert_outcomes(passed=3, warnings=3)
    out = result.stdout.str()
    assert "LeftRunningWarning: scenarios/s0.yaml: the planner left 1 process(es) running after its episode" in out
    assert "time.sleep(300) navscenario-test-marker" in out
    if not workers:   # ended by this process (with -n 2: by the workers, as the pool closes)
        assert "navscenario: ended 3 process(es) the planner had left running" in out
    assert settle(lambda: running_with(project.marker)) == []


def test_a_planner_that_forks_leaves_no_process_behind(project: pytest.Pytester):
    result = run(project, "--nav-subject=inproc:Forker")
    result.assert_outcomes(passed=3, warnings=3)
    pids = [int(p) for p in (project.path / "forked.pids").read_text().split()]
    assert len(pids) == 3
    assert settle(lambda: [p for p in pids if alive(p)]) == []
