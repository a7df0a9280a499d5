"""The pytest plugin, end to end: real pytest runs (plugin autoload disabled, loaded with -p),
real YAML files, real MuJoCo episodes. One serial run of a small project (one scenario per outcome,
a non-scenario YAML and an invalid scenario) is shared by several tests; xdist runs must give the
same results file."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.report.results_file import read_results
from pytest_navscenario.harness.runner import effective_seed
from pytest_navscenario.scenario.model import content_hash

# Trajectory plots of failing items (the report plugin, tested there) are off: they dominate the time.
PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none"]

PLANNER = '''
import math


class Straight:
    """Drives straight at the target at full speed; raises at tick 2 if the description says so."""
    name = "straight"
    version = "2.1"

    def reset(self, scenario):
        self.boom = scenario.description == "raise"
        self.speed = scenario.robot.limits.max_speed

    def act(self, obs):
        if self.boom and obs.tick == 2:
            raise ValueError("planner boom")
        x, y, yaw = obs.pose
        tx, ty = obs.target
        dx, dy = tx - x, ty - y
        d = math.hypot(dx, dy) or 1.0
        c, s = math.cos(yaw), math.sin(yaw)
        v = min(self.speed, d)
        return (c * dx + s * dy) / d * v, (-s * dx + c * dy) / d * v, 0.0


class NotAPlanner:
    def reset(self, scenario):
        pass
'''

WALL = "obstacles: [{type: box, name: wall, x: 2, y: 0, length: 0.4, width: 2}]\n"


def scenario(goal_x: float, timeout: float = 10.0, extra: str = "") -> str:
    return (f"version: 1\nmission: {{start: {{x: 0, y: 0}}, goal: {{x: {goal_x}, y: 0}}, "
            f"timeout: {timeout}}}\n{extra}")


PROJECT = {
    "scenarios/alpha/ok.yaml": scenario(2),
    "scenarios/alpha/crash.yaml": scenario(4, extra="robot: {safety: {enabled: false}}\n" + WALL),
    "scenarios/beta/stop.yaml": scenario(4, extra=WALL),
    "scenarios/beta/slow.yaml": scenario(5, timeout=4.5),   # can be driven in 4.2 s at top speed; dwa cannot
    "scenarios/beta/boom.yaml": scenario(2, extra="description: raise\n"),
    "scenarios/notes.yaml": "version: 3\nauthor: someone\n",        # YAML, but not a scenario
    "scenarios/broken.yaml": scenario(2, extra="obstacles: [{type: box, x: 1, y: 3, length: -1, width: 1}]\n"),
}
OUTCOMES = {"ok": "success", "crash": "collision", "stop": "safety-stop", "slow": "timeout",
            "boom": "subject-error"}
SEED = 7
ARGS = ["scenarios", "--nav-subject=straight:Straight", f"--nav-seed={SEED}", "--nav-results=r.jsonl"]


def write_project(root: Path) -> None:
    (root / "straight.py").write_text(PLANNER)
    for rel, text in PROJECT.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)


def env_without_autoload(root: Path) -> dict[str, str]:
    env = dict(os.environ, PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
    env["PYTHONPATH"] = os.pathsep.join([str(root), env.get("PYTHONPATH", "")])
    return env


def strip_times(records: list[dict]) -> list[dict]:
    return [{k: v for k, v in r.items() if k != "wall_time"} for r in records]


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory):
    """One real serial pytest run of PROJECT, shared: (completed process, project folder)."""
    root = tmp_path_factory.mktemp("project")
    write_project(root)
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", *PLUGIN, *ARGS, "-v", "-p", "no:cacheprovider",
         "--junitxml=junit.xml", "-o", "junit_family=xunit1"],
        cwd=root, env=env_without_autoload(root), capture_output=True, text=True, timeout=120)
    return proc, root


def section(out: str, title: str) -> str:
    """The text of one failure section ``____ title ____`` of pytest's output."""
    start = out.index(f"_ {title}")
    ends = [e for e in (out.find(sep, start) for sep in ("\n___", "\n---", "\n===")) if e != -1]
    return out[start:min(ends)]


