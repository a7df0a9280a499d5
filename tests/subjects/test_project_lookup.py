"""A planner module beside the user's pyproject.toml is found as the docs say (issue 23 item 1):
by pytest from the rootdir, by the ``navscenario`` command from the current folder, in a project
with no conftest.py and nothing on sys.path; and an installed module of the same name still wins."""
from __future__ import annotations

import os
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

# Before pytester's in-process runs snapshot sys.modules: a worker pool pickles functions of
# concurrent.futures by reference, which fails if a later run re-imports that module.
import pytest_navscenario.dispatch.local  # noqa: F401
import pytest_navscenario.harness.runner  # noqa: F401  (numpy cannot load twice)
from pytest_navscenario.core.errors import SubjectLoadError
from pytest_navscenario.core.user_code import ShadowedModuleWarning, load_object, look_in_project

REPO = Path(__file__).resolve().parents[2]

# The tutorial's planner, split over two modules of the project (mynav imports its neighbour).
MYNAV = '''
from steering import towards


class Careful:
    name = "careful"
    version = "0.1"

    def reset(self, scenario):
        self.speed = 0.6 * scenario.robot.limits.max_speed

    def act(self, obs):
        return towards(obs, self.speed)
'''
STEERING = '''
import math


def towards(obs, speed):
    x, y, yaw = obs.pose
    tx, ty = obs.target
    dx, dy = tx - x, ty - y
    d = math.hypot(dx, dy) or 1.0
    c, s = math.cos(yaw), math.sin(yaw)
    v = min(speed, d)
    return (c * dx + s * dy) / d * v, (-s * dx + c * dy) / d * v, 0.0
'''
SCENARIO = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 2, y: 0}, timeout: 10}\n"


def make_project(folder: Path) -> Path:
    """A user's project: pyproject.toml naming the subject, the planner beside it, a scenario;
    no conftest.py, nothing installed."""
    (folder / "pyproject.toml").write_text('[tool.pytest.ini_options]\nnav_subject = "mynav:Careful"\n'
                                           'addopts = "-p no:cacheprovider"\n')
    (folder / "mynav.py").write_text(MYNAV)
    (folder / "steering.py").write_text(STEERING)
    (folder / "scenarios").mkdir()
    (folder / "scenarios" / "short.yaml").write_text(SCENARIO)
    return folder


def test_pytest_finds_the_subject_in_the_rootdir_without_a_conftest(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    make_project(pytester.path)
    assert str(pytester.path) not in sys.path and not (pytester.path / "conftest.py").exists()
    result = pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "--nav-plots=none")
    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines(["*subject mynav:Careful (ini nav_subject)*"])


def test_pytest_from_a_subfolder_and_on_worker_processes(pytester, monkeypatch):
    """The rootdir, not the current folder, is the project folder for pytest; worker processes
    (which copy sys.path when they start) find the subject too."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    make_project(pytester.path)
    monkeypatch.chdir(pytester.path / "scenarios")
    result = pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "--nav-plots=none",
                                          "--nav-workers=2", ".")
    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines(["*episodes run on 2 local worker process*"])


def _cli(folder: Path, *args: str) -> subprocess.CompletedProcess:
    # -P: no current folder on sys.path (the console script `navscenario` has none either)
    env = dict(os.environ, PYTHONPATH=str(REPO))
    main = "import sys; from pytest_navscenario.cli import main; sys.exit(main())"
    return subprocess.run([sys.executable, "-P", "-c", main, *args],
                          cwd=folder, env=env, capture_output=True, text=True, timeout=120)


def test_the_cli_finds_the_subject_in_the_current_folder(tmp_path):
    make_project(tmp_path)
    check = _cli(tmp_path, "check-planner", "mynav:Careful", "--ticks", "3")
    assert check.returncode == 0, check.stderr
    assert "check_planner(mynav:Careful): OK" in check.stdout
    run = _cli(tmp_path, "run", "scenarios/short.yaml", "--subject", "mynav:Careful")
    assert run.returncode == 0, run.stderr
    assert "with careful 0.1" in run.stdout and "outcome: success" in run.stdout
    elsewhere = _cli(tmp_path / "scenarios", "check-planner", "mynav:Careful")
    assert elsewhere.returncode == 2
    assert "cannot import module 'mynav'" in elsewhere.stderr
    assert f"then in {tmp_path / 'scenarios'}" in elsewhere.stderr and "PYTHONPATH" in elsewhere.stderr


def test_a_module_on_sys_path_wins_over_the_project_folder_and_a_warning_says_so(tmp_path, monkeypatch):
    installed, project = tmp_path / "site", tmp_path / "project"
    installed.mkdir()
    project.mkdir()
    (installed / "nu_shadow_nav.py").write_text("class Planner:\n    where = 'installed'\n")
    (project / "nu_shadow_nav.py").write_text("class Planner:\n    where = 'project'\n")
    (project / "nu_only_here.py").write_text("class Planner:\n    where = 'project'\n")
    monkeypatch.syspath_prepend(str(installed))
    monkeypatch.delitem(sys.modules, "nu_shadow_nav", raising=False)
    monkeypatch.delitem(sys.modules, "nu_only_here", raising=False)
    with pytest.warns(ShadowedModuleWarning, match=r"'nu_shadow_nav' is imported from .*site.*not from the project"):
        assert load_object("nu_shadow_nav:Planner", project=[project]).where == "installed"
    assert str(project) not in sys.path          # the project folder was not needed: not added
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load_object("nu_only_here:Planner", project=[project]).where == "project"
    assert sys.path[-1] == str(project)          # appended last: anything installed still wins
    assert look_in_project("nu_only_here", [project]) is None   # already importable now


def test_a_missing_dependency_is_not_reported_as_a_missing_module(tmp_path, monkeypatch):
    (tmp_path / "nu_needs_dep.py").write_text("import nu_not_installed_dep\nclass P: pass\n")
    monkeypatch.delitem(sys.modules, "nu_needs_dep", raising=False)
    monkeypatch.setattr(sys, "path", list(sys.path))
    with pytest.raises(SubjectLoadError, match="it imports 'nu_not_installed_dep', which is not installed"):
        load_object("nu_needs_dep:P", project=[tmp_path])


def test_the_docs_say_where_subjects_are_looked_up_in_one_place():
    text = (REPO / "docs" / "reference" / "planner-protocol.md").read_text()
    assert "## Where a subject is looked up" in text
    for page in ("tutorial/own-planner.md", "reference/pytest-plugin.md"):
        assert "planner-protocol.md#where-a-subject-is-looked-up" in (REPO / "docs" / page).read_text(), page
    assert "puts the project root on `sys.path`" not in (REPO / "docs/tutorial/own-planner.md").read_text()
