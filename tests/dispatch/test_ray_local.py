"""--nav-ray on a real local Ray instance (one per module, shared by its tests): the suite's
items report in the usual order with the results, and artifacts, of a serial run."""
from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ray_fixtures import RAY_MISSING

ray = pytest.importorskip("ray", reason=RAY_MISSING)

# Imported here, before pytester's in-process runs snapshot sys.modules (numpy cannot load twice).
import pytest_navscenario.dispatch.on_ray  # noqa: E402,F401
import pytest_navscenario.harness.runner  # noqa: E402,F401
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "search"))   # test_search, test_search_parallel
from ray_fixtures import item_lines, planners_on_worker_path, restore_pythonpath, write_suite  # noqa: E402


SEARCH_DIR = Path(__file__).resolve().parents[1] / "search"


@pytest.fixture(scope="module")
def planners(tmp_path_factory: pytest.TempPathFactory):
    folder = tmp_path_factory.mktemp("ray-planners")
    old = planners_on_worker_path(folder)
    (folder / "straight_planner.py").write_text((SEARCH_DIR / "straight_planner.py").read_text() + SLOW)
    (folder / "victim.pid").write_text("0")   # no kill in this module: the victim does not sleep
    # a test instance that another pytest process on this machine may join without a token
    old_auth = os.environ.get("RAY_AUTH_MODE")
    os.environ["RAY_AUTH_MODE"] = "disabled"
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        yield folder
    finally:
        ray.shutdown()
        restore_pythonpath(old)
        if old_auth is None:
            os.environ.pop("RAY_AUTH_MODE", None)
        else:
            os.environ["RAY_AUTH_MODE"] = old_auth


SLOW = '''

class SlowStraight(Straight):
    """5 ms per tick: a search long enough to interrupt."""
    def act(self, obs):
        import time
        time.sleep(0.005)
        return super().act(obs)


class SlowerStraight(Straight):
    """50 ms per tick: an episode of about a second (a suite long enough to interrupt)."""
    def act(self, obs):
        import time
        time.sleep(0.05)
        return super().act(obs)
'''


def search_project(pytester: pytest.Pytester) -> None:
    from test_search import SEED_YAML
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "crate.yaml").write_text(SEED_YAML.replace("name: crate\n", ""))
    pytester.makeini("[pytest]\nnav_scenario_paths = scenarios\n")


def records(path: Path) -> list[dict]:
    return [{k: v for k, v in json.loads(line).items() if k != "wall_time"}
            for line in path.read_text().splitlines()]


def test_suite_on_ray_reports_like_a_serial_run(pytester: pytest.Pytester, planners: Path, monkeypatch):
    monkeypatch.syspath_prepend(str(planners))   # the serial run loads the subject here
    write_suite(pytester.path / "suite", short_timeout="1.6")
    common = ["suite", "-v", "-p", "no:cacheprovider", "--nav-subject=killable:Planner", "--nav-plots=none"]
    serial = pytester.runpytest(*common, "--nav-results=s.jsonl", "--nav-artifacts=art-s")
    on_ray = pytester.runpytest(*common, "--nav-ray=auto", "--nav-results=r.jsonl", "--nav-artifacts=art-r")
    serial.assert_outcomes(passed=5, failed=1)
    on_ray.assert_outcomes(passed=5, failed=1)
    assert "episodes run as Ray tasks on a local Ray instance" in on_ray.stdout.str()
    assert item_lines(on_ray.outlines) == item_lines(serial.outlines)
    assert records(pytester.path / "r.jsonl") == records(pytester.path / "s.jsonl")
    # the failing item's artifacts (scenario as run, trajectory CSV) came back from the worker
    files_s = sorted(p.relative_to(pytester.path / "art-s") for p in (pytester.path / "art-s").rglob("*") if p.is_file())
    files_r = sorted(p.relative_to(pytester.path / "art-r") for p in (pytester.path / "art-r").rglob("*") if p.is_file())
    assert files_s and files_r == files_s
    for rel in files_s:
        a, b = (pytester.path / "art-r" / rel).read_bytes(), (pytester.path / "art-s" / rel).read_bytes()
        if rel.suffix == ".json":   # the record: its wall time is measured, the rest must match
            a, b = ({k: v for k, v in json.loads(x).items() if k != "wall_time"} for x in (a, b))
        assert a == b, rel


def test_an_unreachable_cluster_is_a_usage_error_before_any_episode(pytester: pytest.Pytester, planners: Path):
    write_suite(pytester.path / "suite")
    result = pytester.runpytest_subprocess("suite", "-p", "no:cacheprovider", "--nav-ray=127.0.0.1:1")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    err = result.stderr.str()
    assert "no Ray cluster answers at 127.0.0.1:1" in err and "ray start --head --port=1" in err
    assert "passed" not in result.stdout.str() and "failed" not in result.stdout.str()   # nothing ran


