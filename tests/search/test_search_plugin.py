"""``pytest --navsearch``: real pytest runs (pytester) with the plugin loaded explicitly.

The subject is a straight-line driver that ignores obstacles (tests/straight_planner.py), so the
``crate`` seed has failures a small shift away and searches stay a few simulations long.
"""
from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from test_search import SEED_YAML
# Before pytester's in-process runs snapshot sys.modules: a worker pool pickles functions of
# concurrent.futures by reference, which fails if a later run re-imports that module.
import pytest_navscenario.dispatch.local  # noqa: E402,F401

STRAIGHT = (Path(__file__).parent / "straight_planner.py").read_text()

SUBJECT = "--nav-subject=straight_planner:Straight"


@pytest.fixture
def project(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(straight_planner=STRAIGHT)
    pytester.syspathinsert()
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "crate.yaml").write_text(SEED_YAML.replace("name: crate\n", ""))
    twin = SEED_YAML.replace("name: crate\n", "").replace("x: 1.2", "x: -1.2").replace("[-1.5, 0.5]", "[-0.5, 1.5]")
    (pytester.path / "scenarios" / "crate2.yaml").write_text(twin)
    pytester.makeini("[pytest]\nnav_scenario_paths = scenarios\npythonpath = .\n")  # pythonpath: for xdist workers
    return pytester


def candidates(log: Path) -> list[dict]:
    """The candidate records of a search log (its start and end records left out)."""
    return [r for r in map(json.loads, log.read_text().splitlines()) if r["record"] == "candidate"]


def run(pytester, *args):
    return pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", SUBJECT, *args)


def test_search_freezes_failures_that_fail_again_when_collected(project):
    out = project.path / "scenarios" / "regressions"
    result = run(project, "--navsearch", "crate", "--budget", "6", "--navsearch-seed", "3",
                 "--navsearch-shrink-budget", "10", "--navsearch-junit", "suite.xml")
    assert result.ret == 0, result.stdout.str()
    result.stdout.fnmatch_lines(["*navsearch summary*",
                                 "crate vs straight_planner:Straight 1.0 (evolve, search seed 3): 6/6 sims*"])
    frozen = sorted((out / "crate").glob("crate-*.yaml"))
    assert frozen, result.stdout.str()
    log = candidates(out / "crate" / "search-log.jsonl")
    assert sum(r["phase"] == "search" for r in log) == 6 and all("params" in r and "outcome" in r for r in log)
    cases = list(ET.parse(project.path / "suite.xml").getroot().iter("testcase"))
    assert len(cases) == 6
    failing = [r for r in log if r["phase"] == "search" and r["outcome"] != "success"]
    assert sum(1 for c in cases if c.find("failure") is not None) == len(failing) > 0
    result.stdout.fnmatch_lines(["navsearch crate: 6/6 sims, * failure(s), lowest clearance so far *"])  # live progress
    result.stdout.fnmatch_lines(["crate vs *, lowest clearance of any run * m (sim *, a*)*"])

    from pytest_navscenario.scenario.loader import load_scenario
    prov = load_scenario(frozen[0]).provenance
    assert prov["seed"] == "crate" and prov["search_seed"] == 3 and prov["budget"] == 6
    assert prov["seed_file"] == "scenarios/crate.yaml"
    assert prov["subject"] == "straight_planner:Straight" and prov["subject_version"] == "1.0"
    assert prov["outcome"] in ("collision", "safety-stop") and "date" in prov

    # the next plain run re-executes the frozen failures: same outcome
    again = run(project, "scenarios/regressions")
    again.assert_outcomes(failed=len(frozen))
    for path in frozen:
        again.stdout.fnmatch_lines([f"*{load_scenario(path).provenance['outcome']}*"])

    # the same search again finds the same failures: kept, not duplicated
    third = run(project, "--navsearch", "crate", "--budget", "6", "--navsearch-seed", "3",
                "--navsearch-shrink-budget", "10")
    assert third.ret == 0
    assert sorted((out / "crate").glob("crate-*.yaml")) == frozen
    third.stdout.fnmatch_lines(["*kept scenarios/regressions/crate/crate-*.yaml*(already frozen)"])


