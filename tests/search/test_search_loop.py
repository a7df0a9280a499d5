"""The search loop of issue 13: ask/tell batches, strategies, mutations, insertion and removal,
the stuck-robot early stop, determinism. Real MuJoCo episodes throughout."""
from __future__ import annotations

import hashlib
import json
import math
import os
import random
import subprocess
import sys
from pathlib import Path

import pytest

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.search.engine import (
    Candidate, EvalContext, SearchReport, _search_loop, Simulator, evaluate_candidate, run_search,
    shrink_failure)
from pytest_navscenario.search.space import INSERT_PREFIX, SearchSpace
from pytest_navscenario.search.strategies import Evolve, HillClimb
from straight_planner import Straight

ROOT = Path(__file__).resolve().parents[2]

OPEN_YAML = """\
version: 1
name: lane
mission:
  start: {x: 0.0, y: 0.0, yaw: 90.0}
  goal: {x: 0.0, y: 6.0, yaw: 90.0}
  timeout: 15.0
obstacles:
  - {type: box, name: crate, x: 1.5, y: 3.0, length: 0.6, width: 0.6}
search:
  obstacle_dx: [-1.5, 0.5]
  obstacle_dy: 0.5
  obstacle_size: 0
  obstacle_yaw: 0
  insert: 1
  insert_size: [0.4, 0.6]
  insert_margin: 1.5
  remove: 1
"""


@pytest.fixture(scope="module")
def lane():
    return loads_scenario(OPEN_YAML, "lane.yaml", name="lane")


def _report(space, strategy="evolve", budget=10):
    return SearchReport("lane", None, "?", None, strategy, 0, budget, 0, [p.name for p in space.params])


def _values(space, **named):
    out = list(space.zero())
    for name, v in named.items():
        out[space.index[name.replace("__", ".")]] = v
    return tuple(out)


# -- insertion and removal ------------------------------------------------------------------------
def test_insertion_and_removal_are_parameters_zero_is_the_seed(lane):
    space = SearchSpace(lane)
    names = [p.name for p in space.params]
    assert names == ["obstacles.crate.dx", "obstacles.crate.dy", "obstacles.crate.removed",
                     "inserted[0].on", "inserted[0].x", "inserted[0].y", "inserted[0].size", "inserted[0].yaw"]
    assert space.apply(space.zero()) == lane
    inserted = space.apply(_values(space, **{"inserted[0]__on": 1.0, "inserted[0]__x": 0.5, "inserted[0]__size": 0.1}))
    new = inserted.obstacle(f"{INSERT_PREFIX}1")
    assert (new.x, new.y, new.length, new.width) == (0.5, 3.0, 0.5, 0.5)   # region centre (0, 3) + offset
    assert space.apply(_values(space, **{"inserted[0]__on": 0.4, "inserted[0]__x": 0.5})) == lane  # flag off
    removed = space.apply(_values(space, **{"obstacles.crate__removed": 1.0}))
    assert removed.obstacles == ()


@pytest.mark.parametrize("search, message", [
    ({"insert": -1}, "must be between 0 and 100"),       # the documented limits (search_keys.py)
    ({"insert": 1.5}, "expected a whole number"),
    ({"insert_size": [0.8, 0.2]}, "0 < lo <= hi"),
    ({"insert_size": [0.1, 0.2, 0.3]}, "exactly two numbers"),
    ({"insert_margin": -1}, "must be >= 0"),
    ({"remove": 3}, "at most that many"),
    ({"insrt": 1}, "did you mean 'insert'"),
])
def test_new_search_keys_are_validated_with_file_and_field(lane, search, message):
    with pytest.raises(ScenarioError) as err:
        SearchSpace(lane, search)
    text = str(err.value)
    assert message in text and "lane.yaml" in text and "search." in text


def test_new_search_key_errors_give_the_line(tmp_path):
    from pytest_navscenario.scenario.loader import load_scenario
    path = tmp_path / "lane.yaml"
    path.write_text(OPEN_YAML.replace("  remove: 1\n", "  remove: 7\n"))
    with pytest.raises(ScenarioError) as err:
        SearchSpace(load_scenario(path))
    assert f"{path}:{OPEN_YAML.splitlines().index('  remove: 1') + 1}" in str(err.value)


