"""The MuJoCo release series the project supports is declared, bounded and the one installed: the
tests, the docs' outputs and the frozen files record its bits, so an unbounded requirement lets a
fresh install pull a release whose trajectories differ (issue 32: `mujoco>=3.2` brought 4.0.1 onto a
project recorded under 4.0.0, and 3 tests failed)."""
from __future__ import annotations

from pathlib import Path

import mujoco
import pytest
from packaging.requirements import Requirement
from packaging.version import Version

tomllib = pytest.importorskip("tomllib", reason="reading pyproject.toml needs Python 3.11 (tomllib)")

ROOT = Path(__file__).resolve().parents[2]


def _mujoco_requirement() -> Requirement:
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    (req,) = [Requirement(d) for d in deps if Requirement(d).name == "mujoco"]
    return req


def test_the_mujoco_requirement_is_one_release_series_and_the_installed_one_is_in_it():
    req = _mujoco_requirement()
    uppers = [s for s in req.specifier if s.operator == "<"]
    assert uppers, f"{req}: no upper bound, so a fresh install may bring a MuJoCo the recorded bits do not match"
    lower = Version(next(s.version for s in req.specifier if s.operator == ">="))
    upper = Version(uppers[0].version)
    assert (upper.major, upper.minor) == (lower.major, lower.minor + 1), f"{req}: more than one minor series"
    assert Version(mujoco.__version__) in req.specifier, (
        f"MuJoCo {mujoco.__version__} is installed but pyproject.toml supports {req}: "
        f"pip install -e . installs a supported one")
