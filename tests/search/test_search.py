"""The failure search as a library: search space, validity, budget, determinism, shrinking.

Real MuJoCo episodes throughout. The subject is a tiny straight-line driver that ignores
obstacles, so a seed with a crate beside the line has failures a small shift away.
"""
from __future__ import annotations


import pytest
from hypothesis import given, settings

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.search.engine import run_search
from pytest_navscenario.search.space import SearchSpace, invalid_reason, scenarios_around
from straight_planner import Straight

SEED_YAML = """\
version: 1
name: crate
mission:
  start: {x: 0.0, y: 0.0, yaw: 90.0}
  goal: {x: 0.0, y: 5.0, yaw: 90.0}
  timeout: 12.0
obstacles:
  - {type: box, name: crate, x: 1.2, y: 2.5, length: 0.6, width: 0.6}
  - {type: box, name: far, x: 3.5, y: 2.5, length: 0.6, width: 0.6}
search:
  obstacle_dx: [-1.5, 0.5]
  obstacle_dy: 0.5
  obstacle_size: 0
  obstacle_yaw: 0
  insert: 0          # this seed's space is moves only (insertion has its own tests)
"""


@pytest.fixture(scope="module")
def seed():
    return loads_scenario(SEED_YAML, "crate.yaml", name="crate")


@pytest.fixture(scope="module")
def found(seed):
    """One evolve search, shared by the tests that only read its report."""
    return run_search(seed, Straight, budget=8, seed_value=3, shrink_budget=15)


# -- search space ---------------------------------------------------------------------------------
def test_space_is_offsets_from_the_seed(seed):
    space = SearchSpace(seed)
    assert [p.name for p in space.params] == [
        "obstacles.crate.dx", "obstacles.crate.dy", "obstacles.far.dx", "obstacles.far.dy"]
    assert space.apply(space.zero()) == seed
    moved = space.apply((-1.0, 0.25, 0.0, 0.0))
    assert (moved.obstacle("crate").x, moved.obstacle("crate").y) == (0.2, 2.75)
    assert moved.obstacle("far") == seed.obstacle("far")


def test_frozen_parts_and_waypoint_offsets(seed):
    space = SearchSpace(seed, {"frozen": ["far"], "goal_dx": 0.3})
    assert [p.name for p in space.params] == ["obstacles.crate.dx", "obstacles.crate.dy", "mission.goal.dx"]
    assert space.apply((0.0, 0.0, 0.3)).mission.goal.x == 0.3


@pytest.mark.parametrize("search, message", [
    ({"obstacle_yw": 5}, "did you mean 'obstacle_yaw'"),
    ({"obstacle_dx": [0.5, -0.5]}, "inverted bounds"),
    ({"obstacle_dx": [0.2, 0.2]}, "empty bounds"),
    ({"obstacle_dx": [0.1, 0.5]}, "do not contain 0"),
    ({"frozen": ["crat"]}, "did you mean 'crate'"),
])
def test_bad_search_settings_name_file_and_field(seed, search, message):
    with pytest.raises(ScenarioError) as err:
        SearchSpace(seed, search)
    text = str(err.value)
    assert message in text and "crate.yaml" in text and "search." in text


@settings(max_examples=30, deadline=None)
@given(scenarios_around(loads_scenario(SEED_YAML, "crate.yaml", name="crate")))
def test_public_strategy_stays_within_bounds(scenario):
    crate = scenario.obstacle("crate")
    assert -0.3 - 1e-9 <= crate.x <= 1.7 + 1e-9 and 2.0 - 1e-9 <= crate.y <= 3.0 + 1e-9
    assert scenario.mission == loads_scenario(SEED_YAML, "crate.yaml", name="crate").mission


def test_validity_rejects_blocked_start_and_closed_way(seed):
    space = SearchSpace(seed)
    assert invalid_reason(seed) is None
    blocked = seed.__class__(**{**seed.__dict__, "obstacles": (
        seed.obstacles[0].__class__(name="onstart", x=0.0, y=0.1, length=0.4, width=0.4),)})
    assert invalid_reason(blocked) == "start-blocked:onstart"
    box = seed.obstacles[0].__class__
    pen = (box(name="s", x=0.0, y=3.8, length=3.4, width=0.2), box(name="n", x=0.0, y=6.2, length=3.4, width=0.2),
           box(name="w", x=-1.6, y=5.0, length=0.2, width=2.6), box(name="e", x=1.6, y=5.0, length=0.2, width=2.6))
    walled_in = seed.__class__(**{**seed.__dict__, "obstacles": pen})   # the goal is in a closed pen
    assert invalid_reason(walled_in) == "no-path"
    assert space.apply(space.zero()) == seed


# -- the search -----------------------------------------------------------------------------------
def test_finds_a_failure_within_a_few_simulations_and_budget_is_exact(found):
    search = [c for c in found.candidates if c.phase == "search"]
    assert found.sims_used == len(search) == 8
    assert [c.sim for c in search] == list(range(1, 9))
    # generation 1: seven uniform layouts, the likeliest to fail first, then the seed itself
    assert [c.origin for c in search] == ["explore"] * 7 + ["seed"] and search[7].outcome == "success"
    assert found.first_failure == 1, "the crate is 0.65 m from the line: the tightest draw breaks Straight"
    assert found.failures, "the crate is 0.65 m from the line; a shift of -0.65 m breaks Straight"
    assert all(f.found.outcome in ("collision", "safety-stop") and f.found.culprit == "crate"
               for f in found.failures)
    assert found.best_clearance < search[7].clearance
    assert found.shrink_sims == sum(f.shrink_sims for f in found.failures) > 0
    assert found.subject == "straight" and found.subject_version == "1.0"