def test_shrinking_removes_an_inserted_obstacle_that_does_not_matter(lane):
    space = SearchSpace(lane)
    # the crate moved onto the line (the cause) plus an inserted box far off the line (noise)
    cause = _values(space, **{"obstacles.crate__dx": -1.4, "inserted[0]__on": 1.0, "inserted[0]__x": 1.4,
                              "inserted[0]__y": 2.5})
    ctx = EvalContext(space, Straight)
    found = evaluate_candidate(ctx, cause, "test")
    assert found.failed and found.culprit == "crate"
    sim = Simulator(ctx, _report(space), None)
    failure = shrink_failure(space, sim, found, 12)
    shrunk = space.apply(failure.shrunk.offsets)
    assert f"{INSERT_PREFIX}1" not in [o.name for o in shrunk.obstacles]
    first = sim.report.candidates[0]   # the first shrink simulation tried dropping the inserted box
    assert first.offsets[space.index["inserted[0].on"]] == 0.0
    assert failure.shrunk.signature == found.signature
    assert abs(failure.shrunk.offsets[0]) <= abs(found.offsets[0])


def test_shrinking_keeps_an_inserted_obstacle_that_causes_the_failure(lane):
    space = SearchSpace(lane)
    cause = _values(space, **{"inserted[0]__on": 1.0, "inserted[0]__y": 0.5})   # on the line at y=3.5
    ctx = EvalContext(space, Straight)
    found = evaluate_candidate(ctx, cause, "test")
    assert found.failed and found.culprit == f"{INSERT_PREFIX}1" and found.signature[1] == "inserted"
    failure = shrink_failure(space, Simulator(ctx, _report(space), None), found, 8)
    assert failure.shrunk.offsets[space.index["inserted[0].on"]] >= 0.5
    assert failure.shrunk.signature == found.signature


# -- mutations that use the episode --------------------------------------------------------------
def _parent(lane, space):
    return evaluate_candidate(EvalContext(space, Straight), space.zero(), "seed")


def test_insert_mutation_puts_a_new_box_on_the_robots_path(lane):
    import random
    space = SearchSpace(lane)
    evo = Evolve(space, _report(space), 10, 0)
    parent = _parent(lane, space)
    assert not parent.failed and len(parent.path) > 10
    for k in range(20):
        offsets = evo._insert(parent, random.Random(k))
        box = space.apply(offsets).obstacle(f"{INSERT_PREFIX}1")
        lateral = min(math.hypot(box.x - x, box.y - y) for x, y in parent.path)
        assert lateral <= 1.3 * (0.25 + box.length / 2) + 1e-6, (k, box)


def test_place_mutation_moves_an_obstacle_onto_the_path_within_its_bounds(lane):
    import random
    space = SearchSpace(lane)
    evo = Evolve(space, _report(space), 10, 0)
    parent = _parent(lane, space)
    moved_onto_path = 0
    for k in range(20):
        offsets = evo._place(parent, random.Random(k))
        assert space.clip(offsets) == offsets
        crate = space.apply(offsets).obstacle("crate")
        lateral = min(math.hypot(crate.x - x, crate.y - y) for x, y in parent.path)
        moved_onto_path += lateral <= 1.3 * (0.25 + 0.3) + 1e-6
    assert moved_onto_path == 20   # the crate can reach the line (dx down to -1.5): it always does


def test_place_mutation_finds_failures_where_uniform_sampling_rarely_does(lane):
    import random
    space = SearchSpace(lane, {"insert": 0, "remove": 0})
    evo = Evolve(space, _report(space), 10, 0)
    parent = _parent(lane, space)
    ctx = EvalContext(space, Straight, stuck_after=None)
    placed = [evaluate_candidate(ctx, evo._place(parent, random.Random(k)), "place").failed for k in range(8)]
    rnd = random.Random(0)
    uniform = [evaluate_candidate(ctx, tuple(rnd.uniform(p.lo, p.hi) for p in space.params), "u").failed
               for _ in range(8)]
    assert sum(placed) >= 5 and sum(placed) > sum(uniform)   # lateral offsets up to 1.3x contact: most hit


def _lane_quarter(y):
    return min(3, int(y / 6.0 * 4))   # the lane's route runs straight from y = 0 to y = 6


