"""compare.py and ``navscenario compare`` on hand-made results files."""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import pytest

from pytest_navscenario.cli import main
from pytest_navscenario.report.compare import compare_files, compare_records, format_comparison
from pytest_navscenario.report.results_file import ResultsFileError, write_results


_SAME = object()


def rec(nodeid, outcome, *, family=None, subject="dwa", h=None, repeat=0, seed=7, message="", spec=_SAME):
    """A record as pytest writes it; ``spec`` (default: the subject) is its subject_spec."""
    name = nodeid.split("::")[-1]
    return {
        "format": "navscenario-results", "format_version": 1, "tool_version": "0.1.0",
        "nodeid": nodeid, "path": nodeid.split("::")[0], "scenario": name,
        "family": family or nodeid.split("/")[1], "scenario_hash": h or f"h-{name}",
        "subject": subject, "subject_version": None, "seed": seed, "repeat": repeat,
        "subject_spec": subject if spec is _SAME else spec,
        "outcome": outcome, "passed": outcome == "success", "message": message or outcome,
        "metrics": {"min_clearance": 0.2}, "wall_time": 0.01,
    }


def suite(outcomes: dict[str, str], **kw):
    return [rec(n, o, **kw) for n, o in outcomes.items()]


BASE = {
    "scenarios/boxes/b1.yaml::b1": "success",
    "scenarios/boxes/b2.yaml::b2": "success",
    "scenarios/boxes/b3.yaml::b3": "collision",
    "scenarios/corridor/c1.yaml::c1": "safety-stop",
    "scenarios/corridor/c2.yaml::c2": "timeout",
}


@pytest.fixture
def files(tmp_path):
    def make(a_records, b_records):
        a, b = tmp_path / "a.jsonl", tmp_path / "b.jsonl"
        write_results(a, a_records)
        write_results(b, b_records)
        return a, b
    return make


def test_improvement_and_regression_per_family(files, capsys):
    changed = dict(BASE)
    changed["scenarios/boxes/b2.yaml::b2"] = "safety-stop"     # broke
    changed["scenarios/boxes/b3.yaml::b3"] = "success"         # fixed
    changed["scenarios/corridor/c1.yaml::c1"] = "success"      # fixed
    changed["scenarios/corridor/c2.yaml::c2"] = "success"      # fixed
    a, b = files(suite(BASE, subject="dwa"), suite(changed, subject="mypkg.nav:Planner"))
    cmp = compare_files(a, b)
    assert [p.nodeid for p in cmp.broke] == ["scenarios/boxes/b2.yaml::b2"]
    assert [p.nodeid for p in cmp.fixed] == ["scenarios/boxes/b3.yaml::b3", "scenarios/corridor/c1.yaml::c1",
                                             "scenarios/corridor/c2.yaml::c2"]
    boxes, corridor = cmp.families
    assert (boxes.family, boxes.n, boxes.broke, boxes.fixed) == ("boxes", 3, 1, 1)
    assert boxes.a["success"].count == 2 and boxes.b["success"].count == 2
    assert boxes.b["safety-stop"].count == 1 and boxes.a["collision"].count == 1
    assert corridor.a["success"].rate == 0 and corridor.b["success"].rate == 1
    assert corridor.success_change == pytest.approx(1.0)
    assert cmp.overall.n == 5 and cmp.overall.mcnemar_p == pytest.approx(0.625)  # b=1, c=3
    assert boxes.metrics["min_clearance"] == (0.2, 0.2, 1)    # only b1 passed under both
    assert corridor.metrics["min_clearance"][2] == 0
    lo, hi = corridor.b["success"].low, corridor.b["success"].high
    assert lo == pytest.approx(0.3424, abs=1e-4) and hi == 1.0                   # Wilson 2/2

    assert main(["compare", str(a), str(b), "--fail-on-regression"]) == 1
    out = capsys.readouterr().out
    assert "B broke (regressions: A passed, B failed) (1):" in out
    assert "reproduce: pytest scenarios/boxes/b2.yaml::b2 --nav-subject=mypkg.nav:Planner" in out
    assert "B fixed (A failed, B passed) (3):" in out
    assert "result: 1 regression(s), 3 fix(es)" in out
    assert "metrics over the pairs both passed, median A -> B:" in out
    assert main(["compare", str(a), str(b)]) == 0   # without the gate: report only