def test_shrinking_moves_toward_the_seed_and_still_fails(seed, found):
    from pytest_navscenario.harness.runner import run_scenario

    space = SearchSpace(seed)
    for f in found.failures:
        before = (sum(1 for v in f.found.offsets if v), sum(abs(v) for v in f.found.offsets))
        after = (sum(1 for v in f.shrunk.offsets if v), sum(abs(v) for v in f.shrunk.offsets))
        assert after <= before
        assert run_scenario(space.apply(f.shrunk.offsets), Straight()).outcome.value == f.found.outcome
    assert any(sum(1 for v in f.shrunk.offsets if v) < sum(1 for v in f.found.offsets if v)
               for f in found.failures), "the far box and the crate's dy are irrelevant: shrinking drops them"


def test_same_seed_value_same_search(seed, found):
    again = run_search(seed, Straight, budget=8, seed_value=3, shrink_budget=15)
    assert [(c.offsets, c.outcome, c.clearance) for c in again.candidates] == \
        [(c.offsets, c.outcome, c.clearance) for c in found.candidates]


def test_invalid_candidates_are_discarded_without_spending_budget(seed):
    # the crate may land on the start footprint: such candidates are not simulated
    space = SearchSpace(seed, {"obstacle_dy": [-2.6, 0.0], "frozen": ["far"]})
    report = run_search(seed, Straight, budget=6, seed_value=1, strategy="random", shrink_budget=0, space=space)
    assert report.sims_used == len(report.candidates) == 6
    assert report.discarded.get("start-blocked", 0) > 0
    for c in report.candidates:
        assert invalid_reason(space.apply(c.offsets)) is None


def test_stop_keeps_the_failures_found_so_far(seed):
    calls = []

    def stop():
        calls.append(1)
        return len(calls) > 5

    report = run_search(seed, Straight, budget=50, seed_value=3, shrink_budget=10, stop=stop)
    assert report.interrupted and report.sims_used < 50
    failing = [c for c in report.candidates if c.failed]
    assert len(report.failures) >= 1 if failing else True
    assert all(f.shrunk is f.found for f in report.failures)


def test_bad_arguments(seed):
    with pytest.raises(ValueError, match="budget"):
        run_search(seed, Straight, budget=0)
    with pytest.raises(ValueError, match="evolve, random"):
        run_search(seed, Straight, budget=1, strategy="annealing")


def test_frozen_files_round_trip_and_are_not_duplicated(seed, found, tmp_path):
    from pytest_navscenario.search.freeze import freeze_failures, read_search_log, write_search_log
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.scenario.model import content_hash

    space = SearchSpace(seed)
    first = freeze_failures(found, space, tmp_path, subject="straight")
    assert first and all(f.new for f in first)
    for f, failure in zip(first, found.failures):
        frozen = load_scenario(f.path)
        assert f.path.name == f"crate-{content_hash(frozen)}.yaml"
        assert content_hash(frozen) == content_hash(space.apply(failure.shrunk.offsets))  # exactly what ran
        assert frozen.provenance["outcome"] == failure.shrunk.outcome and frozen.search is None
    second = freeze_failures(found, space, tmp_path, subject="straight")
    assert [f.path for f in second] == [f.path for f in first] and not any(f.new for f in second)
    assert len(list((tmp_path / "crate").glob("*.yaml"))) == len(first)
    log = write_search_log(found, space, tmp_path)
    write_search_log(found, space, tmp_path)        # a second search into the same folder: appended
    searches = list(read_search_log(log).values())
    assert len(searches) == 2 and searches[0][0]["search"] != searches[1][0]["search"]
    for records in searches:
        assert [r["record"] for r in records] == ["start"] + ["candidate"] * (found.sims_used + found.shrink_sims) + ["end"]
        assert (records[-1]["search_sims"], records[-1]["shrink_sims"]) == (found.sims_used, found.shrink_sims)


def test_empty_space_is_refused(seed):
    space = SearchSpace(seed, {"frozen": ["crate", "far"]})
    with pytest.raises(ValueError, match="empty"):
        run_search(seed, Straight, budget=3, space=space)


def test_a_search_config_is_the_same_search_as_its_keywords(seed):
    from pytest_navscenario.search.engine import SearchConfig

    by_keywords = run_search(seed, Straight, budget=6, seed_value=2, strategy="random", shrink_budget=0)
    by_config = run_search(seed, Straight, SearchConfig(budget=6, seed_value=2, strategy="random", shrink_budget=0))
    assert [c.offsets for c in by_config.candidates] == [c.offsets for c in by_keywords.candidates]
    assert [c.outcome for c in by_config.candidates] == [c.outcome for c in by_keywords.candidates]
    with pytest.raises(TypeError, match="budgett"):
        run_search(seed, Straight, budgett=6)


def test_a_margin_source_joins_the_fitness_and_names_what_came_closest(seed, monkeypatch):
    """The seam STL requirements plug into (fitness.MARGIN_SOURCES): a source's margins join the
    robustness of a successful episode, and the smallest is named."""
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.search import fitness

    res = run_scenario(seed, Straight())
    assert res.outcome.value == "success"
    route = fitness.Route(seed)
    plain, _ = fitness.read_episode(res, route)
    assert plain.closest_margin in plain.margins and "requirement:slow" not in plain.margins
    monkeypatch.setattr(fitness, "MARGIN_SOURCES", [*fitness.MARGIN_SOURCES,
                                                     lambda res, pose, route: {"requirement:slow": 0.01}])
    joined, _ = fitness.read_episode(res, route)
    assert joined.closest_margin == "requirement:slow" and joined.margins["requirement:slow"] == 0.01
    assert joined.robustness < plain.robustness