def test_squeeze_mutation_narrows_the_passage_beside_the_path_without_blocking_it(lane):
    import random
    space = SearchSpace(lane)
    evo = Evolve(space, _report(space), 10, 0)
    parent = _parent(lane, space)
    seen = set()
    for k in range(20):
        scenario = space.apply(evo._squeeze(parent, random.Random(k)))
        moved = [o for o in scenario.obstacles if o.name.startswith(INSERT_PREFIX)
                 or (o.name == "crate" and o.x != 1.5)]
        assert len(moved) == 1, (k, moved)
        box = moved[0]
        contact = 0.25 + box.length / 2    # robot half width + the box's half size, across the path
        lateral = min(abs(box.x - x) for x, y in parent.path if abs(y - box.y) < 0.3)
        assert contact - 1e-6 <= lateral <= 1.3 * contact + 1e-6, (k, box, lateral)   # beside, not on it
        seen.add(box.name)
    assert seen == {"crate", f"{INSERT_PREFIX}1"}   # moves a seed obstacle and inserts new boxes


def test_aimed_mutations_put_the_obstacle_in_the_quarter_of_the_route_they_aim_at(lane):
    import random
    space = SearchSpace(lane)
    evo = Evolve(space, _report(space), 10, 0)
    parent = _parent(lane, space)
    # the crate (y 2.5-3.5 within its bounds) can reach quarters 1 and 2 of the 6 m route only
    assert evo._arms().arms == [("crate", 1), ("crate", 2)] + [("inserted", q) for q in range(4)]
    for k in range(30):
        for op in (evo._place, evo._insert):
            scenario = space.apply(op(parent, random.Random(k)))
            name, quarter = evo.aim
            obs = scenario.obstacle("crate" if name == "crate" else f"{INSERT_PREFIX}1")
            assert _lane_quarter(obs.y) == quarter, (k, op.__name__, evo.aim, obs)


CROSSING_YAML = """\
version: 1
name: crossing
mission:
  start: {x: 0.0, y: 0.0, yaw: 90.0}
  goal: {x: 0.0, y: 8.0, yaw: 90.0}
  timeout: 20.0
obstacles:
  - type: person
    name: walker
    motion: {path: [[-2.0, 5.0], [3.0, 5.0]], speed: 1.0, start: 8.0}
search:
  obstacle_size: 0
  insert: 0
"""


def test_retime_mutation_sends_a_moving_obstacle_to_meet_the_robot():
    """A person who crosses long after the robot passed: retime picks a start time and speed (and
    shifts the path with what is left) so that the person reaches a point of the robot's recorded
    path when the robot was there, and the child episodes meet the person where uniform samples
    of the same space do not."""
    import random

    import numpy as np

    from pytest_navscenario.scenario.motion import Track
    from pytest_navscenario.search.strategies import RETIME_LAG

    seed = loads_scenario(CROSSING_YAML, "crossing.yaml", name="crossing")
    space = SearchSpace(seed)
    evo = Evolve(space, _report(space), 10, 0)
    ctx = EvalContext(space, Straight, stuck_after=None)
    parent = evaluate_candidate(ctx, space.zero(), "seed")
    assert not parent.failed and evo.moving
    n, duration = len(parent.path), parent.metrics["duration"]
    times = np.array([k / (n - 1) * duration for k in range(n)])
    robot = np.asarray(parent.path)
    contact = 0.25 + seed.obstacle("walker").radius
    met = 0
    for k in range(12):
        child = evo._retime(parent, random.Random(k))
        assert space.clip(child) == child
        track = Track(space.apply(child).obstacle("walker"))
        gap = min(float(np.hypot(*(robot - track.positions(times + lag)).T).min())
                  for lag in np.linspace(*RETIME_LAG, 31))
        assert gap <= 1.8 * contact + 1e-6, (k, gap)     # at most the jitter (0.8 x contact) off
        met += evaluate_candidate(ctx, child, "retime").culprit == "walker"
    rnd = random.Random(0)
    uniform = sum(evaluate_candidate(ctx, tuple(rnd.uniform(p.lo, p.hi) for p in space.params), "u").failed
                  for _ in range(12))
    assert met >= 8 and met > uniform + 4, (met, uniform)


