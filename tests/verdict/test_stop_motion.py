"""Issue 32 item 6: a robot the safety layer halts while turning in place was "predicted to hit
'pallet_a' at 0.00 m/s", which reads as a robot standing still stopped for nothing. Real episode:
potential-field turns in place towards a goal beside it, its footprint's sweep reaching a pallet."""
from __future__ import annotations

import pytest

from pytest_navscenario import loads_scenario, run_scenario

TURN = """version: 1
robot:
  footprint: {shape: box, length: 0.9, width: 0.5}
  drive: diff
  safety: {enabled: true, horizon: 0.5, margin: 0.05}
mission:
  start: {x: 0, y: 0, yaw: 0}
  goal: {x: 0, y: 4}
  timeout: 20
obstacles:
  - {type: box, name: pallet_a, x: 0.2, y: 0.45, length: 0.4, width: 0.3}
"""


def test_a_stop_while_turning_in_place_says_so():
    result = run_scenario(loads_scenario(TURN, "turn.yaml"), "potential-field")
    assert result.outcome.value == "safety-stop"
    assert result.message == "safety stop at t=0.10 s: predicted to hit 'pallet_a' turning in place at 15 deg/s"
    assert "0.00 m/s" not in result.message


def test_the_failure_header_says_it_too(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makefile(".yaml", turn=TURN)
    out = pytester.runpytest("-p", "pytest_navscenario.plugin", "turn.yaml", "--nav-subject=potential-field",
                             "--nav-plots=none").stdout.str()
    assert "  safety stop:   predicted hit of obstacle 'pallet_a' at t=0.10 s, turning in place at 15 deg/s" in out, out
    assert "0.00 m/s" not in out