def test_two_searches_on_two_workers(project):
    result = run(project, "-n", "2", "-p", "xdist.plugin", "--navsearch", "crate", "--navsearch", "crate2",
                 "--budget", "4", "--navsearch-shrink-budget", "0", "--navsearch-out", "found")
    assert result.ret == 0, result.stdout.str()
    result.assert_outcomes(passed=2)
    result.stdout.fnmatch_lines_random(["crate vs * 4/4 sims*", "crate2 vs * 4/4 sims*"])
    for name in ("crate", "crate2"):
        assert (project.path / "found" / name / "search-log.jsonl").is_file()


def test_ctrl_c_keeps_what_was_found(project):
    result = project.runpytest_inprocess(
        "-p", "pytest_navscenario.plugin", "--nav-subject=straight_planner:interrupted_after_five",
        "--navsearch", "crate", "--budget", "50", "--navsearch-seed", "3")
    out = result.stdout.str()
    assert "CUT SHORT: interrupted (Ctrl-C)" in out and "Interrupted: navsearch crate was cut short" in out, out
    sims = int(re.search(r"\): (\d+)/50 sims", out).group(1))  # the summary line
    assert 0 < sims < 50
    log = candidates(project.path / "scenarios" / "regressions" / "crate" / "search-log.jsonl")
    assert len(log) == sims
    failures = [r for r in log if r["outcome"] != "success"]
    frozen = list((project.path / "scenarios" / "regressions" / "crate").glob("crate-*.yaml"))
    assert bool(frozen) == bool(failures)
    assert not list((project.path / "scenarios" / "regressions" / "crate").glob(".*tmp"))


@pytest.mark.parametrize("args, message", [
    (["--navsearch", "crat"], "no seed scenario named 'crat' in "),
    (["--navsearch", "crat"], "Available: bad, crate, crate2. Give one of these names"),
    (["--navsearch", "crate", "--budget", "0"], "--budget: the budget (simulations per search) must be >= 1, got 0"),
    (["--navsearch", "crate", "--budget", "-3"], "must be >= 1, got -3"),
    (["--navsearch", "bad"], "bad.yaml:10: search.obstacle_dx: inverted bounds [0.5, -0.5] (lo > hi) (fix: write [-0.5, 0.5])"),
    (["--navsearch", "crate", "--navsearch-strategy", "anneal"], "unknown strategy 'anneal'; use one of evolve, random"),
])
def test_bad_input_is_a_usage_error(project, args, message):
    (project.path / "scenarios" / "bad.yaml").write_text(
        SEED_YAML.replace("name: crate\n", "").replace("[-1.5, 0.5]", "[0.5, -0.5]"))
    result = run(project, *args)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    err = result.stderr.str()
    assert err.startswith("ERROR: ") and message in err, err


def test_live_progress_shows_without_dash_s_in_a_ci_log(project):
    """Issue 15 item 5: capture must not swallow the progress; not a terminal: plain lines."""
    result = project.runpytest_subprocess("-p", "pytest_navscenario.plugin", SUBJECT, "--navsearch", "crate",
                                          "--budget", "20", "--navsearch-shrink-budget", "0")
    assert result.ret == 0, result.stdout.str()
    lines = [line for line in result.stdout.lines if line.startswith("navsearch crate: ")]
    counts = [int(re.match(r"navsearch crate: (\d+)/20 sims", line).group(1)) for line in lines]
    assert {2, 10, 20} <= set(counts), lines          # a line per tenth of the budget
    assert len(lines) <= 10 + 20 // 2, lines            # occasional lines, not one per simulation
    assert not any("\r" in line for line in result.stdout.lines)


def test_stuck_after_option_is_checked(project):
    result = run(project, "--navsearch", "crate", "--navsearch-stuck-after", "-3")
    assert result.ret != 0
    result.stderr.fnmatch_lines(["*--navsearch-stuck-after: the stuck time must be >= 0 seconds*"])
    result = run(project, "--navsearch", "crate", "--navsearch-strategy", "climb")
    result.stderr.fnmatch_lines(["*unknown strategy 'climb'; use one of evolve, random, hillclimb*"])


def test_shrink_budget_is_a_share_and_the_summary_and_log_say_how_sims_were_spent(project):
    result = run(project, "--navsearch", "crate", "--budget", "8", "--navsearch-seed", "3",
                 "--navsearch-shrink-budget", "150%")
    assert result.ret == 0, result.stdout.str()
    line = next(x for x in result.stdout.lines if x.startswith("crate vs "))
    search, shrink, total = map(int, re.search(r"(\d+) sims searching \+ (\d+) shrinking \(shrink budget "
                                               r"(\d+)\)", line).groups())
    assert (search, total) == (8, 12) and 0 < shrink <= 12, line
    records = [json.loads(x) for x in (project.path / "scenarios" / "regressions" / "crate" /
                                       "search-log.jsonl").read_text().splitlines()]
    end = records[-1]
    assert end["record"] == "end" and (end["search_sims"], end["shrink_sims"], end["shrink_budget"]) == (8, shrink, 12)
    assert sum(r.get("phase") == "shrink" for r in records) == shrink


