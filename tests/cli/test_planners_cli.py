"""``navscenario run`` and ``navscenario check-planner``, called through cli.main."""
from __future__ import annotations

import json
import textwrap
from pathlib import Path

from pytest_navscenario import cli

SEEDS_DIR = Path(__file__).resolve().parents[2] / "scenarios"


def test_run_prints_outcome_message_and_metrics_and_exits_0_on_success(capsys):
    code = cli.main(["run", str(SEEDS_DIR / "boxes1.yaml"), "--subject", "dwa", "--seed", "0"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "boxes1" in out and "with dwa 1.1, seed 0" in out
    assert "outcome: success" in out and "message: success in" in out
    assert "min_clearance            0.750 m" in out and "path_efficiency" in out


def test_run_json_and_exit_1_on_a_failing_outcome(capsys):
    code = cli.main(["run", str(SEEDS_DIR / "boxes2.yaml"), "-s", "potential-field", "--json"])
    record = json.loads(capsys.readouterr().out)
    assert code == 1
    assert record["outcome"] == "safety-stop" and record["passed"] is False
    assert "box_near" in record["message"] and record["subject"] == "potential-field"
    assert 0 < record["metrics"]["min_clearance"] < 1 and record["seed"] == 0


def test_run_with_a_bad_file_or_subject_says_what_is_wrong_and_exits_2(tmp_path, capsys):
    assert cli.main(["run", str(tmp_path / "missing.yaml")]) == 2
    assert "missing.yaml" in capsys.readouterr().err
    code = cli.main(["run", str(SEEDS_DIR / "boxes1.yaml"), "--subject", "nope"])
    err = capsys.readouterr().err
    assert code == 2 and "subject 'nope'" in err and "potential-field" in err


def test_check_planner_passes_builtins_and_fails_a_broken_user_planner(tmp_path, monkeypatch, capsys):
    assert cli.main(["check-planner", "potential-field", "--ticks", "5"]) == 0
    assert "check_planner(potential-field): OK after 5 ticks" in capsys.readouterr().out

    (tmp_path / "my_broken_nav.py").write_text(textwrap.dedent("""
        class Planner:
            def reset(self, scenario):
                pass
            def act(self, obs):
                return [1.0, 0.0]
    """))
    monkeypatch.syspath_prepend(str(tmp_path))
    assert cli.main(["check-planner", "my_broken_nav:Planner", "--ticks", "3"]) == 1
    out = capsys.readouterr().out
    assert "FAILED" in out and "problem: planner.act returned a list of length 2" in out

    assert cli.main(["check-planner", "my_broken_nav:Planner", "--json",
                     "--scenario", str(SEEDS_DIR / "corridor.yaml")]) == 1
    record = json.loads(capsys.readouterr().out)
    assert record["ok"] is False and len(record["problems"]) == 1


def test_run_has_pytests_tick_limit_and_check_planner_warns_about_a_tick_over_it(tmp_path, monkeypatch, capsys):
    """Issue 23 item 8: `navscenario run` gives a pytest item's outcome (1 s per tick by default,
    0 = no limit); check-planner lets a slow tick finish and says pytest would stop it."""
    (tmp_path / "nu_slow_nav.py").write_text(textwrap.dedent("""
        import time
        class Planner:
            name = "slow"
            version = "1"
            def reset(self, scenario):
                pass
            def act(self, obs):
                if obs.tick == 0:
                    time.sleep(1.2)
                return (0.5, 0.0, 0.0)
    """))
    monkeypatch.syspath_prepend(str(tmp_path))
    short = tmp_path / "short.yaml"
    short.write_text("version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 0.6, y: 0}, timeout: 5}\n")
    assert cli.main(["run", str(short), "--subject", "nu_slow_nav:Planner"]) == 1
    out = capsys.readouterr().out
    assert "outcome: subject-error" in out and "per-tick limit of 1 s" in out
    assert cli.main(["check-planner", "nu_slow_nav:Planner", "--ticks", "2"]) == 0
    out = capsys.readouterr().out
    assert "over the 1 s a tick may take by default in pytest and navscenario run" in out


def test_run_takes_several_files_and_batches_them(capsys):
    files = [str(SEEDS_DIR / f"{n}.yaml") for n in ("boxes1", "corridor", "boxes2")]
    assert cli.main(["run", *files, "--seed", "0"]) == 0
    out = capsys.readouterr().out
    assert out.count("outcome: success") == 3
    assert out.rstrip().endswith("3 scenario(s): 3 passed, 0 failed; batches (--batch auto): 3 episode(s) in 1 batch(es)")
    alone = _json_run(files, "--batch", "off", capsys=capsys)
    batched = _json_run(files, capsys=capsys)
    for a, b in zip(alone, batched):
        a.pop("wall_time"), a.pop("timings"), b.pop("wall_time"), b.pop("timings")
    assert batched == alone and [r["file"] for r in batched] == files
    assert cli.main(["run", *files, "--batch", "none of it"]) == 2
    assert "--batch 'none of it': expected auto" in capsys.readouterr().err


def _json_run(files, *extra, capsys):
    assert cli.main(["run", *files, "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out)


def test_run_of_several_files_reports_every_file_that_cannot_load_and_runs_the_others(tmp_path, capsys):
    # the first broken file stopped the run before any episode, and hid the next broken one
    broken = tmp_path / "broken.yaml"
    broken.write_text("version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 5, y: 0}}\nobstacles:\n"
                      "  - {type: box, x: 2, y: 0, length: -1, width: 1}\n")
    files = [str(SEEDS_DIR / "boxes1.yaml"), str(broken), str(tmp_path / "gone.yaml"), str(SEEDS_DIR / "corridor.yaml")]
    assert cli.main(["run", *files]) == 2
    out = capsys.readouterr().out
    assert out.count("outcome: success") == 2
    assert f"broken ({broken}): error: {broken}:4: obstacles[0].length: must be > 0" in out
    assert f"gone ({tmp_path / 'gone.yaml'}): error: {tmp_path / 'gone.yaml'}: no such scenario file" in out
    assert "4 scenario(s): 2 passed, 0 failed, 2 error(s); batches (--batch auto): 2 episode(s) in 1 batch(es)" in out
    assert cli.main(["run", *files, "--json"]) == 2
    records = json.loads(capsys.readouterr().out)
    assert [r["file"] for r in records] == files
    assert records[1]["error"].startswith(f"ScenarioError: {broken}:4: obstacles[0].length")
    assert records[0]["outcome"] == records[3]["outcome"] == "success"