def test_collection_one_item_per_scenario_file_sorted_other_yaml_ignored(run):
    proc, _ = run
    items = [line.split(" ")[0] for line in proc.stdout.splitlines()
             if line.startswith("scenarios/") and "::" in line]
    assert items == ["scenarios/alpha/crash.yaml::crash", "scenarios/alpha/ok.yaml::ok",
                     "scenarios/beta/boom.yaml::boom", "scenarios/beta/slow.yaml::slow",
                     "scenarios/beta/stop.yaml::stop"]
    assert "notes.yaml" not in proc.stdout
    assert "collected 5 items / 1 error" in proc.stdout


def test_invalid_scenario_is_a_collection_error_and_every_other_item_runs(run):
    proc, _ = run
    out = proc.stdout
    assert "ERROR collecting scenarios/broken.yaml" in out
    assert "broken.yaml:3: obstacles[0].length: must be > 0, got -1.0 (fix:" in out
    assert "4 failed, 1 passed, 1 error" in out
    assert proc.returncode == 1


def test_header_names_subject_and_seed(run):
    proc, root = run
    assert f"navscenario: subject straight:Straight (--nav-subject), seed {SEED}" in proc.stdout


@pytest.mark.parametrize("name", ["crash", "stop", "slow", "boom"])
def test_failure_report_is_short_and_reproducible(run, name):
    proc, root = run
    text = section(proc.stdout, f"scenario {name} (")
    assert text.splitlines()[1].startswith(OUTCOMES[name] + ":")
    assert f"reproduce: pytest scenarios/{'alpha' if name == 'crash' else 'beta'}/{name}.yaml::{name} " \
           f"--nav-subject=straight:Straight --nav-seed={SEED}" in text
    assert "_pytest" not in text and "pluggy" not in text
    if name in ("crash", "stop"):
        assert "'wall'" in text and "min clearance:" in text
    if name == "boom":
        assert "planner traceback:" in text
        assert 'straight.py", line' in text and "ValueError: planner boom" in text


def test_results_file_has_one_record_per_episode(run):
    _, root = run
    records = read_results(root / "r.jsonl")
    assert [r["scenario"] for r in records] == ["crash", "ok", "boom", "slow", "stop"]
    for rec in records:
        source = root / rec["path"]
        scen = load_scenario(source)
        assert rec["outcome"] == OUTCOMES[rec["scenario"]]
        assert rec["passed"] == (rec["scenario"] == "ok")
        assert rec["family"] == source.parent.name
        assert rec["scenario_hash"] == content_hash(scen)
        assert rec["seed"] == effective_seed(scen.simulation.seed, SEED)
        assert (rec["subject"], rec["subject_version"]) == ("straight", "2.1")
        assert rec["nodeid"] == f"{rec['path']}::{rec['scenario']}"


def test_junit_testcases_carry_outcome_and_metrics(run):
    _, root = run
    tree = ET.parse(root / "junit.xml")
    cases = {c.get("name"): c for c in tree.iter("testcase")}
    assert set(cases) >= set(OUTCOMES)
    for name, outcome in OUTCOMES.items():
        props = {p.get("name"): p.get("value") for p in cases[name].iter("property")}
        assert props["nav_outcome"] == outcome
        assert props["nav_subject"] == "straight"
        assert float(props["nav_duration"]) > 0
    crash = {p.get("name"): p.get("value") for p in cases["crash"].iter("property")}
    assert float(crash["nav_min_clearance"]) == 0.0 and crash["nav_min_clearance_obstacle"] == "wall"


def test_artifacts_only_for_failing_items(run):
    _, root = run
    folders = sorted(p.name for p in (root / "nav-artifacts").iterdir())
    assert len(folders) == 4 and not any("ok" in f.split("-")[0] for f in folders)
    crash = next((root / "nav-artifacts").glob("scenarios_alpha_crash.yaml_crash-*"))
    as_run = load_scenario(crash / "scenario.yaml")
    assert content_hash(as_run) == content_hash(load_scenario(root / "scenarios/alpha/crash.yaml"))
    rows = (crash / "trajectory.csv").read_text().splitlines()
    assert rows[0] == "t,x,y,yaw,vx,vy,wz" and len(rows) > 100
    assert json.loads((crash / "result.json").read_text())["outcome"] == "collision"


