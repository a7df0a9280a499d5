"""Issue 15 item 11: every ini option is declared with its real type, so pytest 9's native
``[tool.pytest]`` TOML table takes numbers and booleans as numbers and booleans, while string
values in ``[tool.pytest.ini_options]`` and ``pytest.ini`` keep working. Real pytest runs."""
from __future__ import annotations

import pytest

from pytest_navscenario.report.results_file import read_results
# Imported here so the in-process runs share it: a second in-process pytester run that imports the
# scenario loader afresh reads every scenario as empty (seen with pytest 9.0.3; not this test's subject).
from pytest_navscenario.scenario.loader import load_scenario  # noqa: F401

PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none"]
SCENARIO = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1, y: 0}, timeout: 10}\n"
NATIVE_TOML = pytest.version_tuple >= (9,)

# the same settings three ways: native TOML types, strings in ini_options, strings in pytest.ini
TYPED = ("nav_subject = 'potential-field'\nnav_seed = 3\nnav_summary = false\nnav_tick_limit = 2.5\n"
         "nav_repeat = 2\nnav_plots_max = 5\nnavsearch_budget = 7\n")
STRINGS = ("nav_subject = 'potential-field'\nnav_seed = '3'\nnav_summary = 'no'\nnav_tick_limit = '2.5'\n"
           "nav_repeat = '2'\nnav_plots_max = '5'\nnavsearch_budget = '7'\n")
INI = ("[pytest]\nnav_subject = potential-field\nnav_seed = 3\nnav_summary = no\nnav_tick_limit = 2.5\n"
       "nav_repeat = 2\nnav_plots_max = 5\nnavsearch_budget = 7\n")


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makefile(".yaml", ok=SCENARIO)
    return pytester


def _check_run(project: pytest.Pytester) -> None:
    result = project.runpytest(*PLUGIN, "--nav-results=r.jsonl")
    assert result.ret == 0, result.stdout.str() + result.stderr.str()
    result.stdout.fnmatch_lines(["*subject potential-field (built-in), seed 3*, tick limit 2.5 s*",
                                 "*2 runs per scenario*"])
    assert "navscenario summary" not in result.stdout.str()     # nav_summary = false / no
    assert len(read_results(project.path / "r.jsonl")) == 2


@pytest.mark.skipif(not NATIVE_TOML, reason="[tool.pytest] native TOML is pytest 9's")
def test_native_toml_table_takes_ints_floats_and_bools(project):
    project.makepyprojecttoml("[tool.pytest]\n" + TYPED)
    _check_run(project)


@pytest.mark.parametrize("form", ["ini_options", "pytest.ini"])
def test_string_values_keep_working(project, form):
    if form == "ini_options":
        project.makepyprojecttoml("[tool.pytest.ini_options]\n" + STRINGS)
    else:
        project.makeini(INI)
    _check_run(project)


@pytest.mark.parametrize("line, message", [
    ("nav_repeat = lots", "ini option nav_repeat"),
    ("nav_summary = maybe", "ini option nav_summary"),
    ("nav_plots_max = many", "ini option nav_plots_max"),
    ("navsearch_budget = big", "ini option navsearch_budget"),
    ("nav_tick_limit = soon", "ini option nav_tick_limit"),
])
def test_bad_ini_value_is_a_usage_error_naming_the_option(project, line, message):
    project.makeini("[pytest]\n" + line + "\n")
    result = project.runpytest(*PLUGIN)
    assert result.ret == pytest.ExitCode.USAGE_ERROR, result.stdout.str() + result.stderr.str()
    assert message in result.stderr.str()
    assert "Traceback" not in result.stderr.str() + result.stdout.str()


@pytest.mark.skipif(not NATIVE_TOML, reason="[tool.pytest] native TOML is pytest 9's")
def test_native_toml_wrong_type_is_a_usage_error(project):
    project.makepyprojecttoml("[tool.pytest]\nnav_summary = 'no'\n")
    result = project.runpytest(*PLUGIN)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert "nav_summary" in result.stderr.str() and "expects a bool" in result.stderr.str()
