"""``--navsearch-suite DIR``: the generated suite kept as ordinary scenario files (the paper's
TS-Exp-A), re-run later against any planner. Real pytest runs (pytester), the straight-line
driver of test_search_plugin.py as the subject."""
from __future__ import annotations

import json
import re

import pytest

from pytest_navscenario.scenario.loader import load_scenario
from test_search_plugin import SUBJECT, project, run  # noqa: F401  (project: a fixture)

NAME = re.compile(r"crate-sim(\d{4})-[0-9a-f]{16}\.yaml")


def _search_log(project, out="scenarios/regressions"):
    lines = (project.path / out / "crate" / "search-log.jsonl").read_text().splitlines()
    return [r for r in map(json.loads, lines) if r["record"] == "candidate"]


def test_every_search_candidate_is_a_file_that_reruns_with_the_same_outcome(project):
    result = run(project, "--navsearch", "crate", "--budget", "8", "--navsearch-seed", "3",
                 "--navsearch-shrink-budget", "10", "--navsearch-stuck-after", "0", "--navsearch-suite", "suite")
    assert result.ret == 0, result.stdout.str()
    log = _search_log(project)
    search = [r for r in log if r["phase"] == "search"]
    assert len(search) == 8 and any(r["phase"] == "shrink" for r in log)   # shrink candidates: not in the suite
    files = sorted((project.path / "suite" / "crate").iterdir())
    assert [int(NAME.fullmatch(f.name).group(1)) for f in files] == list(range(1, 9)), files
    failing = [r for r in search if r["outcome"] != "success"]
    assert 0 < len(failing) < 8
    result.stdout.fnmatch_lines([f"  suite suite/crate/: 8 scenario file(s), {len(failing)} failing for "
                                 f"straight_planner:Straight (re-run: pytest suite --nav-subject=...)"])
    for path, rec in zip(files, search):
        s = load_scenario(path)
        assert s.family == "crate" and s.name == path.stem and s.search is None
        assert s.provenance["simulation"] == rec["sim"] and s.provenance["outcome"] == rec["outcome"]
        assert path.stem.endswith(rec["scenario_hash"])

    again = run(project, "suite", "--nav-results=again.jsonl")
    again.assert_outcomes(passed=8 - len(failing), failed=len(failing))
    again.stdout.fnmatch_lines(["crate *8 *"])   # the end-of-run table: one row, the seed's family
    records = [json.loads(line) for line in (project.path / "again.jsonl").read_text().splitlines()]
    assert {r["scenario_hash"]: r["outcome"] for r in records} == {r["scenario_hash"]: r["outcome"] for r in search}


def test_same_search_seed_writes_the_same_bytes_and_a_new_suite_replaces_the_old(project):
    args = ("--navsearch", "crate", "--navsearch-seed", "5", "--navsearch-shrink-budget", "0")
    assert run(project, *args, "--budget", "6", "--navsearch-suite", "a").ret == 0
    assert run(project, *args, "--budget", "6", "--navsearch-suite", "b").ret == 0
    a, b = (sorted((project.path / d / "crate").iterdir()) for d in ("a", "b"))
    assert len(a) == 6 and [p.name for p in a] == [p.name for p in b]
    assert all(pa.read_bytes() == pb.read_bytes() for pa, pb in zip(a, b))

    other = project.path / "a" / "crate" / "notes.yaml"
    other.write_text("not ours\n")
    third = run(project, *args, "--budget", "4", "--navsearch-suite", "a")
    third.stdout.fnmatch_lines(["  suite a/crate/: 4 scenario file(s), *, 2 of an earlier suite removed*"])
    assert sorted(p.name for p in (project.path / "a" / "crate").glob("crate-*")) == [p.name for p in a[:4]]
    assert other.read_text() == "not ours\n"      # files it did not write are left alone


def test_ini_twin_is_relative_to_the_rootdir(project):
    project.makeini("[pytest]\nnav_scenario_paths = scenarios\npythonpath = .\nnavsearch_suite = suites/straight\n")
    sub = project.path / "elsewhere"
    sub.mkdir()
    result = project.runpytest_inprocess("-p", "pytest_navscenario.plugin", SUBJECT, "--rootdir", str(project.path),
                                         "--navsearch", "crate", "--budget", "3", "--navsearch-shrink-budget", "0")
    assert result.ret == 0, result.stdout.str()
    assert len(list((project.path / "suites" / "straight" / "crate").glob("crate-sim*.yaml"))) == 3


@pytest.fixture
def fresh_interrupt_counter():
    """interrupted_after_five counts episodes in its module, which this process imported already
    (test_search.py): start from zero, and leave zero for the next test that uses it."""
    import straight_planner
    straight_planner.CALLS[0] = 0
    yield
    straight_planner.CALLS[0] = 0


def test_ctrl_c_keeps_the_suite_simulated_so_far(project, fresh_interrupt_counter):
    result = project.runpytest_inprocess(
        "-p", "pytest_navscenario.plugin", "--nav-subject=straight_planner:interrupted_after_five",
        "--navsearch", "crate", "--budget", "50", "--navsearch-seed", "3", "--navsearch-suite", "suite")
    out = result.stdout.str()
    assert "CUT SHORT" in out, out
    sims = int(re.search(r"\): (\d+)/50 sims", out).group(1))
    assert 0 < sims < 50
    assert len(list((project.path / "suite" / "crate").glob("crate-sim*.yaml"))) == sims


@pytest.mark.parametrize("args, message", [
    (["--navsearch-suite", "taken.txt"],
     "--navsearch-suite: 'taken.txt' exists and is not a folder; give a folder for the generated suite"),
    (["--navsearch-suite", "found", "--navsearch-out", "found"],
     "--navsearch-suite: 'found' is also the folder of the frozen failures (--navsearch-out); give the "
     "suite a folder of its own"),
])
def test_bad_suite_folder_is_a_usage_error(project, args, message):
    (project.path / "taken.txt").write_text("a file\n")
    result = run(project, "--navsearch", "crate", "--budget", "2", *args)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    err = result.stderr.str()
    assert err.startswith("ERROR: ") and message in err, err