def test_stall_margin_sees_a_robot_that_hesitated():
    """A success after standing still for a while ranks closer to a timeout than the same run
    without the wait: the stall margin is the longest time without progress over the spare time."""
    from pytest_navscenario.search.fitness import Route, longest_stall, read_episode, spare_time

    lane = loads_scenario(OPEN_YAML, "lane.yaml", name="lane")
    route = Route(lane)
    quick = run_scenario(lane, Straight())
    slow = run_scenario(lane, WaitThenGo())     # stands still for 4 s first
    assert quick.outcome.value == slow.outcome.value == "success"
    stall_quick = longest_stall(quick.trajectory.t, quick.trajectory.pose, route)
    stall_slow = longest_stall(slow.trajectory.t, slow.trajectory.pose, route)
    assert stall_quick < 1.0 and 4.0 <= stall_slow < 5.0, (stall_quick, stall_slow)
    a, b = read_episode(quick, route)[0], read_episode(slow, route)[0]
    assert b.margins["stall"] == pytest.approx(1 - stall_slow / spare_time(lane, route))
    assert b.robustness < a.robustness


def test_barrier_mutation_walls_off_the_path_with_two_boxes_the_robot_cannot_pass_between(lane):
    """Two inserted boxes side by side across the robot's path, the gap between them narrower than
    the robot: the straight line is blocked (a robot that does not go round hits one of them)."""
    import random
    space = SearchSpace(lane, {"insert": 2})
    evo = Evolve(space, _report(space), 10, 0)
    parent = _parent(lane, space)
    ctx = EvalContext(space, Straight, stuck_after=None)
    for k in range(10):
        scenario = space.apply(evo._barrier(parent, random.Random(k)))
        a, b = sorted((o for o in scenario.obstacles if o.name.startswith(INSERT_PREFIX)), key=lambda o: o.x)
        assert abs(a.y - b.y) < 1e-3 and a.yaw == b.yaw == 0.0, (k, a, b)   # across a path along +y
        assert b.x - b.length / 2 - (a.x + a.length / 2) < 0.5 * 0.8 + 1e-6     # gap below the robot's width
        assert a.x - a.length / 2 <= 0.0 <= b.x + b.length / 2                   # the line is covered
        if k < 4:
            cand = evaluate_candidate(ctx, evo._barrier(parent, random.Random(k)), "b")
            assert cand.failed and cand.culprit.startswith(INSERT_PREFIX), (k, cand.outcome, cand.culprit)


def _inserted(scenario):
    return sorted((o for o in scenario.obstacles if o.name.startswith(INSERT_PREFIX)), key=lambda o: o.name)


def test_shift_mutation_carries_a_failing_trap_to_a_quarter_where_inserted_boxes_have_not_failed(lane):
    """A box on the line in the lane's first quarter stops the straight driver. Shift moves that
    box, and the second box beside it (a barrier's other half), along the route to another
    quarter, the same distance beside the line; the quarters where inserted boxes already failed
    are chosen least; and the carried trap fails again there: a new place, a new signature."""
    import random
    from pytest_navscenario.search.strategies import SHIFT_RADIUS

    space = SearchSpace(lane, {"insert": 2})
    x0, y0, x1, y1 = space.region
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    trap = _values(space, **{"inserted[0]__on": 1.0, "inserted[0]__x": 0.1 - cx, "inserted[0]__y": 1.2 - cy,
                             "inserted[1]__on": 1.0, "inserted[1]__x": -0.6 - cx, "inserted[1]__y": 1.2 - cy})
    ctx = EvalContext(space, Straight, stuck_after=None)
    parent = evaluate_candidate(ctx, trap, "insert")
    assert parent.failed and parent.signature[1:3] == ("inserted", 0), parent.signature
    evo = Evolve(space, _report(space), 10, 0)
    evo.tell([parent])
    evo.failure_signatures.add(("timeout", "inserted", 1, 1))   # quarter 1 has failed already
    assert evo._shiftable() == [parent]
    quarters, new = [], set()
    for k in range(24):
        child = evo._shift(parent, random.Random(k))
        boxes = _inserted(space.apply(child))
        assert [round(b.x, 3) for b in boxes] == [0.1, -0.6], (k, boxes)   # beside the line as before
        assert abs(boxes[0].y - boxes[1].y) < 1e-6 and boxes[0].y != 1.2
        quarter = _lane_quarter(boxes[0].y)
        assert evo.aim == ("inserted", quarter) != ("inserted", 0)
        quarters.append(quarter)
        if k < 6:
            cand = evaluate_candidate(ctx, child, "shift")
            assert cand.failed and cand.signature[1:3] == ("inserted", quarter), (k, cand.signature)
            new.add(cand.signature)
    assert quarters.count(1) < min(quarters.count(2), quarters.count(3))
    assert len(new - {parent.signature}) >= 2
    far = _values(space, **{"inserted[0]__on": 1.0, "inserted[0]__x": 0.1 - cx, "inserted[0]__y": 1.2 - cy,
                            "inserted[1]__on": 1.0, "inserted[1]__x": 1.4 - cx, "inserted[1]__y": 1.2 + SHIFT_RADIUS + 0.5 - cy})
    parent_far = evaluate_candidate(ctx, far, "insert")
    boxes = _inserted(space.apply(evo._shift(parent_far, random.Random(0))))
    assert (boxes[1].x, boxes[1].y) == (1.4, round(1.2 + SHIFT_RADIUS + 0.5, 4))   # not part of the trap: stays


