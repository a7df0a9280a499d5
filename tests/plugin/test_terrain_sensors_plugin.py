"""A wheeled robot with noisy 2D and 3D lidars on rough ground, beside a pit and a heightfield read
from a file, through real pytest runs: the same records on 0 and 2 workers, and a bag (written on
the controller from the worker's payload) holding the 3D lidar's clouds."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.report.results_file import read_results

ROOT = Path(__file__).resolve().parents[2]
PLUGIN = ["-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider", "--nav-subject=dwa", "-p", "xdist.plugin"]
YARD = """\
version: 1
robot:
  body: {type: wheeled}
  drive: diff
  lidar: {noise_sigma: 0.02, dropout: 0.05}
  lidar3d: {rings: 8, beams: 180, noise_sigma: 0.02, dropout: 0.05, spurious: 0.01}
mission: {start: {x: 0, y: 0}, goal: {x: 8, y: 0}, timeout: 20}
obstacles:
  - {type: box, name: crate, x: 4, y: 1.2, length: 0.6, width: 0.6, height: 0.8}
terrain:
  - {type: pit, name: hole, x: 5, y: -2.5, length: 2, width: 1.5, depth: 0.6}
  - {type: rough, name: yard, x: 4, y: 0, length: 3, width: 2, amplitude: 0.04, wavelength: 0.6, seed: 2}
  - {type: heightfield, name: hills, x: 3, y: 5, file: hills.npy, length: 6, width: 4, max_height: 0.5}
"""


def strip_times(records):
    return [{k: v for k, v in r.items() if k != "wall_time"} for r in records]


@pytest.mark.heavy
def test_terrain_sensors_give_the_same_results_on_zero_and_two_workers_and_bag_their_clouds(
        pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    folder = pytester.path / "scenarios"
    folder.mkdir()
    rng = np.random.default_rng(3)
    np.save(folder / "hills.npy", np.cumsum(rng.normal(size=(31, 41)), axis=0))
    (folder / "yard.yaml").write_text(YARD)
    serial = pytester.runpytest_subprocess(*PLUGIN, "scenarios", "--nav-results=r0.jsonl", "-n", "0")
    parallel = pytester.runpytest_subprocess(*PLUGIN, "scenarios", "--nav-results=r2.jsonl", "-n", "2",
                                             "--nav-bag=all")
    assert serial.ret == parallel.ret == 0, serial.stdout.str() + parallel.stdout.str()
    r0, r2 = read_results(pytester.path / "r0.jsonl"), read_results(pytester.path / "r2.jsonl")
    assert len(r0) == 1 and strip_times(r0) == strip_times(r2)
    (bag,) = (pytester.path / "nav-bags").iterdir()
    import sys
    sys.path.insert(0, str(ROOT / "tests" / "ros"))
    from test_bags import read_bag
    topics = read_bag(bag)
    assert len(topics["/points"][1]) == len(topics["/scan"][1]) > 10    # a cloud a control tick
    assert "/navscenario/terrain" in topics
