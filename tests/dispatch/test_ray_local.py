"""--nav-ray on a real local Ray instance (one per module, shared by its tests): the suite's
items report in the usual order with the results, and artifacts, of a serial run."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

ray = pytest.importorskip("ray")

# Imported here, before pytester's in-process runs snapshot sys.modules (numpy cannot load twice).
import pytest_navscenario.dispatch.on_ray  # noqa: E402,F401
import pytest_navscenario.harness.runner  # noqa: E402,F401
from ray_fixtures import item_lines, planners_on_worker_path, restore_pythonpath, write_suite  # noqa: E402


@pytest.fixture(scope="module")
def planners(tmp_path_factory: pytest.TempPathFactory):
    folder = tmp_path_factory.mktemp("ray-planners")
    old = planners_on_worker_path(folder)
    (folder / "victim.pid").write_text("0")   # no kill in this module: the victim does not sleep
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        yield folder
    finally:
        ray.shutdown()
        restore_pythonpath(old)


def records(path: Path) -> list[dict]:
    return [{k: v for k, v in json.loads(line).items() if k != "wall_time"}
            for line in path.read_text().splitlines()]


def test_suite_on_ray_reports_like_a_serial_run(pytester: pytest.Pytester, planners: Path, monkeypatch):
    monkeypatch.syspath_prepend(str(planners))   # the serial run loads the subject here
    write_suite(pytester.path / "suite", short_timeout="1.0")
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
