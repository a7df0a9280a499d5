"""The public API survives the restructure: the top-level names, the entry points, and the old flat
import paths that users may have written (they forward to the new modules with a warning that names
the new path; a name that is gone fails with a message saying where the module went)."""
import importlib
import importlib.metadata
import subprocess
import sys

import pytest

import pytest_navscenario
from pytest_navscenario import _compat


def test_top_level_names_resolve():
    for name in pytest_navscenario.__all__:
        assert getattr(pytest_navscenario, name) is not None, name
    from pytest_navscenario import check_planner, load_scenario, run_scenario, scenarios_around
    assert callable(load_scenario) and callable(run_scenario)
    assert callable(check_planner) and callable(scenarios_around)


def test_entry_points_are_unchanged():
    eps = importlib.metadata.entry_points()
    assert [e.value for e in eps.select(group="pytest11", name="navscenario")] == ["pytest_navscenario.plugin"]
    assert [e.value for e in eps.select(group="console_scripts", name="navscenario")] == \
        ["pytest_navscenario.cli:main"]


@pytest.mark.parametrize("old, name, new", [
    ("loader", "load_scenario", "pytest_navscenario.scenario.loader"),
    ("loader", "dump_scenario", "pytest_navscenario.scenario.dump"),
    ("search_space", "scenarios_around", "pytest_navscenario.search.space"),
    ("planner", "Observation", "pytest_navscenario.subjects.protocol"),
    ("planner", "load_subject", "pytest_navscenario.subjects.loading"),
    ("result", "EpisodeResult", "pytest_navscenario.verdict.result"),
    ("result", "Trajectory", "pytest_navscenario.sim.trajectory"),
    ("runner", "run_scenario", "pytest_navscenario.harness.runner"),
    ("results", "atomic_write_text", "pytest_navscenario.core.files"),
    ("planners.dwa", "DynamicWindowPlanner", "pytest_navscenario.subjects.planners.dwa"),
])
def test_old_import_paths_forward_with_a_warning_naming_the_new_path(old, name, new):
    module = importlib.import_module(f"pytest_navscenario.{old}")
    with pytest.warns(DeprecationWarning, match=f"import {name} from {new}"):
        value = getattr(module, name)
    assert value is getattr(importlib.import_module(new), name)


def test_a_name_that_is_gone_says_where_the_module_went():
    module = importlib.import_module("pytest_navscenario.loader")
    with pytest.raises(AttributeError, match="moved to pytest_navscenario.scenario.loader"):
        module.no_such_function  # noqa: B018


def test_every_forwarding_target_exists():
    for old, targets in _compat.OLD_PATHS.items():
        for target in targets:
            importlib.import_module(f"pytest_navscenario.{target}")


def test_from_import_of_an_old_path_works_in_a_fresh_process():
    code = ("import warnings; warnings.simplefilter('error')\n"
            "try:\n    from pytest_navscenario.loader import load_scenario\n"
            "except DeprecationWarning as w:\n    print('warned:', w)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "warned: pytest_navscenario.loader moved: import load_scenario from " \
           "pytest_navscenario.scenario.loader" in out


def test_plugin_load_imports_nothing_heavy():
    code = ("import sys, pytest_navscenario.plugin\n"
            "print(sorted(m for m in ('numpy', 'mujoco', 'matplotlib', 'shapely', 'jinja2') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_the_search_plugins_copies_of_engine_constants_agree():
    """plugin/search.py keeps its own copies so that a run without --navsearch never imports the
    search (its help text and checks need them); they must say what the engine does."""
    from pytest_navscenario.plugin import search as plugin_search
    from pytest_navscenario.search import engine
    assert plugin_search.STRATEGY_NAMES == engine.STRATEGIES
    assert plugin_search.DEFAULT_SHRINK_BUDGET == engine.DEFAULT_SHRINK_BUDGET
    assert plugin_search.DEFAULT_STUCK_AFTER == engine.DEFAULT_STUCK_AFTER


def test_a_suite_run_without_navsearch_does_not_import_the_search(tmp_path):
    (tmp_path / "s.yaml").write_text("version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1, y: 0}, timeout: 5}\n")
    code = ("import sys, pytest\n"
            "rc = pytest.main([%r, '-q', '-p', 'no:cacheprovider', '--nav-plots=none', '--nav-artifacts=none'])\n"
            "print('RC', int(rc), 'pytest_navscenario.search.engine' in sys.modules)" % str(tmp_path))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path).stdout
    assert "RC 0 False" in out, out[-2000:]