def test_identical_runs(files, capsys):
    a, b = files(suite(BASE), suite(BASE))
    cmp = compare_files(a, b)
    assert not cmp.broke and not cmp.fixed and not cmp.only_a and not cmp.not_comparable
    assert all(f.mcnemar_p == 1.0 and f.success_change == 0 for f in cmp.families)
    assert main(["compare", str(a), str(b), "--fail-on-regression"]) == 0
    assert "result: 0 regression(s), 0 fix(es)" in capsys.readouterr().out


def test_disjoint_sets_and_changed_scenario_are_reported_not_paired(files, capsys):
    a_recs = suite(BASE)
    b_recs = [rec("scenarios/boxes/new.yaml::new", "collision")]
    b_recs.append(rec("scenarios/boxes/b1.yaml::b1", "collision", h="other-layout"))
    a, b = files(a_recs, b_recs)
    cmp = compare_files(a, b)
    assert cmp.pairs == [] and cmp.broke == []
    assert [u.nodeid for u in cmp.not_comparable] == ["scenarios/boxes/b1.yaml::b1"]
    assert "scenario changed between the runs" in cmp.not_comparable[0].reason
    assert len(cmp.only_a) == 4 and [u.nodeid for u in cmp.only_b] == ["scenarios/boxes/new.yaml::new"]
    assert main(["compare", str(a), str(b), "--fail-on-regression"]) == 1   # nothing compared: no pass
    out = capsys.readouterr().out
    assert "not comparable (1):" in out and "only in A" in out and "only in B" in out
    assert "could be paired" in out and "nothing to compare" in out


def test_repeats_are_paired_by_index(files):
    a_recs = [rec("scenarios/boxes/b1.yaml::b1", "success", repeat=r, seed=r) for r in range(3)]
    b_recs = [rec("scenarios/boxes/b1.yaml::b1", o, repeat=r, seed=r, subject="new")
              for r, o in enumerate(["success", "collision", "success"])]
    cmp = compare_records(a_recs, b_recs)
    assert cmp.overall.n == 3
    assert [(p.nodeid, p.repeat) for p in cmp.broke] == [("scenarios/boxes/b1.yaml::b1", 1)]
    assert "(repeat 1)" in format_comparison(cmp) and "episode seed 1" in format_comparison(cmp)
    with pytest.raises(ResultsFileError, match="two records for"):
        compare_records(a_recs + a_recs[:1], b_recs)