def test_crowd_mutation_puts_a_box_just_beside_the_start_or_goal_footprint(lane):
    """Crowd puts an inserted box within CROWD_GAP of the robot's footprint at the start or the
    goal pose, never on it; once boxes have failed at the start, it crowds the goal most; and a
    box crowding the start ahead of the straight driver stops it."""
    import random

    from pytest_navscenario.scenario.geometry import footprint_polygon, obstacle_polygon
    from pytest_navscenario.search.strategies import CROWD_GAP

    space = SearchSpace(lane, {"insert": 1})
    evo = Evolve(space, _report(space), 10, 0)
    parent = _parent(lane, space)
    fp = lane.robot.footprint
    poses = {"start": lane.mission.start, "goal": lane.mission.goal}
    ends = []
    for k in range(40):
        if k == 20:   # from now on the start has failed twice: the goal is crowded most
            evo.failure_signatures |= {("safety-stop", "inserted", 0, 0), ("timeout", "inserted", 0, 0)}
        (box,) = _inserted(space.apply(evo._crowd(parent, random.Random(k))))
        gaps = {end: footprint_polygon(fp, p.x, p.y, math.radians(p.yaw)).distance(obstacle_polygon(box))
                for end, p in poses.items()}
        end = min(gaps, key=gaps.get)
        assert 0.0 < gaps[end] <= CROWD_GAP + 1e-6, (k, box, gaps)
        assert evo.aim == ("inserted", 0 if end == "start" else 3)
        ends.append(end)
    assert 5 <= ends[:20].count("start") <= 15 and ends[20:].count("goal") >= 16, ends
    ctx = EvalContext(space, Straight, stuck_after=None)
    fresh = Evolve(space, _report(space), 10, 0)
    ahead = [k for k in range(200) if (b := _inserted(space.apply(fresh._crowd(parent, random.Random(k))))[0])
             and 0.4 < b.y < 1.5 and abs(b.x) < 0.4]
    assert ahead
    cand = evaluate_candidate(ctx, fresh._crowd(parent, random.Random(ahead[0])), "crowd")
    assert cand.failed and cand.signature[1:] == ("inserted", 0, 0), cand.signature


def test_target_bandit_moves_on_from_a_place_that_has_failed():
    import random
    from pytest_navscenario.search.strategies import _Targets

    class C:
        def __init__(self, failed, robustness=-1.0):
            self.failed, self.robustness = failed, robustness

    arms = _Targets([("crate", 1), ("crate", 2)])
    known = {("timeout", "crate", 1, 1)}
    arms.tell(("crate", 1), C(True), new_failure=True)
    for _ in range(3):
        arms.tell(("crate", 1), C(True), new_failure=False)   # the same failure again and again
    arms.tell(("crate", 2), C(False, 0.4), new_failure=False)
    assert arms.weight(("crate", 1), known) < arms.weight(("crate", 2), known) / 3
    rnd = random.Random(0)
    picks = [arms.pick(rnd, arms.arms, known) for _ in range(200)]
    assert picks.count(("crate", 2)) > 150