def test_summary_table_per_family_with_wilson_intervals(run):
    proc, _ = run
    out = proc.stdout[proc.stdout.index("navscenario summary"):]
    alpha = next(line for line in out.splitlines() if line.startswith("alpha "))
    # 2 episodes: 1 success, 1 collision -> 50.0 % [9.5-90.5]
    assert alpha.split()[1] == "2" and alpha.count("50.0% [ 9.5- 90.5]") == 2
    assert any(line.startswith("all ") for line in out.splitlines())
    assert "subject-error" in out and "min clearance" in out


@pytest.mark.parametrize("dist", [["-n", "2"], ["--tx", "2*popen", "--dist", "load"]],
                         ids=["n2", "tx-popen"])
def test_xdist_gives_the_serial_results(run, pytester: pytest.Pytester, monkeypatch, dist):
    _, root = run
    write_project(pytester.path)
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(pytester.path), os.environ.get("PYTHONPATH", "")]))
    result = pytester.runpytest_subprocess(*PLUGIN, "-p", "xdist.plugin", *ARGS, *dist)
    result.assert_outcomes(passed=1, failed=4, errors=1)
    out = result.stdout.str()     # the invalid file: the same error item and message as serial
    assert "ERROR collecting scenarios/broken.yaml" in out
    assert "broken.yaml:3: obstacles[0].length: must be > 0, got -1.0 (fix:" in out
    assert strip_times(read_results(pytester.path / "r.jsonl")) == strip_times(read_results(root / "r.jsonl"))
    assert len(list((pytester.path / "nav-artifacts").iterdir())) == 4


# ---------------------------------------------------------------- small in-process runs

@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(straight=PLANNER)
    pytester.syspathinsert()
    return pytester


@pytest.mark.parametrize("spec, message", [
    ("no_such_module_xyz:Planner", "cannot import module 'no_such_module_xyz'"),
    ("straight:Nope", "has no attribute 'Nope' (it has: NotAPlanner, Straight"),
    ("straight:NotAPlanner", "has no act() method"),
    ("justaword", "is not of the form 'package.module:Attribute'"),
])
def test_bad_subject_stops_the_run_before_any_test(project, spec, message):
    (project.path / "s").mkdir()
    (project.path / "s" / "ok.yaml").write_text(scenario(2))
    result = project.runpytest(*PLUGIN, "s", f"--nav-subject={spec}")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines([f"ERROR: navscenario: subject*{message}*"])
    assert "passed" not in result.stdout.str() and "failed" not in result.stdout.str()


@pytest.mark.parametrize("option, message", [
    ("--nav-seed=abc", "--nav-seed: seed must be a whole number >= 0, got 'abc'"),
    ("--nav-summary=maybe", "--nav-summary: expected yes or no, got 'maybe'"),
    ("--nav-tick-limit=-1", "--nav-tick-limit: expected seconds >= 0 (0 or none: no limit), got '-1'"),
])
def test_bad_option_value_is_a_usage_error(project, option, message):
    result = project.runpytest(*PLUGIN, option)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert message in result.stderr.str()


def test_make_subject_hook_provides_the_subject(project):
    project.makeconftest("""
        import straight

        def pytest_navscenario_make_subject(config):
            return straight.Straight
    """)
    project.makefile(".yaml", ok=scenario(2))
    result = project.runpytest(*PLUGIN, "--nav-results=r.jsonl", "--nav-summary=no")
    result.stdout.fnmatch_lines(["navscenario: subject Straight (from the pytest_navscenario_make_subject hook)*"])
    result.assert_outcomes(passed=1)
    assert read_results(project.path / "r.jsonl")[0]["subject"] == "straight"
    assert "navscenario summary" not in result.stdout.str()


def test_marks_from_yaml_select_with_m_and_k(project):
    project.makeini("[pytest]\nmarkers =\n    slow: long scenarios\n")
    files = {
        "a_slow": scenario(2, extra="marks: [slow]\n"),
        "b_skip": scenario(2, extra="marks: [{skip: not today}]\n"),
        "c_xfail": scenario(5, timeout=0.5, extra="marks: [{xfail: {reason: known gap}}]\n"),
        "d_plain": scenario(2),
    }
    for name, text in files.items():
        project.makefile(".yaml", **{name: text})
    result = project.runpytest(*PLUGIN, "--nav-subject=straight:Straight", "-rsx", "-W", "error::pytest.PytestUnknownMarkWarning")
    result.assert_outcomes(passed=2, skipped=1, xfailed=1)
    result.stdout.fnmatch_lines(["*SKIPPED*b_skip.yaml*not today*", "*XFAIL*c_xfail*known gap*"])
    result = project.runpytest(*PLUGIN, "--collect-only", "-q", "-m", "slow")
    result.stdout.fnmatch_lines(["a_slow.yaml::a_slow", "1/4 tests collected (3 deselected)*"])
    result = project.runpytest(*PLUGIN, "--collect-only", "-q", "-k", "plain or skip")
    result.stdout.fnmatch_lines(["b_skip.yaml::b_skip", "d_plain.yaml::d_plain", "2/4 tests collected*"])