def test_other_format_version_is_one_clear_line(files, tmp_path, capsys):
    a, b = files(suite(BASE), suite(BASE))
    old = rec("scenarios/boxes/b1.yaml::b1", "success")
    old["format_version"] = 0
    b.write_text(json.dumps(old) + "\n")
    assert main(["compare", str(a), str(b)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{b}:1: results format version 0" in err[0]
    assert main(["compare", str(a), str(tmp_path / "missing.jsonl")]) == 2
    assert "no such results file" in capsys.readouterr().err
    incomplete = rec("scenarios/boxes/b1.yaml::b1", "success")
    del incomplete["scenario_hash"]
    b.write_text(json.dumps(incomplete) + "\n")
    assert main(["compare", str(a), str(b)]) == 2
    assert f"{b}:1: record lacks field(s) scenario_hash" in capsys.readouterr().err


def test_junit_one_case_per_scenario_failing_on_regressions(files, tmp_path):
    changed = dict(BASE, **{"scenarios/boxes/b1.yaml::b1": "collision"})
    b_recs = suite(changed, subject="new") + [rec("scenarios/boxes/extra.yaml::extra", "success")]
    a, b = files(suite(BASE), b_recs)
    out = tmp_path / "cmp.xml"
    assert main(["compare", str(a), str(b), "--junit", str(out)]) == 0
    cases = ET.parse(out).getroot().findall(".//testcase")
    assert len(cases) == 6
    failed = [c.get("name") for c in cases if c.find("failure") is not None]
    skipped = [c.get("name") for c in cases if c.find("skipped") is not None]
    assert failed == ["scenarios/boxes/b1.yaml::b1"] and skipped == ["scenarios/boxes/extra.yaml::extra"]
    assert "--nav-subject=new" in ET.tostring(cases[0], encoding="unicode")
    suite_el = ET.parse(out).getroot().find(".//testsuite")
    assert suite_el.get("name") == "navscenario compare: dwa -> dwa, new"   # A -> B (B mixes two subjects)


def test_side_by_side_reruns_regressions_with_both_subjects(tmp_path, capsys):
    """--side-by-side re-runs what B broke with both subjects (real MuJoCo episodes), writes one
    plot per scenario, says when a re-run disagrees with the file, and refuses a changed file."""
    from matplotlib.image import imread

    from pytest_navscenario.scenario.loader import loads_scenario
    from pytest_navscenario.scenario.model import content_hash

    text = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1.5, y: 0}, timeout: 5}\n"
    (tmp_path / "s").mkdir()
    (tmp_path / "s" / "short.yaml").write_text(text)
    (tmp_path / "s" / "moved.yaml").write_text(text.replace("x: 1.5", "x: 1.0"))
    h = content_hash(loads_scenario(text))  # moved.yaml was edited after the run: its hash differs now
    a_recs = [dict(rec("s/short.yaml::short", "success", h=h, subject="dwa"), path="s/short.yaml"),
              dict(rec("s/moved.yaml::moved", "success", h=h, subject="dwa"), path="s/moved.yaml")]
    b_recs = [dict(r, outcome="collision", subject="potential-field", subject_spec="potential-field")
              for r in a_recs]
    a, b = tmp_path / "a.jsonl", tmp_path / "b.jsonl"
    write_results(a, a_recs)
    write_results(b, b_recs)
    out = tmp_path / "sbs"
    assert main(["compare", str(a), str(b), "--side-by-side", str(out), "--root", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    pngs = list(out.glob("*.png"))
    assert len(pngs) == 1 and pngs[0].name.startswith("s_short.yaml_short")
    assert imread(str(pngs[0])).shape[1] > 600
    assert "1 of 2 side-by-side plot(s) written" in captured.out
    assert "s/short.yaml::short: B re-run gave success, the results file says collision" in captured.err
    assert "moved.yaml changed since the run" in captured.err


def test_side_by_side_says_its_cap_and_how_to_raise_it(tmp_path, capsys):
    """Issue 32 item 3: "10 of 10 side-by-side plot(s)" for 12 regressions hid the other two."""
    from pytest_navscenario.scenario.loader import loads_scenario
    from pytest_navscenario.scenario.model import content_hash

    text = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1.5, y: 0}, timeout: 5}\n"
    (tmp_path / "s").mkdir()
    a_recs = []
    for name in ("p", "q", "r"):
        (tmp_path / "s" / f"{name}.yaml").write_text(text)
        a_recs.append(dict(rec(f"s/{name}.yaml::{name}", "success", h=content_hash(loads_scenario(text)),
                               subject="dwa", spec="dwa"), path=f"s/{name}.yaml"))
    b_recs = [dict(r, outcome="collision") for r in a_recs]
    a, b = tmp_path / "a.jsonl", tmp_path / "b.jsonl"
    write_results(a, a_recs)
    write_results(b, b_recs)
    args = ["compare", str(a), str(b), "--side-by-side", str(tmp_path / "sbs"), "--root", str(tmp_path)]
    assert main([*args, "--max-plots", "2"]) == 0
    out = capsys.readouterr().out
    assert "2 of 2 side-by-side plot(s) written" in out
    assert ("side-by-side: B broke or fixed 3 scenarios; plotted the first 2 (--max-plots 2, default 10: "
            "broken ones first); --max-plots 3 or 0 plots them all") in out
    assert main([*args, "--max-plots", "0"]) == 0
    out = capsys.readouterr().out
    assert "3 of 3 side-by-side plot(s) written" in out and "plotted the first" not in out
    assert len(list((tmp_path / "sbs").glob("*.png"))) == 3


def test_reproduce_commands_use_the_recorded_spec_never_the_display_name(files, tmp_path, capsys):
    """Issue 23 item 2: a planner named "careful" ran as --nav-subject=mynav:Careful."""
    broke = dict(BASE, **{"scenarios/boxes/b2.yaml::b2": "safety-stop"})
    a, b = files(suite(BASE), suite(broke, subject="careful", spec="mynav:Careful"))
    xml = tmp_path / "compare.xml"
    assert main(["compare", str(a), str(b), "--junit", str(xml)]) == 0
    out = capsys.readouterr().out
    assert "reproduce: pytest scenarios/boxes/b2.yaml::b2 --nav-subject=mynav:Careful" in out
    assert "--nav-subject=careful" not in out
    junit = xml.read_text()
    assert "--nav-subject=mynav:Careful" in junit and "--nav-subject=careful" not in junit

    hook = suite(broke, subject="careful", spec=None)     # a conftest hook made the subject
    old = [{k: v for k, v in r.items() if k != "subject_spec"} for r in hook]   # an older file
    cmp = compare_records(suite(BASE), hook)
    assert cmp.reproduce_command(cmp.broke[0]) == (
        "pytest scenarios/boxes/b2.yaml::b2  # subject careful from the project's "
        "pytest_navscenario_make_subject hook")
    cmp = compare_records(suite(BASE), old)
    assert cmp.reproduce_command(cmp.broke[0]).startswith(
        "pytest scenarios/boxes/b2.yaml::b2  # subject careful: its --nav-subject spec is unknown")