# -- hill-climb -------------------------------------------------------------------------------------
def test_hillclimb_lowers_clearance_monotonically(lane):
    space = SearchSpace(lane, {"insert": 0, "remove": 0})
    report = _report(space, "hillclimb", 16)
    climb = HillClimb(space, report, 16, 0)
    _search_loop(climb, Simulator(EvalContext(space, Straight), report, None), 16, lambda c: None)
    seed_clearance = report.candidates[0].clearance
    assert sum(len(c) for c in climb.climbs) >= 2 and climb.climbs[0][0] < seed_clearance
    for steps in climb.climbs:   # a climb restarts from the seed after it found a failure
        assert all(b < a for a, b in zip([seed_clearance] + steps, steps)), climb.climbs
    assert all(c.origin in ("seed", "climb") for c in report.candidates)
    # one coordinate at a time: each probe differs from the point it climbs from in one parameter
    assert all(sum(v != 0 for v in c.offsets) <= 2 for c in report.candidates)


def test_hillclimb_is_a_strategy_of_run_search(lane):
    report = run_search(lane, Straight, budget=12, strategy="hillclimb", shrink_budget=0)
    assert report.sims_used == 12 and report.strategy == "hillclimb"
    assert report.best_clearance < report.candidates[0].clearance


# -- stuck-robot early stop -------------------------------------------------------------------------
class WaitThenGo(Straight):
    """Stands still for ``wait`` seconds, then drives straight at its target."""
    wait = 4.0

    def act(self, obs):
        return (0.0, 0.0, 0.0) if obs.time < self.wait else super().act(obs)


class Dither(Straight):
    """Drives back and forth on the spot for ever."""

    def act(self, obs):
        return (0.5 if int(obs.time) % 2 == 0 else -0.5, 0.0, 0.0)


def test_stuck_stop_changes_nothing_when_the_robot_recovers_in_time(lane):
    plain = run_scenario(lane, WaitThenGo)
    early = run_scenario(lane, WaitThenGo, stuck_after=5.0)
    assert plain.outcome.value == early.outcome.value == "success"
    assert plain.metrics.duration == early.metrics.duration


def test_stuck_robot_ends_early_as_a_timeout_that_says_so(lane):
    plain = run_scenario(lane, Dither)
    early = run_scenario(lane, Dither, stuck_after=3.0)
    assert plain.outcome.value == early.outcome.value == "timeout"
    assert plain.metrics.duration >= 14.9 and early.metrics.duration < 6.0
    assert "stuck" in early.message and "3 s" in early.message
    waited = run_scenario(lane, WaitThenGo, stuck_after=2.0)   # too short a window: the stop bites
    assert waited.outcome.value == "timeout" and "stuck" in waited.message


@pytest.mark.parametrize("name", sorted(p.stem for p in (ROOT / "scenarios").glob("*.yaml")))
def test_default_stuck_stop_changes_no_outcome_on_the_shipped_seeds(name):
    """All shipped seeds; the example suites are checked by benchmarks/check_stuck.py (231
    episodes with three planners: the longest stall any of them recovered from is 14.5 s)."""
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search.engine import DEFAULT_STUCK_AFTER

    seed = load_scenario(ROOT / "scenarios" / f"{name}.yaml")
    for planner in ("dwa", "potential-field"):
        plain = run_scenario(seed, planner)
        early = run_scenario(seed, planner, stuck_after=DEFAULT_STUCK_AFTER)
        assert plain.outcome == early.outcome, (name, planner, early.message)


# -- batches and determinism ------------------------------------------------------------------------
def chunked(size, reverse=True):
    """An evaluator that evaluates ``size`` candidates at a time, each chunk in reverse order
    (as parallel workers finish in any order), and hands them back in proposal order."""
    def evaluator(ctx, proposals):
        for i in range(0, len(proposals), size):
            chunk = list(enumerate(proposals[i:i + size]))
            done = {j: evaluate_candidate(ctx, *p) for j, p in (reversed(chunk) if reverse else chunk)}
            yield from (done[j] for j in range(len(chunk)))
    return evaluator


def _fingerprint(report):
    return ([(c.phase, c.origin, c.offsets, c.outcome, c.clearance, c.signature) for c in report.candidates],
            [(f.found.sim, f.shrunk.offsets) for f in report.failures])


@pytest.mark.parametrize("strategy", ["evolve", "hillclimb", "random"])
def test_results_do_not_depend_on_how_many_are_evaluated_at_once(lane, strategy):
    serial = run_search(lane, Straight, budget=14, seed_value=5, strategy=strategy, shrink_budget=4)
    for size in (1, 3, 100):
        batched = run_search(lane, Straight, budget=14, seed_value=5, strategy=strategy, shrink_budget=4,
                             evaluator=chunked(size))
        assert _fingerprint(batched) == _fingerprint(serial), size


