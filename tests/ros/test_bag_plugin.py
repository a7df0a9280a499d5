"""``--nav-bag``: real pytest runs (plugin autoload off, loaded with -p), real episodes."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.scenario.dump import dump_scenario

PLUGIN = ["-p", "pytest_navscenario.plugin"]
SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"


def _texts() -> tuple[str, str]:
    """Two scenarios: cylinders as shipped (passes) and the same with a 9 s timeout (fails: its 9.7 m can be
    driven in 8.7 s at top speed, so it is a test, but dwa needs 10 s).
    Made once at import: in-process pytester runs swap modules under the loader afterwards."""
    seed = load_scenario(SCENARIOS / "cylinders.yaml")
    late = dataclasses.replace(seed, mission=dataclasses.replace(seed.mission, timeout=9.0))
    return dump_scenario(seed), dump_scenario(late)


OK_TEXT, LATE_TEXT = _texts()


@pytest.fixture
def project(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    folder = pytester.mkdir("scen")
    (folder / "ok.yaml").write_text(OK_TEXT)
    (folder / "late.yaml").write_text(LATE_TEXT)
    return pytester


def bags_in(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else []


def test_failed_writes_one_bag_per_failed_episode_under_xdist(project):
    project.makeini("[pytest]\nnav_bag_dir = out/bags\nnav_bag_format = ros1\n")
    # a subprocess: an in-process run under xdist would leave pytester's module snapshot mixed up
    res = project.runpytest_subprocess(*PLUGIN, "-p", "xdist.plugin", "-n", "2", "scen",
                                       "--nav-bag=failed", "--nav-artifacts=none", "--nav-plots=none")
    res.assert_outcomes(passed=1, failed=1)
    names = bags_in(project.path / "out" / "bags")
    assert len(names) == 1 and names[0].startswith("scen_late.yaml") and names[0].endswith(".bag")
    res.stdout.fnmatch_lines(["navscenario: wrote 1 ros1 bag(s) to *out/bags (--nav-bag=failed)"])

    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore
    with AnyReader([project.path / "out" / "bags" / names[0]],
                   default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    assert counts["/scan"] == 90 and counts["/navscenario/result"] == 1  # 9 s of 10 Hz ticks


def test_default_writes_no_bag_and_bad_values_are_usage_errors(project):
    res = project.runpytest(*PLUGIN, "scen/ok.yaml")
    res.assert_outcomes(passed=1)
    assert not (project.path / "nav-bags").exists()

    res = project.runpytest(*PLUGIN, "scen/ok.yaml", "--nav-bag=some")
    assert res.ret == pytest.ExitCode.USAGE_ERROR
    res.stderr.fnmatch_lines(["*--nav-bag: expected one of none, failed, all, got 'some'*"])
    res = project.runpytest(*PLUGIN, "scen/ok.yaml", "--nav-bag=all", "--nav-bag-format=bag")
    assert res.ret == pytest.ExitCode.USAGE_ERROR
    res.stderr.fnmatch_lines(["*--nav-bag-format: expected one of mcap, sqlite3, ros1, got 'bag'*"])


def test_a_bag_that_cannot_be_written_is_reported_not_fatal(project):
    (project.path / "afile").write_text("not a folder\n")
    res = project.runpytest(*PLUGIN, "scen/ok.yaml", "--nav-bag=all", "--nav-bag-dir=afile/bags")
    res.assert_outcomes(passed=1)   # the episode ran and passed; the bag error sets the exit status
    assert res.ret == pytest.ExitCode.INTERNAL_ERROR
    res.stdout.fnmatch_lines(["navscenario: error: scen/ok.yaml::*: *afile/bags/scen_ok.yaml_*: cannot create "
                              "the bag's folder: *Not a directory*"])


def test_all_writes_mcap_for_passing_episodes_too(project):
    res = project.runpytest(*PLUGIN, "scen/ok.yaml", "--nav-bag=all", "--nav-bag-dir=b")
    res.assert_outcomes(passed=1)
    (bag,) = (project.path / "b").iterdir()
    assert len(list(bag.glob("*.mcap"))) == 1 and (bag / "metadata.yaml").exists()


def test_plugin_knows_the_writer_formats_without_importing_it():
    import subprocess
    import sys

    from pytest_navscenario.plugin import bags as bag_plugin
    from pytest_navscenario.ros import bag_writer as bags
    assert bag_plugin.FORMATS == bags.FORMATS
    code = "import sys, pytest_navscenario.plugin.bags; print('pytest_navscenario.ros.bag_writer' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