def test_side_by_side_without_a_spec_to_rerun_says_what_is_needed_and_fails(files, tmp_path, capsys):
    broke = dict(BASE, **{"scenarios/boxes/b2.yaml::b2": "safety-stop"})
    a, b = files(suite(BASE, subject="careful", spec=None), suite(broke, subject="careful", spec=None))
    out = tmp_path / "sbs"
    assert main(["compare", str(a), str(b), "--side-by-side", str(out)]) == 2
    err = capsys.readouterr().err
    assert "cannot re-run A (subject 'careful'): its results file records no --nav-subject spec " \
           "(it came from a conftest pytest_navscenario_make_subject hook); give it with --a-subject SPEC" in err
    assert err.count("cannot re-run A") == 1      # said once, not once per scenario
    assert "none of the 1 side-by-side plot(s) could be made" in err
    assert not list(tmp_path.glob("sbs/*.png"))
    a, b = files(suite(BASE), suite(BASE))           # nothing broke or fixed: nothing to show
    assert main(["compare", str(a), str(b), "--side-by-side", str(out)]) == 0
    assert "no side-by-side plots: B neither broke nor fixed a scenario A ran" in capsys.readouterr().out


def test_html_comparison_report(files, tmp_path):
    changed = dict(BASE, **{"scenarios/boxes/b1.yaml::b1": "collision"})
    b_recs = suite(changed, subject="new") + [rec("scenarios/boxes/extra.yaml::extra", "timeout")]
    a, b = files(suite(BASE), b_recs)
    out = tmp_path / "cmp.html"
    assert main(["compare", str(a), str(b), "--html", str(out)]) == 0
    page = out.read_text()
    # B's failures: b1 (broke), b3, c1, c2 (failed in both), extra (only in B)
    assert page.count('<section class="failure"') == 5
    assert 'id="comparison"' in page and "B broke (A passed, B failed) (1)" in page
    assert page.count("data:image/png;base64,") == 1       # the bar chart
    assert "pytest scenarios/boxes/b1.yaml::b1 --nav-subject=new" in page
    # the comparison is A (baseline) -> B (candidate): the title says it in that order
    assert "<title>navscenario compare: dwa → dwa, new</title>" in page and "new vs dwa" not in page


def test_subject_errors_get_their_own_column():
    changed = dict(BASE, **{"scenarios/boxes/b1.yaml::b1": "subject-error"})
    cmp = compare_records(suite(BASE), suite(changed, subject="new"))
    assert cmp.overall.b["subject-error"].count == 1 and cmp.overall.a["subject-error"].count == 0
    header = next(line for line in format_comparison(cmp).splitlines() if line.startswith("family"))
    assert header.split()[2:7] == ["success", "safety-stop", "timeout", "collision", "error"]
    assert "error" not in format_comparison(compare_records(suite(BASE), suite(BASE))).split("\n\n")[1]


@pytest.mark.parametrize("case, why", [
    ("b-empty", "B ({b}) has no records"),
    ("disjoint", "A and B share no scenario"),
    ("a-empty", "A ({a}) has no records"),
    ("all-changed", "the 5 scenario run(s) A and B share changed between the runs"),
])
def test_nothing_compared_fails_the_gate_and_says_why(files, capsys, case, why):
    """A candidate run that crashed before writing results (B empty), or a run of another suite,
    must not pass the CI gate: nothing compared is not 'no regression'."""
    a_recs, b_recs = suite(BASE), suite(BASE, subject="new")
    if case == "b-empty":
        b_recs = []
    elif case == "a-empty":
        a_recs = []
    elif case == "disjoint":
        b_recs = [rec("scenarios/other/x.yaml::x", "success")]
    else:  # every shared scenario changed its layout: not comparable
        b_recs = [dict(r, scenario_hash="other") for r in b_recs]
    a, b = files(a_recs, b_recs)
    assert main(["compare", str(a), str(b), "--fail-on-regression"]) == 1
    captured = capsys.readouterr()
    assert "nothing to compare" in captured.out
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("navscenario compare: FAILED the gate: nothing was compared: ")
    assert why.format(a=a, b=b) in err[0]
    assert main(["compare", str(a), str(b)]) == 0          # without the gate: report only
    assert "navscenario compare: warning: nothing was compared: " in capsys.readouterr().err
