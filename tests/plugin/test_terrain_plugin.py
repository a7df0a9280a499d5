"""Terrain through real pytest runs: riding episodes (wheeled, legged, the user's MJCF robot with a
controller from the project folder) give the same results, bit for bit, on 0 and 2 workers."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from pytest_navscenario.report.results_file import read_results

ROOT = Path(__file__).resolve().parents[2]
PLUGIN = ["-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider", "--nav-subject=tests.search.straight_planner:Straight",
          "--nav-plots=none"]
HEAD = "version: 1\nmission: {{start: {{x: 0, y: 0}}, goal: {{x: 9, y: 0}}, timeout: 25}}\nrobot:\n  drive: diff\n  body: {body}\n"
RAMP = """terrain:
  - {type: ramp, name: ramp, x: 4.5, y: 0, length: 3.0, width: 3.0, rise: 0.53}
  - {type: platform, name: top, x: 9.0, y: 0, length: 6.0, width: 3.0, height: 0.53}
obstacles:
  - {type: box, name: crate, x: 6.5, y: 0.9, length: 0.6, width: 0.6}
  - {type: person, name: walker, motion: {path: [[8, -1.2], [3, -1.2]], mode: back-and-forth, start: 1}}
"""
STAIRS = """terrain:
  - {type: steps, name: stairs, x: 5.0, y: 0, count: 5, rise: 0.17, run: 0.3, width: 3.0}
  - {type: platform, name: landing, x: 7.75, y: 0, length: 4.0, width: 3.0, height: 0.85}
  - {type: rough, name: yard, x: 2.0, y: 0, length: 3.0, width: 3.0, amplitude: 0.04, wavelength: 0.5, seed: 3}
"""
CONTROLLER = (ROOT / "tests" / "sim" / "cart_controller.py").read_text()


def strip_times(records):
    return [{k: v for k, v in r.items() if k not in ("wall_time", "timings")} for r in records]


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    folder = pytester.path / "scenarios"
    folder.mkdir()
    (folder / "wheeled-ramp.yaml").write_text(HEAD.format(body="{type: wheeled}") + RAMP)
    (folder / "legged-stairs.yaml").write_text(HEAD.format(body="{type: legged}") + STAIRS)
    shutil.copy(ROOT / "tests" / "data" / "mjcf" / "cart.xml", folder / "cart.xml")
    (pytester.path / "my_cart.py").write_text(CONTROLLER)        # the project folder's own module
    (folder / "cart-ramp.yaml").write_text(
        HEAD.format(body='{type: mjcf, file: cart.xml, controller: "my_cart:Cart"}') + RAMP)
    return pytester


def test_riding_episodes_are_bit_identical_on_zero_and_two_workers(project):
    serial = project.runpytest_subprocess(*PLUGIN, "scenarios", "--nav-results=r0.jsonl", "-n", "0",
                                          "-p", "xdist.plugin")
    parallel = project.runpytest_subprocess(*PLUGIN, "scenarios", "--nav-results=r2.jsonl", "-n", "2",
                                            "-p", "xdist.plugin")
    r0, r2 = read_results(project.path / "r0.jsonl"), read_results(project.path / "r2.jsonl")
    assert len(r0) == 3, serial.stdout.str()[-3000:]
    assert strip_times(r0) == strip_times(r2), parallel.stdout.str()[-3000:]
    by_name = {r["scenario"]: r for r in r0}
    assert by_name["legged-stairs"]["outcome"] == "success", by_name["legged-stairs"]["message"]
    assert by_name["cart-ramp"]["metrics"]["climb"] > 0.3             # the user's cart rode up the ramp
