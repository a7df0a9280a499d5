"""Families: a scenario's family is its folder's name unless its YAML says ``family:``; two
folders with the same name (``scenarios/`` and ``examples/scenarios/``) stay apart, named by their
path relative to the rootdir. Real pytest runs (pytester) with the built-in planner."""
from __future__ import annotations

import json

import pytest

# in-process runs: import the extension modules (MuJoCo, shapely) once, before pytester's
# sys.modules snapshot, so that a second run does not try to load them again
import pytest_navscenario.harness.runner  # noqa: F401
import pytest_navscenario.scenario.loader  # noqa: F401

OK = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1, y: 0}, timeout: 10}\n"


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    files = {
        "scenarios/a.yaml": OK,
        "examples/scenarios/b.yaml": OK,
        "examples/scenarios/c.yaml": OK + "family: custom\n",      # the YAML's family wins
        "examples/scenarios/d.yaml": OK + "family: scenarios\n",   # ...also to join a family on purpose
        "walls/w.yaml": OK,                                         # a folder name nobody else has
    }
    for rel, text in files.items():
        path = pytester.path / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return pytester


def families(pytester: pytest.Pytester, *args: str) -> dict[str, str]:
    result = pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "--nav-results=r.jsonl", *args)
    assert result.ret == pytest.ExitCode.OK, result.stdout.str()
    records = [json.loads(line) for line in (pytester.path / "r.jsonl").read_text().splitlines()]
    return {r["nodeid"].split("::")[0]: r["family"] for r in records}


def test_folders_with_the_same_name_stay_apart(project):
    assert families(project, ".") == {
        "scenarios/a.yaml": "scenarios",
        "examples/scenarios/b.yaml": "examples/scenarios",
        "examples/scenarios/c.yaml": "custom",
        "examples/scenarios/d.yaml": "scenarios",
        "walls/w.yaml": "walls",
    }


def test_summary_has_one_row_per_family(project):
    result = project.runpytest_inprocess("-p", "pytest_navscenario.plugin", ".")
    rows = [line.split()[0] for line in result.stdout.lines if line.split()[:1] and line.split()[0] in
            ("scenarios", "examples/scenarios", "custom", "walls")]
    assert sorted(set(rows)) == ["custom", "examples/scenarios", "scenarios", "walls"]


def test_a_selection_does_not_rename_a_family(project):
    """-k deselects after the families are named: the names of a run do not depend on -k."""
    assert families(project, ".", "-k", "b or w") == {"examples/scenarios/b.yaml": "examples/scenarios",
                                                      "walls/w.yaml": "walls"}


def test_same_names_under_xdist(project):
    assert families(project, ".", "-p", "xdist.plugin", "-n", "2")["examples/scenarios/b.yaml"] == \
        "examples/scenarios"


def test_a_path_family_survives_plots_artifacts_and_reloading(project):
    """The family travels with the scenario (report.nav, artifacts' scenario.yaml): a family named
    by a path must load again, so the failing item's plot is drawn and its artifact re-runs."""
    from pytest_navscenario.scenario.loader import load_scenario

    (project.path / "examples" / "scenarios" / "slow.yaml").write_text(OK.replace("timeout: 10", "timeout: 0.65"))
    result = project.runpytest_inprocess("-p", "pytest_navscenario.plugin", ".", "--nav-html=r.html")
    result.assert_outcomes(passed=5, failed=1)
    assert "could not draw" not in result.stdout.str()
    assert 'data-family="examples/scenarios"' in (project.path / "r.html").read_text()
    (copy,) = (project.path / "nav-artifacts").glob("*/scenario.yaml")
    assert load_scenario(copy).family == "examples/scenarios"


@pytest.mark.parametrize("family", ["a/../b", "../x", "a//b", "a\\\\b", "/abs"])
def test_a_family_path_may_not_climb_or_be_absolute(family):
    from pytest_navscenario.core.errors import ScenarioError
    from pytest_navscenario.scenario.loader import loads_scenario

    with pytest.raises(ScenarioError, match="family"):
        loads_scenario(OK + f'family: "{family}"\n')