@pytest.mark.parametrize("strategy, lag", [(Evolve, 1), (HillClimb, 0)])
def test_the_next_generation_is_handed_over_before_this_one_is_told(lane, strategy, lag):
    """Evolve learns one generation late once it has seen the seed's episode, so workers evaluate
    the next generation while it draws; a hill-climb needs every result before its next step. The
    same in serial and parallel runs: the lag is the strategy's, not the evaluator's."""
    events = []

    def eager(ctx, proposals):   # evaluates when handed over, as worker processes start at once
        events.append("evaluate")
        return [evaluate_candidate(ctx, *p) for p in proposals]

    space = SearchSpace(lane, {"insert": 0, "remove": 0})
    report = _report(space, budget=40)
    strat = strategy(space, report, 40, 3)
    tell = strat.tell
    strat.tell = lambda results: (events.append("tell"), tell(results))
    _search_loop(strat, Simulator(EvalContext(space, Straight), report, None, eager), 40, lambda c: None)
    assert report.sims_used == 40 and strat.lag == lag
    generations = events.count("evaluate")
    assert events.count("tell") == generations
    tells = [i for i, e in enumerate(events) if e == "tell"]
    # the first generation (the seed's) is told before the second is drawn; after that,
    # generation k+lag+1 is handed over before generation k is told
    assert events[:2] == ["evaluate", "tell"]
    for k in range(1, generations):
        assert events[:tells[k]].count("evaluate") == min(generations, k + 1 + lag), events


def _frozen_digest(out_dir: Path) -> str:
    h = hashlib.sha256()
    for path in sorted(out_dir.rglob("*.yaml")):
        text = "\n".join(line for line in path.read_text().splitlines() if "date:" not in line)
        h.update(path.name.encode() + text.encode())
    return h.hexdigest()


FREEZE_SCRIPT = """
import sys
sys.path.insert(0, {tests!r})
from pathlib import Path
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.search.engine import run_search
from pytest_navscenario.search.freeze import freeze_failures
from pytest_navscenario.search.space import SearchSpace
from straight_planner import Straight
import test_search_loop as T
seed = loads_scenario(T.OPEN_YAML, "lane.yaml", name="lane")
space = SearchSpace(seed)
report = run_search(seed, Straight, budget=12, seed_value=7, shrink_budget=6, space=space)
freeze_failures(report, space, sys.argv[1])
print(len(report.failures))
"""


def test_same_search_seed_same_frozen_files_across_hash_seeds(tmp_path):
    script = tmp_path / "freeze.py"
    script.write_text(FREEZE_SCRIPT.format(tests=str(Path(__file__).parent)))
    digests = []
    for hash_seed in ("1", "2"):
        out = tmp_path / f"out{hash_seed}"
        env = {**os.environ, "PYTHONHASHSEED": hash_seed, "PYTHONPATH": os.pathsep.join(
            [str(ROOT), str(Path(__file__).parent), os.environ.get("PYTHONPATH", "")])}
        done = subprocess.run([sys.executable, str(script), str(out)], env=env, capture_output=True, text=True,
                              timeout=600)
        assert done.returncode == 0, done.stderr
        assert int(done.stdout.split()[-1]) > 0
        digests.append(_frozen_digest(out))
    assert digests[0] == digests[1]


def test_distinct_failures_differ_in_cause_signature(lane):
    report = run_search(lane, Straight, budget=20, seed_value=1, shrink_budget=0)
    sigs = [f.found.signature for f in report.failures]
    assert sigs and len(set(sigs)) == len(sigs)
    failing = [c for c in report.candidates if c.failed]
    assert {c.signature for c in failing} == set(sigs)   # every failing candidate is one of them
    assert json.loads(json.dumps(report.candidates[0].to_dict(SearchSpace(lane))))["signature"]


def test_candidate_is_plain_data_for_worker_processes(lane):
    import pickle
    space = SearchSpace(lane)
    cand = evaluate_candidate(EvalContext(space, Straight), space.zero(), "seed")
    again = pickle.loads(pickle.dumps(cand))
    assert isinstance(again, Candidate) and again.signature == cand.signature and again.path == cand.path


