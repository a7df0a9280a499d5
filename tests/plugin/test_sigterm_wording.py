"""A search stopped by SIGTERM (a cancelled CI job) says SIGTERM, not "Ctrl-C", in its summary and
in pytest's "Interrupted:" line (issue 26, "Also"). A real pytest run in a subprocess whose
planner factory sends SIGTERM to its own process on the sixth episode."""
from __future__ import annotations

import pytest

SEED = """version: 1
mission: {start: {x: 0, y: 0, yaw: 90}, goal: {x: 0, y: 5, yaw: 90}, timeout: 12}
obstacles: [{type: box, name: crate, x: 1.2, y: 2.5, length: 0.6, width: 0.6}]
search: {obstacle_dx: [-1.5, 0.5], obstacle_dy: 0.5, obstacle_size: 0, obstacle_yaw: 0, insert: 0}
"""
PLANNER = '''
import os
import signal

CALLS = [0]


class Straight:
    def reset(self, scenario):
        pass

    def act(self, obs):
        return (1.0, 0.0, 0.0)


def terminated_after_five():
    """The sixth episode's planner is never made: the run receives SIGTERM."""
    CALLS[0] += 1
    if CALLS[0] > 5:
        os.kill(os.getpid(), signal.SIGTERM)
    return Straight()
'''


def test_a_search_stopped_by_sigterm_says_sigterm(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(sigterm_planner=PLANNER)
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "crate.yaml").write_text(SEED)
    pytester.makeini("[pytest]\npythonpath = .\n")
    result = pytester.runpytest_subprocess("-p", "pytest_navscenario.plugin", "--nav-plots=none",
                                           "--nav-subject=sigterm_planner:terminated_after_five",
                                           "--navsearch", "crate", "--budget", "50", timeout=300)
    out = result.stdout.str()
    assert result.ret == pytest.ExitCode.INTERRUPTED, out[-3000:]
    assert "CUT SHORT: interrupted (SIGTERM)" in out, out[-3000:]
    assert "Interrupted: navsearch crate was cut short by SIGTERM" in out
    assert "Ctrl-C" not in out
