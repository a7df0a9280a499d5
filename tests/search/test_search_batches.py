"""A search's simulations in batches (--nav-batch, search/batched.py): the generations in flight and
the failures' shrinks run in lockstep, one planner call a tick, and the search is the serial one,
bit for bit (issue 27)."""
from __future__ import annotations

import re

import pytest

from straight_planner import Straight, StraightBatch
from test_search_loop import OPEN_YAML, _fingerprint
from test_search_parallel import assert_same_search_output, project  # noqa: F401  (a fixture)
import pytest_navscenario.dispatch.local  # noqa: F401  (before pytester's in-process runs)
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.search.batched import batch_evaluator
from pytest_navscenario.search.engine import run_search


@pytest.fixture
def lane():
    return loads_scenario(OPEN_YAML, "lane.yaml", name="lane")


def fingerprint(report):
    return _fingerprint(report) + ([(c.message, repr(sorted(c.metrics.items())), c.scenario_hash)   # NaN-proof
                                    for c in report.candidates],
                                   [(f.shrink_sims, f.note, f.shrunk.sim) for f in report.failures])


@pytest.mark.parametrize("strategy", ["evolve", "hillclimb", "random"])
def test_a_batched_search_is_the_serial_search(lane, strategy):
    kw = dict(budget=16, seed_value=5, strategy=strategy, shrink_budget="50%")
    serial = run_search(lane, StraightBatch, **kw)
    StraightBatch.calls.clear()
    batched = run_search(lane, StraightBatch, batch=16, evaluator=batch_evaluator(), **kw)
    assert fingerprint(batched) == fingerprint(serial)
    assert serial.failures and sum(f.shrink_sims for f in serial.failures) > 0
    assert max(StraightBatch.calls) > 1                    # episodes did share planner calls
    assert re.fullmatch(r"\d+ episode\(s\) in \d+ batch\(es\)", batched.batching), batched.batching


def test_the_failures_shrink_side_by_side(lane):
    """Several failures: their shrinks' simulations go in the same batches (one per round)."""
    kw = dict(budget=24, seed_value=2, shrink_budget="100%")
    serial = run_search(lane, StraightBatch, **kw)
    assert len([f for f in serial.failures if f.shrink_sims]) >= 2
    StraightBatch.calls.clear()
    evaluator = batch_evaluator()
    batched = run_search(lane, StraightBatch, batch=16, evaluator=evaluator, **kw)
    assert fingerprint(batched) == fingerprint(serial)
    assert evaluator.batching.batches < batched.sims_used + batched.shrink_sims


def test_a_subject_without_the_batch_protocol_searches_alone(lane):
    kw = dict(budget=10, seed_value=1, shrink_budget="50%")
    evaluator = batch_evaluator()
    batched = run_search(lane, Straight, batch=16, evaluator=evaluator, **kw)
    assert fingerprint(batched) == fingerprint(run_search(lane, Straight, **kw))
    assert batched.batching == "" and evaluator.batching.batched == 0     # no summary line: nothing batched
    assert "does not implement the batch protocol" in evaluator.batching.describe()


def test_stopping_while_shrinking_keeps_the_failures(lane):
    """stop() while the shrinks run side by side: the search ends, its failures kept as found."""
    state = {}

    def stop():
        return state.get("report") is not None and state["report"].shrink_sims + state.get("asked", 0) > 0

    def progress(report):
        state["report"] = report
        if report.sims_used >= report.budget and report.failures:
            state["asked"] = 1
    report = run_search(lane, StraightBatch, budget=16, seed_value=5, shrink_budget="50%", batch=16,
                        evaluator=batch_evaluator(), stop=stop, progress=progress)
    assert report.interrupted and report.failures
    assert all(f.shrink_sims == 0 for f in report.failures)


def test_the_search_plugin_batches_and_writes_what_an_unbatched_run_writes(project):
    args = ["-p", "no:cacheprovider", "--nav-subject=straight_planner:StraightBatch", "--navsearch", "crate",
            "--budget", "24", "--navsearch-seed", "5"]
    project.makepyfile(straight_planner=open(__file__.replace("test_search_batches.py", "straight_planner.py")).read())
    alone = project.runpytest(*args, "--nav-batch", "off", "--navsearch-out", "alone")
    batched = project.runpytest(*args, "--navsearch-out", "batched")
    assert alone.ret == batched.ret == 0, batched.stdout.str()
    assert_same_search_output(project.path / "alone", project.path / "batched")
    workers = project.runpytest(*args, "-n", "2", "--navsearch-out", "workers")   # each worker's share a batch
    assert workers.ret == 0, workers.stdout.str()
    assert re.search(r"batches \(--nav-batch\): \d+ episode\(s\) in \d+ batch\(es\)", workers.stdout.str())
    assert_same_search_output(project.path / "alone", project.path / "workers")
    assert re.search(r"batches \(--nav-batch\): \d+ episode\(s\) in \d+ batch\(es\)", batched.stdout.str())
    assert "batches (--nav-batch)" not in alone.stdout.str()
    bad = project.runpytest(*args, "--nav-batch", "some")
    assert bad.ret == pytest.ExitCode.USAGE_ERROR
    assert "--nav-batch: expected auto, a whole number of episodes per batch from 1 to 100000, or off" \
        in bad.stderr.str()
    huge = project.runpytest(*args, "--nav-batch=1000000000")      # said its upper bound only as ">= 1"
    assert huge.ret == pytest.ExitCode.USAGE_ERROR and "from 1 to 100000" in huge.stderr.str()
