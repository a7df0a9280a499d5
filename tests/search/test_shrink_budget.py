"""The shrink phase's own budget (issue 13): a share of the search budget, shared out before
shrinking starts, most severe and earliest failure first; each failure's shrinking an
independent job with a fixed cap. Real MuJoCo episodes where a search runs."""
from __future__ import annotations

import math

import pytest

from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.search.engine import (
    Candidate, EvalContext, Failure, SearchReport, ShrinkBudget, Simulator, run_search, shrink_failure,
    shrink_order, shrink_plan)
from pytest_navscenario.search.space import SearchSpace
from straight_planner import Straight
from test_search_loop import OPEN_YAML as LANE   # the open lane with one crate, insertion and removal


@pytest.fixture(scope="module")
def lane():
    return loads_scenario(LANE, "lane.yaml", name="lane")


def _failure(sim: int, outcome: str, robustness: float, offsets=(0.5, 0.0)) -> Failure:
    c = Candidate(sim, "search", "test", tuple(offsets), outcome, 0.1, "crate", "", {}, f"h{sim}", 0.0,
                  robustness=robustness, signature=(outcome, "crate", 0, sim))
    return Failure(found=c, shrunk=c)


# -- parsing the option's values --------------------------------------------------------------
@pytest.mark.parametrize("value, share, per_failure", [
    ("25%", 0.25, None), (" 10 % ".replace(" ", ""), 0.10, None), ("0", 0.0, None), (0, 0.0, None),
    ("40", None, 40), (40, None, 40), ("150%", 1.5, None)])
def test_shrink_budget_values(value, share, per_failure):
    b = ShrinkBudget.parse(value)
    assert (b.share, b.per_failure) == (share, per_failure)


@pytest.mark.parametrize("value", ["lots", "-5", "25 percent", "-1%", "2.5", "nan%"])
def test_a_bad_shrink_budget_says_what_is_accepted(value):
    with pytest.raises(ValueError) as err:
        ShrinkBudget.parse(value)
    text = str(err.value)
    assert repr(value) in text and "25%" in text and "per failure" in text


def test_the_total_is_a_share_of_the_search_budget_not_a_count_per_failure():
    assert ShrinkBudget.parse("25%").total(1000, 12) == ShrinkBudget.parse("25%").total(1000, 3) == 250
    assert ShrinkBudget.parse("40").total(1000, 12) == 480       # the old form: per failure
    assert ShrinkBudget.parse("0").total(1000, 12) == 0


# -- sharing it out ---------------------------------------------------------------------------
def test_the_most_severe_and_earliest_failures_come_first():
    failures = [_failure(1, "timeout", -0.9), _failure(2, "collision", -0.5), _failure(3, "safety-stop", -0.8),
                _failure(4, "collision", -0.9), _failure(5, "timeout", -0.9)]
    # collisions first (the one that failed earlier along the route first), then the safety stop,
    # then the timeouts, the one found first before the later one
    assert shrink_order(failures) == [3, 1, 2, 0, 4]


def test_the_plan_gives_equal_shares_to_as_many_failures_as_it_can_afford():
    failures = [_failure(1, "timeout", -0.9), _failure(2, "collision", -0.5), _failure(3, "safety-stop", -0.8),
                _failure(4, "timeout", -0.7)]
    assert shrink_plan(failures, 25) == [0, 13, 12, 0]            # two get >= MIN_SHRINK_SIMS, in order
    assert shrink_plan(failures, 100) == [25, 25, 25, 25]
    assert shrink_plan(failures, 5) == [0, 5, 0, 0]               # too little for one: all to the first
    assert shrink_plan(failures, 0) == [0, 0, 0, 0]
    assert shrink_plan(failures, 10, ShrinkBudget.parse("7")) == [7, 7, 7, 7]   # the old form
    seedlike = [_failure(1, "collision", -0.9, offsets=(0.0, 0.0)), _failure(2, "timeout", -0.9)]
    assert shrink_plan(seedlike, 30) == [0, 30]                   # nothing to shrink in the seed itself


# -- in a search ------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def searched(lane):
    return run_search(lane, Straight, budget=24, seed_value=2, strategy="random", shrink_budget="50%")


def test_a_search_spends_at_most_its_share_on_shrinking_and_says_so(searched):
    r = searched
    assert len(r.failures) >= 2, "the lane's random layouts must fail in several ways for this test"
    assert r.shrink_total == 12 and 0 < r.shrink_sims <= 12
    assert r.shrink_sims == sum(f.shrink_sims for f in r.failures)
    assert sum(c.phase == "shrink" for c in r.candidates) == r.shrink_sims
    assert sum(c.phase == "search" for c in r.candidates) == r.sims_used == 24
    first = shrink_order(r.failures)[0]
    assert r.failures[first].shrink_sims > 0                      # the one that matters most was shrunk
    for f in r.failures:
        if f.shrink_sims == 0 and any(f.found.offsets):
            assert "not shrunk: the shrink budget (12 simulations, 50% of the budget of 24)" in f.note


def test_each_failure_shrinks_alone_with_its_cap_in_any_order(lane, searched):
    """What parallel shrinking relies on: a failure's shrink is a pure function of the failure
    and its cap, so shrinking them in reverse order, each on its own, gives the same results."""
    r = searched
    space = SearchSpace(lane)
    caps = shrink_plan(r.failures, r.shrink_total)
    ctx = EvalContext(space, Straight, r.episode_seed)
    for i in reversed(range(len(r.failures))):
        if caps[i] == 0:
            continue
        scratch = SearchReport("lane", None, "?", None, "random", 0, 24, 0, [p.name for p in space.params])
        alone = shrink_failure(space, Simulator(ctx, scratch, None), r.failures[i].found, caps[i])
        assert alone.shrunk.offsets == r.failures[i].shrunk.offsets
        assert alone.shrink_sims == r.failures[i].shrink_sims


def test_shrink_budget_zero_keeps_every_failure_as_found(lane):
    r = run_search(lane, Straight, budget=10, seed_value=2, strategy="random", shrink_budget=0)
    assert r.shrink_sims == r.shrink_total == 0
    assert all(f.shrunk is f.found for f in r.failures)


def test_report_bests_follow_the_candidates_as_they_come(searched):
    r = searched
    search = [c for c in r.candidates if c.phase == "search"]
    assert r.best_clearance == min(c.clearance for c in search if math.isfinite(c.clearance))
    assert r.best is min(search, key=lambda c: c.fitness)
    extra = Candidate(99, "search", "test", search[0].offsets, "success", -1.0, "", "", {}, "x", 0.0,
                      robustness=0.5)
    r.candidates.append(extra)
    try:
        assert r.best_clearance == -1.0                           # a new candidate is seen
    finally:
        r.candidates.pop()
