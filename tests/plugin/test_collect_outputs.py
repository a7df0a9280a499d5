"""Issue 15 item 3: the folders the plugin writes (artifacts, plots, bags) are never collected, so
a second ``pytest .`` does not run the artifact copies of the first run's failures as more items;
frozen regressions (the --navsearch-out folder) are still collected. Real pytest runs."""
from __future__ import annotations

import shutil

import pytest

import pytest_navscenario.plugin.payload  # noqa: F401  (numpy: in-process runs cannot import it afresh)

from pytest_navscenario.scenario.loader import load_scenario  # noqa: F401  (see test_ini_types.py)

PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none"]
RUN = [*PLUGIN, "--nav-subject=potential-field"]
OK = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1, y: 0}, timeout: 10}\n"
SLOW = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 5, y: 0}, timeout: 4.5}\n"   # dwa times out


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    (pytester.path / "scenarios" / "regressions" / "seed").mkdir(parents=True)
    (pytester.path / "scenarios" / "ok.yaml").write_text(OK)
    (pytester.path / "scenarios" / "slow.yaml").write_text(SLOW)
    (pytester.path / "scenarios" / "regressions" / "seed" / "frozen.yaml").write_text(OK)
    return pytester


def _items(result: pytest.RunResult) -> list[str]:
    return sorted(line.split(" ")[0] for line in result.stdout.lines if "::" in line and " " in line)


def test_second_run_does_not_collect_the_first_runs_artifacts(project):
    first = project.runpytest_subprocess(*RUN, ".", "-v")
    first.assert_outcomes(passed=2, failed=1)
    copies = list((project.path / "nav-artifacts").glob("*/scenario.yaml"))
    assert len(copies) == 1                                   # the failure's copy, a real scenario
    second = project.runpytest_subprocess(*RUN, ".", "-v")
    second.assert_outcomes(passed=2, failed=1)
    assert _items(second) == _items(first)
    assert "scenarios/regressions/seed/frozen.yaml::frozen" in _items(second)


@pytest.mark.parametrize("folder, option", [
    ("my-artifacts", "--nav-artifacts=my-artifacts"),
    ("nav-bags", "--nav-bag=none"),                # the default bag folder, bags off
    ("bags", "--nav-bag-dir=bags"),
    ("nav-plots", "--nav-artifacts=none"),          # plots' default folder when artifacts are off
    ("pics", "--nav-plots-dir=pics"),
])
def test_output_folders_are_never_collected(project, folder, option):
    (project.path / folder / "item").mkdir(parents=True)
    shutil.copy(project.path / "scenarios" / "ok.yaml", project.path / folder / "item" / "scenario.yaml")
    result = project.runpytest(*PLUGIN, option, "--collect-only", "-q", ".")
    assert folder not in result.stdout.str()
    result.stdout.fnmatch_lines(["3 tests collected*"])


def test_a_file_named_on_the_command_line_is_collected_even_in_an_output_folder(project):
    (project.path / "nav-artifacts" / "item").mkdir(parents=True)
    shutil.copy(project.path / "scenarios" / "ok.yaml", project.path / "nav-artifacts" / "item" / "scenario.yaml")
    result = project.runpytest(*PLUGIN, "--collect-only", "-q", "nav-artifacts/item/scenario.yaml")
    result.stdout.fnmatch_lines(["nav-artifacts/item/scenario.yaml::scenario", "1 test collected*"])


def test_regressions_inside_an_output_folder_name_are_still_collected(project):
    result = project.runpytest(*PLUGIN, "--navsearch-out=scenarios/regressions", "--nav-artifacts=scenarios",
                               "--collect-only", "-q", ".")
    result.stdout.fnmatch_lines(["*frozen.yaml::frozen*"])