def test_the_summary_says_when_failures_were_frozen_unshrunk(project):
    result = run(project, "--navsearch", "crate", "--budget", "8", "--navsearch-seed", "1",
                 "--navsearch-shrink-budget", "150%", "--navsearch-strategy", "random")
    assert result.ret == 0, result.stdout.str()
    line = next(x for x in result.stdout.lines if x.startswith("crate vs "))
    failures = int(re.search(r"(\d+) distinct failure", line).group(1))
    assert failures > 1, line     # 12 simulations: one failure shrunk with 12, the rest as found
    result.stdout.fnmatch_lines([f"  {failures - 1} of {failures} failure(s) frozen as found: the shrink budget "
                                 f"(12 simulations) went to the most severe and earliest ones*"])


@pytest.mark.parametrize("where, value", [("cli", "lots"), ("cli", "-2"), ("ini", "ten percent")])
def test_a_bad_shrink_budget_is_a_usage_error_that_says_what_works(project, where, value):
    if where == "ini":
        project.makeini(f"[pytest]\nnav_scenario_paths = scenarios\nnavsearch_shrink_budget = {value}\n")
        result = run(project, "--navsearch", "crate")
        option = "ini option navsearch_shrink_budget"
    else:
        result = run(project, "--navsearch", "crate", f"--navsearch-shrink-budget={value}")
        option = "--navsearch-shrink-budget"
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    err = result.stderr.str()
    assert f"{option}: shrink budget '{value}'" in err and "25%" in err and "per failure" in err, err


def test_the_old_per_failure_shrink_budget_still_works(project):
    project.makeini("[pytest]\nnav_scenario_paths = scenarios\nnavsearch_shrink_budget = 3\n")
    result = run(project, "--navsearch", "crate", "--budget", "8", "--navsearch-seed", "3")
    assert result.ret == 0, result.stdout.str()
    line = next(x for x in result.stdout.lines if x.startswith("crate vs "))
    failures = int(re.search(r"(\d+) distinct failure", line).group(1))
    search, shrink, total = map(int, re.search(r"(\d+) sims searching \+ (\d+) shrinking \(shrink budget "
                                               r"(\d+)\)", line).groups())
    assert failures > 0 and total == 3 * failures and shrink <= total, line


def test_the_summary_says_which_run_the_lowest_clearance_came_from():
    """Issue 23 item 4: "best clearance 0.029 m" beside frozen failures of 0.26-0.55 m read as a
    failure's; the summary says it is the lowest of any run and whether that run passed."""
    from pytest_navscenario.plugin.search_report import lowest_clearance_text
    from pytest_navscenario.search.report import Candidate, Failure, SearchReport

    def cand(sim, outcome, clearance, phase="search"):
        return Candidate(sim, phase, "explore", (0.1,), outcome, clearance, "box", "", {}, "h", 0.0)

    report = SearchReport("s", None, "dwa", None, "evolve", 0, 3, "25%", ["x"])
    report.candidates = [cand(1, "safety-stop", 0.26), cand(2, "success", 0.029), cand(3, "timeout", 0.55),
                         cand(1, "safety-stop", 0.001, phase="shrink")]
    report.failures = [Failure(report.candidates[0], report.candidates[0])]
    assert lowest_clearance_text(report) == "lowest clearance of any run 0.029 m (sim 2, a run that passed)"
    report.candidates[1].clearance = 0.4
    assert lowest_clearance_text(report) == "lowest clearance of any run 0.260 m (sim 1, a safety-stop)"