def test_an_interrupt_while_a_strategy_draws_is_held_until_it_has_drawn():
    """Ctrl-C landing inside Hypothesis's engine came out as an AssertionError from Hypothesis
    (the search failed instead of being cut short): the loop holds it until the drawing is done."""
    import signal
    import time

    from pytest_navscenario.core.interrupts import deferred as _interrupts_deferred

    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    drawn = []
    try:
        with pytest.raises(KeyboardInterrupt):
            with _interrupts_deferred():
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.05)
                drawn.append(True)     # reached: the interrupt waited
    finally:
        signal.signal(signal.SIGINT, old)
    assert drawn == [True]
    assert signal.getsignal(signal.SIGINT) is old


def test_safety_margin_reads_polygon_obstacles_as_their_outline():
    """A success among polygon obstacles is read (finite robustness, not a harness error), and
    a square polygon gives the safety margin the same square as a box gives: the search aims at
    polygon and mesh seeds as at box seeds."""
    from pytest_navscenario.search.fitness import Route, read_episode

    near = OPEN_YAML.replace("x: 1.5, y: 3.0", "x: 0.62, y: 3.0")   # the crate just beside the lane
    as_box = loads_scenario(near, "box.yaml", name="box")
    as_polygon = loads_scenario(near.replace(
        "{type: box, name: crate, x: 0.62, y: 3.0, length: 0.6, width: 0.6}",
        "{type: polygon, name: crate, x: 0.62, y: 3.0, height: 0.5, "
        "points: [[-0.3, -0.3], [0.3, -0.3], [0.3, 0.3], [-0.3, 0.3]]}"), "poly.yaml", name="poly")
    readings = []
    for sc in (as_box, as_polygon):
        res = run_scenario(sc, Straight())
        assert res.outcome.value == "success", res.message
        readings.append(read_episode(res, Route(sc))[0])
    box, poly = readings
    assert math.isfinite(poly.robustness)
    assert 0.0 < box.margins["safety"] < 1.0      # near enough to count, far enough not to stop
    assert poly.margins["safety"] == pytest.approx(box.margins["safety"], abs=1e-6)


def test_first_generation_is_uniform_layouts_least_room_first_then_the_seed(lane):
    """Before any episode evolve draws uniform layouts, HUNT_DRAWS per candidate, and keeps the
    ones that leave the robot the least room (the narrowest passage's room less how deep the
    obstacles cut into the seed's route), least first; the seed's own episode comes last, so the
    second generation can aim at it. A smaller budget gets the same layouts, without the seed."""
    from pytest_navscenario.search.strategies import GENERATION, HUNT_DRAWS, ROOM_LEVELS, uniform
    from pytest_navscenario.verdict.paths import passage_room

    space = SearchSpace(lane)
    strat = Evolve(space, _report(space, budget=100), 100, 3)
    first = strat.ask(100)
    assert [origin for _, origin in first] == ["explore"] * (GENERATION - 1) + ["seed"]
    assert first[-1][0] == space.zero()

    def room(offsets):
        scenario = space.apply(offsets)
        return passage_room(scenario, ROOM_LEVELS) - strat._intrusion(scenario)

    rooms = [room(o) for o, _ in first[:-1]]
    assert rooms == sorted(rooms)
    rnd = random.Random(0)
    plain = sorted(room(uniform(space, rnd)) for _ in range(HUNT_DRAWS * (GENERATION - 1)))
    assert max(rooms) <= plain[len(plain) // 2]          # the tightest of many, not any seven
    small = Evolve(space, _report(space, budget=5), 5, 3).ask(5)
    assert small == first[:5]


def test_where_tight_layouts_fail_the_first_candidate_fails_far_more_often_than_a_uniform_one(lane):
    """Straight fails when the crate is moved onto its line, which a uniform layout does about
    four times in ten: evolve's first candidate, the tightest of its draws, fails almost always."""
    firsts = {strategy: [run_search(lane, Straight, budget=1, seed_value=k, strategy=strategy,
                                    shrink_budget=0).first_failure for k in range(10)]
              for strategy in ("evolve", "random")}
    evolve, rnd = (sum(f == 1 for f in firsts[s]) for s in ("evolve", "random"))
    assert evolve >= 9 and evolve >= rnd + 4, firsts