def test_a_search_on_ray_writes_what_a_serial_run_writes(pytester: pytest.Pytester, planners: Path, monkeypatch):
    from test_search_parallel import assert_same_search_output
    monkeypatch.syspath_prepend(str(planners))
    search_project(pytester)
    args = ["-p", "no:cacheprovider", "--nav-subject=straight_planner:Straight", "--navsearch", "crate",
            "--budget", "30", "--navsearch-seed", "5"]
    serial = pytester.runpytest(*args, "--navsearch-out", "serial")
    on_ray = pytester.runpytest(*args, "--nav-ray=auto", "--navsearch-out", "ray")
    assert serial.ret == on_ray.ret == 0, on_ray.stdout.str()
    assert_same_search_output(pytester.path / "serial", pytester.path / "ray")


def test_interrupting_a_search_on_ray_keeps_what_it_found(pytester: pytest.Pytester, planners: Path):
    search_project(pytester)
    address = ray.get_runtime_context().gcs_address     # the module's instance, joined by a new pytest
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(planners), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", f"--nav-ray={address}",
         "--nav-subject=straight_planner:SlowStraight", "--navsearch", "crate", "--budget", "300"],
        cwd=pytester.path, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert proc.stdout is not None
    seen, deadline = "", time.monotonic() + 120
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        seen += line
        if re.search(r"navsearch crate: \d+/300 sims, [1-9]\d* distinct failure", line) or not line:
            break
    proc.send_signal(signal.SIGTERM)
    out = seen + proc.communicate(timeout=120)[0]
    assert proc.returncode == pytest.ExitCode.INTERRUPTED, out[-3000:]
    assert "CUT SHORT: interrupted" in out
    sims = int(re.search(r"\): (\d+)/300 sims", out).group(1))
    folder = pytester.path / "scenarios" / "regressions" / "crate"
    log = [r for r in map(json.loads, (folder / "search-log.jsonl").read_text().splitlines())
           if r["record"] == "candidate"]
    assert 0 < sims < 300 and len([r for r in log if r["phase"] == "search"]) == sims
    assert sorted(folder.glob("crate-*.yaml")), out[-3000:]


# Heavy (~5 s quiet): a suite interrupted on the plugin's own workers keeps its finished items in the
# default run (tests/plugin/test_interrupt.py), and an interrupt on Ray in the search below.
@pytest.mark.heavy
def test_interrupting_a_suite_on_ray_keeps_the_finished_items(pytester: pytest.Pytester, planners: Path):
    from dispatch_helpers import scenario_text
    suite = pytester.path / "suite"
    suite.mkdir()
    for i in range(16):
        (suite / f"s{i:02d}.yaml").write_text(scenario_text(f"s{i:02d}", 1.0 + i / 100))
    address = ray.get_runtime_context().gcs_address
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(planners), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-v", f"--nav-ray={address}", "suite",
         "--nav-subject=straight_planner:SlowerStraight", "--nav-results=out/r.jsonl", "--nav-plots=none"],
        cwd=pytester.path, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert proc.stdout is not None
    seen, passed, deadline = "", 0, time.monotonic() + 120
    while passed < 3 and time.monotonic() < deadline:
        line = proc.stdout.readline()
        seen += line
        passed += " PASSED" in line
        if not line:
            break
    proc.send_signal(signal.SIGTERM)
    out = seen + proc.communicate(timeout=120)[0]
    assert proc.returncode == pytest.ExitCode.INTERRUPTED, out[-3000:]
    from pytest_navscenario.report.results_file import read_results
    records = read_results(pytester.path / "out" / "r.jsonl")
    assert 3 <= len(records) < 16, out[-3000:]
    assert len({r["nodeid"] for r in records}) == len(records)
    assert all(r["outcome"] == "success" for r in records)


def test_a_planner_that_quits_is_a_subject_error_on_ray_too(pytester: pytest.Pytester, planners: Path, monkeypatch):
    """A planner's own KeyboardInterrupt or sys.exit() on a Ray worker ends only its episode, as a
    subject error, exactly as in a serial run (Ray would otherwise take it for a cancelled task)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "plugin"))
    from test_planner_exit import NAMES, PLANNER, SCENARIO
    (planners / "quitter.py").write_text(PLANNER)
    monkeypatch.syspath_prepend(str(planners))
    (pytester.path / "s").mkdir()
    for name in NAMES:
        (pytester.path / "s" / f"{name}.yaml").write_text(f"name: {name}\n" + SCENARIO)
    common = ["s", "-p", "no:cacheprovider", "--nav-subject=quitter:Quitter", "--nav-plots=none"]
    serial = pytester.runpytest(*common, "--nav-results=s.jsonl")
    on_ray = pytester.runpytest(*common, "--nav-ray=auto", "--nav-results=r.jsonl")
    serial.assert_outcomes(passed=1, failed=4)
    on_ray.assert_outcomes(passed=1, failed=4)
    outcomes = {r["nodeid"].split("::")[1]: r["outcome"] for r in records(pytester.path / "r.jsonl")}
    assert outcomes == {r["nodeid"].split("::")[1]: r["outcome"] for r in records(pytester.path / "s.jsonl")}
    assert sorted(n for n, o in outcomes.items() if o == "subject-error") == sorted(n for n in NAMES if n != "fine")