def test_a_search_draws_its_failures_and_writes_its_html_report(project):
    """Issue 23 item 3: --nav-plots and --nav-html were ignored by a search ("0 scenario run(s)")."""
    out = project.path / "scenarios" / "regressions" / "crate"
    result = run(project, "--navsearch", "crate", "--budget", "8", "--navsearch-seed", "3",
                 "--navsearch-shrink-budget", "0", "--nav-plots=failed", "--nav-html=search.html")
    assert result.ret == 0, result.stdout.str()
    frozen = sorted(out.glob("crate-*.yaml"))
    assert frozen
    pictures = sorted(out.glob("crate-*.png"))
    assert [p.stem for p in pictures] == [p.stem for p in frozen]     # one beside each frozen file
    assert all(p.stat().st_size > 20_000 for p in pictures)
    result.stdout.fnmatch_lines([f"  pictures of {len(frozen)} failure(s) in scenarios/regressions/crate/ *"])
    page = (project.path / "search.html").read_text()
    assert "scenario run(s)" not in page and "navsearch report: crate" in page
    assert f"{len(frozen)} distinct failure(s) frozen" in page
    for path in frozen:
        assert f"pytest scenarios/regressions/crate/{path.name} --nav-subject=straight_planner:Straight" in page
    assert page.count('<section class="failure"') == len(frozen)
    assert page.count("data:image/png;base64,") == len(frozen) + 1                  # + the progress chart
    assert "crate vs straight_planner:Straight 1.0: progress" in page
    assert "Discarded before simulation" in page and "lowest clearance of any run" in page
    assert 'class="nav-view"' in page                                               # the time slider

    # without --nav-plots (its default is for scenario items) a search draws nothing
    for p in pictures:
        p.unlink()
    quiet = run(project, "--navsearch", "crate", "--budget", "8", "--navsearch-seed", "3",
                "--navsearch-shrink-budget", "0")
    assert quiet.ret == 0 and not list(out.glob("*.png"))


def test_the_search_report_shows_a_failure_probability_column_when_rows_have_one(tmp_path):
    """The page's data has room for what a search may learn about a failure beyond one run."""
    from pytest_navscenario.report.search_page import FailureRow, Progress, SearchSection, build_search_html

    row = FailureRow(file="scenarios/regressions/s/s-1.yaml", new=True, outcome="timeout", message="m",
                     culprit="box", clearance=0.2, found_at=3, reproduce="pytest x")
    section = SearchSection(title="s vs dwa", facts=[("budget", "8")], progress=Progress(), failures=[row])
    assert "fails in" not in build_search_html([section])
    row.probability, row.interval = 0.6, (0.31, 0.83)
    page = build_search_html([section])
    assert "<th>fails in</th>" in page and "60% <small>[31&ndash;83]</small>" in page


def test_two_searches_into_one_folder_keep_both_logs_and_all_frozen_files(project):
    """Issue 26: the log held only the last search's lines; now each search appends its own,
    between a start and an end record carrying its id."""
    from pytest_navscenario.search.freeze import read_search_log

    folder = project.path / "scenarios" / "regressions" / "crate"
    kept = []
    for seed in ("3", "4"):
        result = run(project, "--navsearch", "crate", "--budget", "6", "--navsearch-seed", seed)
        assert result.ret == 0, result.stdout.str()
        kept.append({p.name for p in folder.glob("crate-*.yaml")})
    searches = list(read_search_log(folder / "search-log.jsonl").values())
    assert [(s[0]["record"], s[0]["search_seed"], s[-1]["record"]) for s in searches] == \
        [("start", 3, "end"), ("start", 4, "end")]
    assert all(sum(r["record"] == "candidate" and r["phase"] == "search" for r in s) == 6 for s in searches)
    assert kept[0] <= kept[1]                                   # the first search's files are all still there


BROKEN = '''
class Broken:
    def reset(self, scenario):
        raise RuntimeError("map server unreachable")

    def act(self, obs):
        return (0.0, 0.0, 0.0)
'''


def test_a_search_whose_every_simulation_is_the_same_subject_error_says_so(project):
    # the planner fails whatever the layout: the summary only said "4 distinct failure(s) (subject-error 4)"
    # and froze them as regressions, without saying that the subject itself is broken, nor how
    project.makepyfile(broken_planner=BROKEN)
    result = project.runpytest_inprocess("-p", "pytest_navscenario.plugin", "--nav-subject=broken_planner:Broken",
                                         "--navsearch", "crate", "--budget", "4")
    result.stdout.fnmatch_lines(["*every one of the 4 simulations ended the same way: subject-error: planner.reset "
                                 "raised RuntimeError: map server unreachable; the subject fails whatever the "
                                 "layout: fix it (navscenario check-planner SPEC) before searching*"])
    assert "ended the same way" not in run(project, "--navsearch", "crate", "--budget", "4").stdout.str()
