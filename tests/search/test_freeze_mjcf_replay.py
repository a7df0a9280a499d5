"""A search over an MJCF seed freezes failures that replay where they were written (issue 38,
part 5): the robot's files and the controller module the seed found beside itself are copied
beside the frozen files, so running them from another folder finds both (it was a
ModuleNotFoundError for every frozen file)."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from pytest_navscenario.report.results_file import read_results

ROOT = Path(__file__).resolve().parents[2]
SEED = """version: 1
name: cart-crate
mission: {start: {x: 0, y: 0}, goal: {x: 4, y: 0}, timeout: 8}
robot:
  drive: diff
  safety: {enabled: false}
  body: {type: mjcf, file: robot/cart.xml, controller: "seed_cart:Cart"}
obstacles:
  - {type: box, name: crate, x: 2.5, y: 1.2, length: 0.4, width: 0.4}
search:
  obstacle_dx: 0
  obstacle_dy: [-1.2, 0.2]
  obstacle_size: 0
  obstacle_yaw: 0
  insert: 0
"""


def pytest_in(cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests" / "search")]),
               PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider",
                           "--nav-subject=straight_planner:Straight", "--nav-plots=none", *args],
                          cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def test_frozen_failures_of_an_mjcf_seed_replay_from_another_folder(tmp_path):
    project = tmp_path / "project"
    (project / "seeds" / "robot").mkdir(parents=True)
    shutil.copy(ROOT / "tests" / "data" / "mjcf" / "cart.xml", project / "seeds" / "robot" / "cart.xml")
    shutil.copy(ROOT / "tests" / "sim" / "cart_controller.py", project / "seeds" / "seed_cart.py")  # beside the seed only
    (project / "seeds" / "cart-crate.yaml").write_text(SEED)
    found = pytest_in(project, "--navsearch", "seeds/cart-crate.yaml", "--budget", "8", "--navsearch-out", "frozen",
                      "--navsearch-shrink-budget", "0")
    frozen = sorted((project / "frozen").rglob("*.yaml"))
    assert frozen, found.stdout[-3000:] + found.stderr[-3000:]
    folder = frozen[0].parent
    assert (folder / "seed_cart.py").is_file()                       # the controller module came along
    assert any((folder / "bodies").rglob("cart.xml"))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    replay = pytest_in(elsewhere, str(folder), "--nav-results=r.jsonl")
    assert "ModuleNotFoundError" not in replay.stdout and "cannot import module" not in replay.stdout, replay.stdout[-3000:]
    records = read_results(elsewhere / "r.jsonl")
    assert len(records) == len(frozen)
    assert all(r["outcome"] not in ("subject-error", "harness-error") for r in records), records
    assert any(r["outcome"] == "collision" for r in records)           # the failures the search found, again
