"""--nav-workers N, and -n N on a run of scenario files only: one pytest process collects and
reports, N local worker processes simulate; the items, their order and the results file are a
serial run's. A run with Python test files keeps pytest-xdist's workers."""
from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

# Imported here, before pytester's in-process runs snapshot sys.modules (numpy cannot load twice).
import pytest_navscenario.dispatch.local  # noqa: F401
import pytest_navscenario.harness.runner  # noqa: F401
from ray_fixtures import item_lines, write_suite

COMMON = ["suite", "-v", "-p", "no:cacheprovider", "--nav-plots=none"]
HEADER = "episodes run on 2 local worker process"


def records(path: Path) -> list[dict]:
    return [{k: v for k, v in json.loads(line).items() if k != "wall_time"}
            for line in path.read_text().splitlines()]


def test_n_on_scenario_files_runs_the_episodes_on_local_workers(pytester: pytest.Pytester):
    write_suite(pytester.path / "suite", short_timeout="1.6")
    serial = pytester.runpytest(*COMMON, "--nav-results=s.jsonl", "--nav-artifacts=art-s")
    par = pytester.runpytest(*COMMON, "-n", "2", "--nav-results=p.jsonl", "--nav-artifacts=art-p")
    serial.assert_outcomes(passed=5, failed=1)
    par.assert_outcomes(passed=5, failed=1)
    out = par.stdout.str()
    assert f"{HEADER}" in out and "(-n 2 on scenario files only)" in out
    # no xdist workers were started (not "gw0" alone: this run's folder is .../popen-gw0/... under -n)
    assert not re.search(r"\[gw\d+\]|\d+ workers \[\d+ items?\]|created: \d+/\d+ workers", out), out
    assert item_lines(par.outlines) == item_lines(serial.outlines)
    assert records(pytester.path / "p.jsonl") == records(pytester.path / "s.jsonl")
    # the failing item's artifacts came back from the worker (the trajectory travelled)
    files = sorted(p.relative_to(pytester.path / "art-p") for p in (pytester.path / "art-p").rglob("*") if p.is_file())
    assert files and files == sorted(p.relative_to(pytester.path / "art-s")
                                     for p in (pytester.path / "art-s").rglob("*") if p.is_file())


def test_nav_workers_and_its_ini_twin(pytester: pytest.Pytester):
    write_suite(pytester.path / "suite")
    cli = pytester.runpytest(*COMMON, "--nav-workers=2", "--nav-results=c.jsonl")
    cli.assert_outcomes(passed=6)
    assert "(--nav-workers 2)" in cli.stdout.str()
    pytester.makeini("[pytest]\nnav_workers = 2\n")
    ini = pytester.runpytest(*COMMON, "--nav-results=i.jsonl")
    ini.assert_outcomes(passed=6)
    assert HEADER in ini.stdout.str()
    assert records(pytester.path / "i.jsonl") == records(pytester.path / "c.jsonl")


def test_python_test_files_or_an_explicit_dist_keep_xdist(pytester: pytest.Pytester):
    write_suite(pytester.path / "suite")
    (pytester.path / "suite" / "test_unit.py").write_text("def test_it():\n    assert True\n")
    mixed = pytester.runpytest(*COMMON, "-n", "2")
    mixed.assert_outcomes(passed=7)
    assert HEADER not in mixed.stdout.str() and "gw" in mixed.stdout.str()
    (pytester.path / "suite" / "test_unit.py").unlink()
    dist = pytester.runpytest(*COMMON, "-n", "2", "--dist", "load")
    dist.assert_outcomes(passed=6)
    assert HEADER not in dist.stdout.str() and "gw" in dist.stdout.str()


@pytest.mark.parametrize("args, message", [
    (["--nav-workers=-1"], "--nav-workers: expected a whole number of worker processes >= 0 or 'auto'"),
    (["--nav-workers=two"], "got 'two' (e.g. --nav-workers=2"),
    (["--nav-workers=2", "-n", "2"], "give either -n N (pytest-xdist) or --nav-workers N, not both"),
    (["--nav-workers=2", "--nav-ray=auto"], "give one of them"),
])
def test_bad_worker_options_are_usage_errors_before_any_episode(pytester: pytest.Pytester, args, message):
    write_suite(pytester.path / "suite")
    result = pytester.runpytest(*COMMON, *args, "--nav-results=r.jsonl")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert message in result.stderr.str()
    assert not (pytester.path / "r.jsonl").exists()


def test_items_dropped_after_collection_report_nothing(pytester: pytest.Pytester):
    """An item a plugin deselects after collection, or skips with a mark added then, is not
    reported, recorded or waited for when the episodes run on workers."""
    write_suite(pytester.path / "suite")
    (pytester.path / "suite" / "conftest.py").write_text(
        "import pytest\n\n"
        "def pytest_collection_modifyitems(config, items):\n"
        "    dropped = [i for i in items if i.name == 'b']\n"
        "    items[:] = [i for i in items if i.name != 'b']\n"
        "    config.hook.pytest_deselected(items=dropped)\n"
        "    for i in items:\n"
        "        if i.name == 'c':\n"
        "            i.add_marker(pytest.mark.skip(reason='added after collection'))\n")
    result = pytester.runpytest(*COMMON, "-n", "2", "--nav-results=r.jsonl")
    result.assert_outcomes(passed=4, skipped=1, deselected=1)
    assert HEADER in result.stdout.str()
    names = sorted(r["nodeid"].split("::")[1] for r in records(pytester.path / "r.jsonl"))
    assert names == ["a", "d", "e", "victim"]
