"""Frozen files and what they were recorded with (issue 32). The MuJoCo release is named wherever
bits are recorded or compared: pytest's header, ``navscenario --version``, every results record, and
the failure of a frozen file that did not reproduce its provenance's outcome, with the release it
was recorded under when that is another. A frozen file run against another subject than the one it
was found against warns."""
from __future__ import annotations

from pathlib import Path

import mujoco
import pytest

from pytest_navscenario.cli.main import main
from pytest_navscenario.report.results_file import read_results

PLANNERS = (Path(__file__).parents[1] / "search" / "straight_planner.py").read_text()

# Straight drives into the wall (no safety layer): a collision; the provenance recorded a timeout.
FROZEN = """version: 1
name: wall-{tag}
family: wall
robot: {{safety: {{enabled: false}}}}
mission: {{start: {{x: 0, y: 0}}, goal: {{x: 4, y: 0}}, timeout: 10}}
obstacles: [{{type: box, name: wall, x: 2, y: 0, length: 0.4, width: 2}}]
provenance:
  seed: wall
  subject: straight_planner:Straight
  outcome: timeout
  message: timeout after 10.0 s, 2.10 m from the goal
  mujoco_version: '{version}'
"""


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(straight_planner=PLANNERS)
    pytester.syspathinsert()
    folder = pytester.path / "regressions"
    folder.mkdir()
    (folder / "old.yaml").write_text(FROZEN.format(tag="old", version="3.9.0"))
    (folder / "same.yaml").write_text(FROZEN.format(tag="same", version=mujoco.__version__))
    return pytester


def _section(out: str, name: str) -> str:
    start = out.index(f"scenario {name} (")
    end = out.find("reproduce:", start)
    return out[start:end]


def test_header_record_and_a_frozen_failure_that_did_not_reproduce_name_the_mujoco_release(project):
    result = project.runpytest_inprocess("-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider",
                                         "regressions", "--nav-subject=straight_planner:Straight",
                                         "--nav-results=r.jsonl", "--nav-plots=none")
    out = result.stdout.str()
    assert f", MuJoCo {mujoco.__version__}" in out.split("collected")[0], out      # the header
    old = _section(out, "wall-old")
    assert old.splitlines()[1].startswith("collision:"), old
    assert "recorded:      timeout: timeout after 10.0 s, 2.10 m from the goal (its provenance; this run did " \
           "not reproduce it)" in old
    assert (f"MuJoCo:        it was recorded under MuJoCo 3.9.0, this run simulates with MuJoCo "
            f"{mujoco.__version__}: a MuJoCo release moves trajectories") in old
    same = _section(out, "wall-same")
    assert "recorded:      timeout" in same and "MuJoCo:" not in same         # same release: no such note
    records = read_results(project.path / "r.jsonl")
    assert {r["mujoco_version"] for r in records} == {mujoco.__version__}


def test_navscenario_version_names_the_mujoco_release(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip().endswith(f"(MuJoCo {mujoco.__version__})")


def test_frozen_failures_run_against_another_subject_than_their_provenance_warn(project):
    """Tutorial 5's `pytest scenarios/regressions/loading-dock` ran the ini's subject against the
    failures dwa was found to have, all of them passed for the wrong reason, without a word."""
    project.makeini("[pytest]\nnav_subject = dwa\n")
    other = project.runpytest_inprocess("-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider",
                                        "regressions", "--nav-plots=none")
    out = other.stdout.str()
    assert "OtherSubjectWarning: frozen failure found against subject 'straight_planner:Straight' runs " \
           "against 'dwa' (from ini nav_subject): against another subject it is only a layout, which it " \
           "may pass; to re-run the failure as found, add --nav-subject=straight_planner:Straight" in out, out
    assert "regressions/old.yaml" in out and "regressions/same.yaml" in out       # both files, one message
    same = project.runpytest_inprocess("-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider",
                                       "regressions", "--nav-plots=none", "--nav-subject=straight_planner:Straight")
    assert "OtherSubjectWarning" not in same.stdout.str()
