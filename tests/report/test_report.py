"""report_plugin + html_report end to end: real pytest runs (plugin autoload disabled, loaded with
-p), real scenario files, real MuJoCo episodes, a hand-made baseline results file.

The project: ``ok`` (a planner that drives straight reaches the goal) and ``crash`` (it drives into
a wall with the safety layer off; marked xfail in its YAML, so the test run itself passes). The
baseline says both passed, so ``crash`` is a regression that only the gate can turn into a failed
session. The runs are started together and shared by the tests.
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.report.results_file import write_results
from pytest_navscenario.scenario.model import content_hash

PLANNER = '''
import math


class Straight:
    """Drives straight at the target at full speed, obstacles or not."""
    name = "straight"

    def reset(self, scenario):
        self.speed = scenario.robot.limits.max_speed

    def act(self, obs):
        x, y, yaw = obs.pose
        tx, ty = obs.target
        dx, dy = tx - x, ty - y
        d = math.hypot(dx, dy) or 1.0
        c, s = math.cos(yaw), math.sin(yaw)
        v = min(self.speed, d)
        return (c * dx + s * dy) / d * v, (-s * dx + c * dy) / d * v, 0.0
'''

CONFTEST = '''
import sys


def pytest_unconfigure(config):
    if not hasattr(config, "workerinput"):
        print("MATPLOTLIB-IMPORTED:", "matplotlib" in sys.modules)
        print("JINJA2-IMPORTED:", "jinja2" in sys.modules)
'''

OK = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 2, y: 0}, timeout: 10}\n"
CRASH = ("version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 4, y: 0}, timeout: 10}\n"
         "robot: {safety: {enabled: false}}\n"
         "obstacles: [{type: box, name: wall, x: 2, y: 0, length: 0.4, width: 2}]\n"
         "marks: [{xfail: {reason: known to crash}}]\n")
SUBJECT = "--nav-subject=straight:Straight"
COMMON = ["-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider", SUBJECT, "--nav-baseline=base.jsonl"]

RUNS = {
    # regression gate on, HTML report, default plots (failing items, into the artifacts folders),
    # side-by-side plots of regressions (the baseline subject re-run: here the same planner)
    "gate": ["scenarios", *COMMON, "--nav-html=out/report.html", "--nav-baseline-subject=straight:Straight"],
    # warn only; plots of every item (at most 2) into one folder; on 2 xdist workers (plots made on
    # the controller); this project has a third scenario, ok2
    "warn": ["scenarios", *COMMON, "--nav-baseline-mode=warn", "--nav-plots=all", "--nav-plots-dir=plots",
             "--nav-plots-max=2", "-p", "xdist.plugin", "-n", "2"],
    # a default run where everything passes: no plot, matplotlib never imported
    "pass": ["scenarios/ok.yaml", "-p", "pytest_navscenario.plugin", "-p", "no:cacheprovider", SUBJECT],
    # a baseline that is not a results file: one clear usage error before anything runs
    "bad": ["scenarios", *COMMON[:-1], "--nav-baseline=scenarios/ok.yaml"],
}


def record(root: Path, rel: str, outcome: str) -> dict:
    name = Path(rel).stem
    text = (root / rel).read_text() if (root / rel).exists() else OK
    return {"format": "navscenario-results", "format_version": 1, "tool_version": "0.1.0",
            "nodeid": f"{rel}::{name}", "path": rel, "scenario": name, "family": "scenarios",
            "scenario_hash": content_hash(loads_scenario(text)), "subject": "old-planner",
            "subject_version": "1.0", "seed": 0, "repeat": 0, "outcome": outcome,
            "passed": outcome == "success", "message": outcome, "metrics": {}, "wall_time": 0.1}


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory):
    """Start the four runs at once (each in its own copy of the project); {name: (proc, root)}."""
    procs = {}
    for name, args in RUNS.items():
        root = tmp_path_factory.mktemp(f"report-{name}")
        (root / "straight.py").write_text(PLANNER)
        (root / "conftest.py").write_text(CONFTEST)
        (root / "scenarios").mkdir()
        (root / "scenarios" / "ok.yaml").write_text(OK)
        (root / "scenarios" / "crash.yaml").write_text(CRASH)
        if name == "warn":
            (root / "scenarios" / "ok2.yaml").write_text(OK.replace("x: 2", "x: 1.5"))
        base = [record(root, "scenarios/ok.yaml", "success"), record(root, "scenarios/crash.yaml", "success"),
                record(root, "scenarios/gone.yaml", "success")]
        write_results(root / "base.jsonl", base)
        env = dict(os.environ, PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
        env["PYTHONPATH"] = os.pathsep.join([str(root), env.get("PYTHONPATH", "")])
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        procs[name] = (subprocess.Popen([sys.executable, "-m", "pytest", *args], cwd=root, env=env,
                                        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True), root)
    out = {}
    for name, (proc, root) in procs.items():
        stdout, _ = proc.communicate(timeout=180)
        out[name] = (proc.returncode, stdout, root)
    return out


def test_regression_gate_fails_the_session(runs):
    code, out, _ = runs["gate"]
    assert code == 1, out
    assert "1 passed, 1 xfailed" in out                       # the tests themselves pass...
    assert "FAILED the regression gate: 1 scenario(s) the baseline passed fail now" in out  # ...the gate does not
    assert "B broke (regressions: A passed, B failed) (1):" in out
    assert "scenarios/crash.yaml::crash: A success, B collision" in out
    assert "reproduce: pytest scenarios/crash.yaml::crash --nav-subject=straight:Straight --nav-seed=0" in out
    assert "only in A (" in out and "scenarios/gone.yaml::gone" in out
    assert "MATPLOTLIB-IMPORTED: True" in out
    assert "JINJA2-IMPORTED: True" in out
    assert "1 side-by-side plot(s) of regressions (baseline | this run)" in out
    # the "baseline" re-run is the same straight planner: it crashes too, and the run says so
    assert ("scenarios/crash.yaml::crash: the baseline's subject 'straight:Straight' re-run gave collision, "
            "the baseline file says success") in out


def test_warn_mode_reports_but_passes_and_plots_every_item_under_xdist(runs):
    code, out, root = runs["warn"]
    assert code == 0, out
    assert "warning: 1 regression(s) against the baseline" in out
    plots = sorted(p.name for p in (root / "plots").glob("*.png"))
    assert len(plots) == 2 and any(p.startswith("scenarios_ok") for p in plots)  # passing items too
    assert "navscenario: 2 trajectory plot(s) in" in out
    assert "1 more item(s) not plotted: at most 2 plots per session (--nav-plots-max=N" in out
    # the baseline's records name a planner "old-planner" and no spec: never re-run by that name
    assert ("no side-by-side plots: cannot re-run the baseline (subject 'old-planner'): its results file "
            "records no --nav-subject spec") in out and "give it with --nav-baseline-subject SPEC" in out


def test_default_passing_run_does_not_import_matplotlib(runs):
    code, out, root = runs["pass"]
    assert code == 0, out
    assert "MATPLOTLIB-IMPORTED: False" in out
    assert "JINJA2-IMPORTED: False" in out           # the templates are loaded only to write a report
    assert not list(root.rglob("*.png"))


def test_bad_baseline_is_one_clear_usage_error(runs):
    code, out, _ = runs["bad"]
    assert code == 4, out
    assert re.search(r"--nav-baseline: .*ok\.yaml:1: not JSON .*is this a --nav-results file\?", out), out
    assert "passed" not in out


def test_failure_plot_lands_in_the_items_artifacts_folder(runs):
    _, _, root = runs["gate"]
    plots = list((root / "nav-artifacts").glob("scenarios_crash.yaml_crash-*/plots/trajectory.png"))
    assert len(plots) == 1 and plots[0].stat().st_size > 20_000
    side = plots[0].with_name("trajectory-vs-baseline.png")
    assert side.stat().st_size > 20_000
    assert not list((root / "nav-artifacts").glob("scenarios_ok*"))


def test_html_report_is_self_contained_with_one_entry_per_failure(runs):
    _, out, root = runs["gate"]
    page = (root / "out" / "report.html").read_text()
    assert "HTML report written to" in out
    assert page.count('<section class="failure"') == 1
    assert 'data-outcome="collision"' in page and 'data-family="scenarios"' in page
    # crash is marked xfail: an expected failure, shown apart, not counted as a failure
    assert "<h2>Failures (0)</h2>" in page and "<h2>Expected failures (xfail) (1)</h2>" in page
    assert "expected to fail (xfail): known to crash" in page
    assert "2 scenario run(s): 1 success, 1 collision (1 expected to fail: xfail)" in page
    assert page.count("data:image/png;base64,") == 3         # the failure's plot, side by side, bar chart
    assert "The same scenario under the baseline and now:" in page
    assert not re.search(r"(src|href)=\"(https?:)?//", page)  # nothing fetched from a server
    assert 'id="comparison"' in page and "B broke (A passed, B failed) (1)" in page
    assert "<script>" in page and "sortFailures" in page and 'class="sortable"' in page
    assert page.count("<tr><td>") >= 2                        # runs table: one row per scenario
    # the failure's interactive time-slider view: the episode's poses as JSON next to a canvas
    views = re.findall(r'<script type="application/json" class="nav-view">(.*?)</script>', page)
    assert len(views) == 1 and '<div class="viewer"><canvas' in page
    view = json.loads(views[0])
    assert 2 <= len(view["t"]) <= 400 and len(view["x"]) == len(view["v"]) == len(view["t"])
    assert view["t"][-1] == pytest.approx(1.6, abs=0.1) and len(view["obs"]) == 1   # the crash, the wall


def test_html_escapes_names_and_messages(tmp_path):
    from pytest_navscenario.report.html import Entry, write_html

    rec = {"nodeid": "s/<b>.yaml::<script>alert(1)</script>", "family": "f&g", "outcome": "timeout",
           "message": "goal <not> reached", "metrics": {"min_clearance": None, "duration": 3.0},
           "repeat": 0, "seed": 1, "subject": "x"}
    passing = [Entry(dict(rec, nodeid="b", outcome="success")), Entry(dict(rec, nodeid="c", outcome="success"), b"png")]
    page = write_html(tmp_path / "r.html", [Entry(rec), *passing]).read_text()
    assert "<script>alert" not in page and "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    assert page.count('<section class="failure"') == 1 and "goal &lt;not&gt; reached" in page
    assert page.count('<section class="passed"') == 1   # only passing runs that have a plot
    assert json.dumps("f&amp;g")[1:-1] in page


@pytest.mark.parametrize("option, message", [
    ("--nav-plots=sometimes", "--nav-plots: expected one of failed, all, none, got 'sometimes'"),
    ("--nav-baseline-mode=maybe", "--nav-baseline-mode: expected one of fail, warn, got 'maybe'"),
    ("--nav-plots-max=-1", "--nav-plots-max: expected a whole number >= 0 (0 = no limit), got '-1'"),
    ("--nav-baseline=missing.jsonl", "--nav-baseline: no results file"),
])
def test_bad_option_values_are_usage_errors(pytester: pytest.Pytester, monkeypatch, option, message):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    result = pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", option)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert message in result.stderr.str()


@pytest.mark.parametrize("mode, status", [("fail", pytest.ExitCode.TESTS_FAILED), ("warn", pytest.ExitCode.OK)])
def test_gate_exit_status_with_pytester(pytester: pytest.Pytester, monkeypatch, mode, status):
    """The regression gate in-process: the items pass (crash is xfail), only the gate decides."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.syspathinsert()
    pytester.makepyfile(straight=PLANNER)
    pytester.mkdir("scenarios")
    (pytester.path / "scenarios" / "ok.yaml").write_text(OK)
    (pytester.path / "scenarios" / "crash.yaml").write_text(CRASH)
    write_results(pytester.path / "base.jsonl", [record(pytester.path, "scenarios/ok.yaml", "success"),
                                                 record(pytester.path, "scenarios/crash.yaml", "success")])
    result = pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "scenarios", SUBJECT,
                                          "--nav-baseline=base.jsonl", f"--nav-baseline-mode={mode}",
                                          "--nav-plots=none")
    assert result.ret == status
    result.assert_outcomes(passed=1, xfailed=1)
    result.stdout.fnmatch_lines(["*B broke (regressions: A passed, B failed) (1):*"])


