"""Issue 32 item 3: a terrain-only scenario has no minimum clearance (no obstacles). Before, it was
written four ways: inf (Python), the string "inf" in `navscenario run --json` (where NaN in the same
object became null), null in the results file and "n/a at t=n/a, robot at (n/a, n/a)" in the
terminal. Now: inf in Python, null in every JSON, "none (no obstacles)" in every terminal text."""
from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from pytest_navscenario import cli
from pytest_navscenario.report.results_file import read_results

# terrain only, and nothing the body cannot cross (a 3 cm hump: no face counts as clearance, issue 36)
HUMP = """version: 1
robot: {drive: diff, body: {type: wheeled}}
mission: {start: {x: 0, y: 0}, goal: {x: 6, y: 0}, timeout: 30.0}
terrain:
  - {type: ramp, name: hump, x: 3, y: 0, length: 2, width: 3, rise: 0.03}
"""


@pytest.fixture
def hump(tmp_path: Path) -> Path:
    path = tmp_path / "hump.yaml"
    path.write_text(HUMP)
    return path


def test_navscenario_run_writes_null_in_json_and_none_in_text(capsys, hump):
    assert cli.main(["run", str(hump), "--json"]) == 0
    text = capsys.readouterr().out
    assert '"inf"' not in text and "NaN" not in text and "Infinity" not in text
    metrics = json.loads(text)["metrics"]
    assert metrics["min_clearance"] is None and metrics["min_obstacle_gap"] is None
    assert metrics["min_clearance_time"] is None
    assert cli.main(["run", str(hump)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "  min_clearance            none (no obstacles)" in lines
    assert "  min_obstacle_gap         none (fewer than 2 obstacles)" in lines
    assert "  min_clearance_time       n/a" in lines
    assert not any(" inf" in line or " nan" in line for line in lines), lines


def test_the_python_api_keeps_inf(hump):
    from pytest_navscenario import load_scenario, run_scenario
    assert math.isinf(run_scenario(load_scenario(hump), "dwa").metrics.min_clearance)


def test_the_failure_header_and_results_file(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "hump.yaml").write_text(HUMP.replace("timeout: 30.0", "timeout: 6.0"))
    result = pytester.runpytest("-p", "pytest_navscenario.plugin", "scenarios", "--nav-results=r.jsonl",
                                "--nav-plots=none")
    out = result.stdout.str()
    assert "  min clearance: none (no obstacles)" in out, out[-3000:]
    assert "n/a at t=n/a" not in out
    record = read_results(pytester.path / "r.jsonl")[0]
    assert record["outcome"] == "timeout" and record["metrics"]["min_clearance"] is None


def test_the_failure_header_says_timeout_once(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch):
    """Issue 32 item 3: "timeout: timeout: stuck on terrain ..." doubled the word in the header and
    in pytest's short summary."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makefile(".yaml", plinth="""version: 1
robot: {drive: diff, body: {type: wheeled}}
mission: {start: {x: 0, y: 0}, goal: {x: 8, y: 0}, timeout: 30}
terrain:
  - {type: platform, name: plinth, x: 4, y: 0, length: 1, width: 2, height: 0.08}
""")
    result = pytester.runpytest("-p", "pytest_navscenario.plugin", "plinth.yaml", "--nav-subject=dwa", "-rf")
    out = result.stdout.str()
    assert "timeout: stuck on terrain at t=" in out, out[-3000:]
    assert "timeout: timeout" not in out