def test_nav_run_fixture_runs_modified_scenarios(project):
    (project.path / "crash.yaml").write_text(
        scenario(4, extra="robot: {safety: {enabled: false}}\n" + WALL))
    project.makepyfile(test_mine="""
        import pytest
        from pytest_navscenario import Outcome

        def test_as_written(nav_run, nav_subject):
            assert nav_subject.spec == "straight:Straight"
            assert nav_run("crash.yaml").outcome is Outcome.COLLISION

        @pytest.mark.parametrize("change", [dict(obstacles=()), dict(obstacles=lambda obs: obs[1:])])
        def test_without_the_wall(nav_run, change):
            assert nav_run("crash.yaml", **change).outcome is Outcome.SUCCESS

        def test_other_planner_and_unknown_field(nav_run):
            assert nav_run("crash.yaml", "potential-field", obstacles=()).subject != "straight"
            with pytest.raises(TypeError, match="no field.*obstacle_list"):
                nav_run("crash.yaml", obstacle_list=())
    """)
    result = project.runpytest(*PLUGIN, "--nav-subject=straight:Straight", "test_mine.py")
    result.assert_outcomes(passed=4)


def test_scenario_name_that_breaks_node_ids_is_a_collection_error(project):
    project.makefile(".yaml", weird=scenario(2, extra='name: "a::b"\n'), fine=scenario(2))
    result = project.runpytest(*PLUGIN, "--collect-only", "-q")
    result.stdout.fnmatch_lines(["fine.yaml::fine", "*weird.yaml: name: scenario name 'a::b' cannot be a "
                                 "pytest item name*(fix: use letters*"])


def test_make_subject_hook_that_raises_is_a_usage_error(project):
    project.makeconftest("""
        def pytest_navscenario_make_subject(config):
            raise RuntimeError("no licence server")
    """)
    result = project.runpytest(*PLUGIN)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert "pytest_navscenario_make_subject hook raised RuntimeError: no licence server" in result.stderr.str()


def test_hanging_planner_is_a_subject_error_and_the_next_item_runs(project):
    project.makepyfile(hang="""
        class Hang:
            def reset(self, scenario):
                self.hang = scenario.name == "a_hangs"

            def act(self, obs):
                while self.hang and obs.tick == 3:
                    pass
                return 1.0, 0.0, 0.0
    """)
    project.makefile(".yaml", a_hangs=scenario(1), b_fine=scenario(1))
    result = project.runpytest(*PLUGIN, "--nav-subject=hang:Hang", "--nav-tick-limit=0.2")
    result.stdout.fnmatch_lines(["*tick limit 0.2 s*",
                                 "subject-error:*tick 3*per-tick limit of 0.2 s*"])
    result.assert_outcomes(passed=1, failed=1)


def test_ini_twins_configure_the_run(project):
    project.makeini("[pytest]\nnav_subject = straight:Straight\nnav_seed = 3\n"
                    "nav_results = out/r.jsonl\nnav_summary = no\nnav_scenario_glob = *.scn.yaml\n")
    project.makefile(".scn.yaml", ok=scenario(1))
    project.makefile(".yaml", ignored=scenario(1))   # does not match nav_scenario_glob
    result = project.runpytest(*PLUGIN)
    result.stdout.fnmatch_lines(["navscenario: subject straight:Straight (ini nav_subject), seed 3*"])
    result.assert_outcomes(passed=1)
    [record] = read_results(project.path / "out" / "r.jsonl")   # relative to the rootdir
    assert record["nodeid"] == "ok.scn.yaml::ok.scn" and record["seed"] == effective_seed(0, 3)
    assert "navscenario summary" not in result.stdout.str()