@pytest.mark.parametrize("mode, status", [("fail", pytest.ExitCode.TESTS_FAILED), ("warn", pytest.ExitCode.OK)])
def test_gate_fails_when_the_run_ran_none_of_the_baselines_scenarios(pytester: pytest.Pytester, monkeypatch,
                                                                     mode, status):
    """--nav-baseline whose scenarios this run did not run (another suite, a selection that
    missed them): nothing was compared, which is no evidence of no regression."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.syspathinsert()
    pytester.makepyfile(straight=PLANNER)
    pytester.mkdir("scenarios")
    (pytester.path / "scenarios" / "ok.yaml").write_text(OK)
    write_results(pytester.path / "base.jsonl", [record(pytester.path, "scenarios/gone.yaml", "success"),
                                                 record(pytester.path, "scenarios/other.yaml", "success")])
    result = pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "scenarios", SUBJECT,
                                          "--nav-baseline=base.jsonl", f"--nav-baseline-mode={mode}",
                                          "--nav-plots=none")
    assert result.ret == status
    result.assert_outcomes(passed=1)
    verdict = "FAILED the regression gate" if mode == "fail" else "warning"
    result.stdout.fnmatch_lines([f"navscenario: {verdict}: nothing was compared with the baseline: this run "
                                 f"ran none of its 2 scenario run(s) (1 run now, not in it)*"])


def test_gate_fails_on_an_empty_baseline(pytester: pytest.Pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.syspathinsert()
    pytester.makepyfile(straight=PLANNER)
    pytester.mkdir("scenarios")
    (pytester.path / "scenarios" / "ok.yaml").write_text(OK)
    (pytester.path / "base.jsonl").write_text("")
    result = pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "scenarios", SUBJECT,
                                          "--nav-baseline=base.jsonl", "--nav-plots=none")
    assert result.ret == pytest.ExitCode.TESTS_FAILED
    result.stdout.fnmatch_lines(["navscenario: FAILED the regression gate: nothing was compared with the "
                                 "baseline: the baseline * has no records*"])


def test_html_counts_expected_failures_apart(tmp_path):
    from pytest_navscenario.report.html import Entry, write_html

    def rec(nodeid, outcome):
        return {"nodeid": nodeid, "family": "f", "outcome": outcome, "message": outcome, "metrics": {},
                "repeat": 0, "seed": 1, "subject": "x"}
    entries = [Entry(rec("a", "collision")), Entry(rec("b", "timeout"), xfail_reason="known <slow>"),
               Entry(rec("c", "success"))]
    page = write_html(tmp_path / "r.html", entries).read_text()
    assert "<h2>Failures (1)</h2>" in page and "<h2>Expected failures (xfail) (1)</h2>" in page
    assert "3 scenario run(s): 1 success, 1 timeout, 1 collision (1 expected to fail: xfail)" in page
    failures, expected = page.split("<h2>Expected failures (xfail)")
    assert 'data-nodeid="a"' in failures and 'data-nodeid="b"' not in failures
    assert 'data-nodeid="b"' in expected and "expected to fail (xfail): known &lt;slow&gt;" in expected
    assert '<a href="#f-' in page.split('id="runs"')[1].split("</table>")[0]   # both linked from the table
    plain = write_html(tmp_path / "p.html", entries[:1]).read_text()
    assert "Expected failures" not in plain and "expected to fail" not in plain


def test_expected_failures_apart_under_xdist(pytester: pytest.Pytester, monkeypatch):
    """xdist workers send the report with its xfail mark: the controller's page still knows."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(straight=PLANNER)
    pytester.mkdir("scenarios")
    (pytester.path / "scenarios" / "ok.yaml").write_text(OK)
    (pytester.path / "scenarios" / "crash.yaml").write_text(CRASH)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(pytester.path), os.environ.get("PYTHONPATH", "")]))
    result = pytester.runpytest_subprocess("-p", "pytest_navscenario.plugin", "-p", "xdist.plugin", "-n", "2",
                                           "scenarios", SUBJECT, "--nav-html=r.html")
    assert result.ret == pytest.ExitCode.OK
    page = (pytester.path / "r.html").read_text()
    assert "<h2>Failures (0)</h2>" in page and "<h2>Expected failures (xfail) (1)</h2>" in page


def test_json_files_nested_too_deeply_are_errors_naming_the_file(tmp_path):
    # json.loads raised RecursionError: a traceback from navscenario compare, the baseline, imports
    from pytest_navscenario.report.results_file import ResultsFileError, read_results
    from pytest_navscenario.ros.qgc_plan import PlanError, read_plan
    from pytest_navscenario.search.freeze import read_search_log

    deep = tmp_path / "deep.jsonl"
    deep.write_text("[" * 100000 + "]" * 100000 + "\n")
    with pytest.raises(ResultsFileError, match=rf"{re.escape(str(deep))}:1: not JSON \(nested too deeply\)"):
        read_results(deep)
    with pytest.raises(PlanError, match=rf"{re.escape(str(deep))}: not valid JSON \(nested too deeply\)"):
        read_plan(deep)
    log = tmp_path / "search-log.jsonl"
    log.write_text('[1, 2]\n' + deep.read_text() + json.dumps({"search": "s1", "type": "start"}) + "\n")
    assert read_search_log(log) == {"s1": [{"search": "s1", "type": "start"}]}    # the others skipped
