"""Moving obstacles (issue 12, part 1): the format, the simulation, the verdict and the pictures.

Real MuJoCo episodes with tiny planners whose behaviour is known (stand still, drive straight), so
each test knows who walked into whom, where the person was and when.
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.report.results_file import make_record
from pytest_navscenario.scenario.dump import dump_scenario
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.scenario.model import content_hash
from pytest_navscenario.scenario.motion import Track
from pytest_navscenario.sim.episode import simulate
from pytest_navscenario.sim.safety import SafetyLayer

BASE = """\
version: 1
robot: {{safety: {{enabled: {safety}}}}}
mission: {{start: {{x: 0, y: 0}}, goal: {{x: 6, y: 0}}, timeout: {timeout}}}
obstacles:
{obstacles}
"""


def scenario(obstacles: str, *, safety: str = "true", timeout: float = 10.0):
    return loads_scenario(BASE.format(safety=safety, timeout=timeout, obstacles=obstacles),
                          source="moving.yaml")


class Still:
    """Stands where it starts."""

    def reset(self, scenario):
        pass

    def act(self, obs):
        return (0.0, 0.0, 0.0)


class Straight:
    """Drives along +x at 1 m/s, blind; records the scans it saw."""

    def __init__(self):
        self.scans = []

    def reset(self, scenario):
        self.scans = []

    def act(self, obs):
        self.scans.append((obs.time, np.array(obs.ranges), np.array(obs.angles)))
        return (1.0, 0.0, 0.0)


CROSSING = "  - {type: person, name: walker, motion: {path: [[%s, -3], [%s, 3]], start: 0.5}}"


# ---------------------------------------------------------------- who walked into whom

def test_a_person_walking_into_a_standing_robot_is_told_apart_from_a_robot_driving_into_one():
    standing = run_scenario(scenario(CROSSING % (0.0, 0.0)), Still)
    driving = run_scenario(scenario(CROSSING % (3.0, 3.0), safety="false"), Straight)
    for result in (standing, driving):
        assert result.outcome.value == "collision" and result.collision.obstacle == "walker"
        assert result.collision.obstacle_speed == pytest.approx(1.3)
    # the standing robot was walked into: the person reached it (0.25 + 0.25 m from y = -3 at
    # 1.3 m/s after 0.5 s)
    assert not standing.collision.robot_moving and standing.collision.robot_speed < 1e-6
    assert standing.collision.time == pytest.approx(0.5 + 2.5 / 1.3, abs=0.02)
    assert "the robot stood still and 'walker' walked into it at 1.30 m/s" in standing.message
    assert driving.collision.robot_moving and driving.collision.robot_speed == pytest.approx(1.0, abs=0.01)
    assert "the robot drove into it at 1.00 m/s" in driving.message
    # the results file says it too
    rec_standing = make_record(standing, nodeid="a", path="a.yaml")
    rec_driving = make_record(driving, nodeid="b", path="b.yaml")
    assert rec_standing["collision"]["robot_moving"] is False
    assert rec_driving["collision"]["robot_moving"] is True
    assert json.loads(json.dumps(rec_standing))["collision"]["obstacle"] == "walker"


def test_a_static_collision_still_reads_as_before():
    result = run_scenario(scenario("  - {type: box, name: crate, x: 3, y: 0, length: 1, width: 1}",
                                   safety="false"), Straight)
    assert result.collision.robot_moving and result.collision.obstacle_speed == 0.0
    assert result.message.endswith(f"({result.collision.x:.2f}, {result.collision.y:.2f})")


# ---------------------------------------------------------------- what the robot senses

def test_the_lidar_sees_a_moving_obstacle_where_it_is_at_each_tick():
    planner = Straight()
    planner.act = lambda obs: (planner.scans.append((obs.time, np.array(obs.ranges))), (0.0, 0.0, 0.0))[1]
    sc = scenario("  - {type: cylinder, name: cart, radius: 0.3, x: 3.0, y: -4.0, "
                  "motion: {velocity: [0.0, 1.0], start: 0.5}}")
    result = simulate(sc, planner, seed=0, max_ticks=60)
    planner_angles = np.asarray(result.trajectory.angles)
    track = Track(sc.obstacles[0])
    assert len(planner.scans) == 60
    for t, ranges in planner.scans:
        cx, cy = track.positions(np.array([t]))[0]
        # every beam from the origin: where it meets the cart's circle where the cart is now
        c, s = np.cos(planner_angles), np.sin(planner_angles)
        along = c * cx + s * cy
        across2 = cx * cx + cy * cy - along ** 2
        hits = (along > 0) & (across2 < 0.3 ** 2)
        expected = np.where(hits, along - np.sqrt(np.maximum(0.3 ** 2 - across2, 0.0)), 8.0)
        assert hits.any()
        np.testing.assert_allclose(ranges, expected, atol=1e-4, err_msg=f"t={t}")
    assert planner.scans[0][1].min() > planner.scans[-1][1].min() + 1.5   # it came closer


def test_the_safety_layer_predicts_with_the_obstacles_velocity():
    sc = scenario("  - {type: person, name: oncoming, motion: {velocity: [-1.3, 0.0]}, x: 2.0, y: 0.0}")
    layer = SafetyLayer(sc)
    # the robot (half length 0.45) at 1.0 m from the person's edge... 2.0 - 0.25 - 0.45 = 1.3 m gap;
    # at 0.5 m/s over 0.5 s the robot alone closes 0.25 m: no halt if the person stood still
    still = [[0.0, 0.0, 0.0, 0.0]]
    assert layer.check(0.0, 0.0, 0.0, 0.5, 0.0, 0.0, still) is None
    # walking towards the robot at 1.3 m/s the gap closes by 0.9 m more: halt
    oncoming = [[0.0, 0.0, -1.3, 0.0]]
    assert layer.check(0.0, 0.0, 0.0, 0.5, 0.0, 0.0, oncoming) is None  # 1.15 m < 1.3 m: not yet
    # 0.5 m nearer (gap 0.8 m): 0.25 m + 0.65 m closes it within the horizon; standing, it would not
    near = [[-0.5, 0.0, -1.3, 0.0]]
    assert layer.check(0.0, 0.0, 0.0, 0.5, 0.0, 0.0, near) == "oncoming"
    near_still = [[-0.5, 0.0, 0.0, 0.0]]
    assert layer.check(0.0, 0.0, 0.0, 0.5, 0.0, 0.0, near_still) is None
    # and it is where it is now, not where the scenario placed it
    gone = [[0.0, 5.0, 0.0, 0.0]]
    assert layer.check(0.0, 0.0, 0.0, 0.5, 0.0, 0.0, gone) is None


def test_the_safety_layer_halts_a_robot_before_a_crossing_person():
    result = run_scenario(scenario(CROSSING % (3.0, 3.0)), Straight)
    assert result.outcome.value == "safety-stop" and result.safety_stop.obstacle == "walker"


# ---------------------------------------------------------------- the verdict

def test_clearance_is_measured_against_where_the_obstacle_was_at_that_moment():
    # a person passes 1.0 m beside a standing robot (box 0.9 x 0.5 along +x): closest when x = 0,
    # clearance 1.0 - 0.25 - 0.25 = 0.5 m at t = 0.5 + 3 / 1.3
    sc = scenario("  - {type: person, name: passer, motion: {path: [[-3, 1], [3, 1]], start: 0.5}}")
    result = run_scenario(sc, Still)
    m = result.metrics
    assert m.min_clearance_obstacle == "passer"
    assert m.min_clearance == pytest.approx(0.5, abs=1e-3)
    # the earliest moment of it: the person's centre level with the robot's back corner... front
    assert 0.5 + 2.55 / 1.3 - 0.01 <= m.min_clearance_time <= 0.5 + 3.45 / 1.3
    # and the shortest path ignores it (it is somewhere else a moment later)
    assert m.shortest_path_length == pytest.approx(6.0)


# ---------------------------------------------------------------- motion itself

def test_motion_modes_follow_their_path():
    sc = scenario("\n".join([
        "  - {type: cylinder, name: once, radius: 0.2, motion: {path: [[10, 0], [12, 0]], speed: 1.0, start: 1.0}}",
        "  - {type: cylinder, name: back, radius: 0.2, motion: {path: [[10, 5], [12, 5]], speed: 1.0, mode: back-and-forth}}",
        "  - {type: cylinder, name: loop, radius: 0.2, motion: {path: [[10, -5], [12, -5], [12, -3]], speed: 2.0, mode: loop}}",
        "  - {type: box, name: cart, length: 1, width: 1, x: 10, y: 10, motion: {velocity: [0.5, -0.5], start: 2}}",
    ]))
    once, back, loop, cart = (Track(o) for o in sc.obstacles)
    t = np.array([0.0, 1.0, 2.0, 3.0, 10.0])
    assert once.positions(t)[:, 0].tolist() == [10, 10, 11, 12, 12]
    assert back.positions(np.array([0.0, 1.0, 2.0, 3.0, 4.0, 5.0]))[:, 0].tolist() == [10, 11, 12, 11, 10, 11]
    # loop: 2 + 2 + 2.83 m at 2 m/s, back to the start after 3.41 s
    period = (4 + math.hypot(2, 2)) / 2
    np.testing.assert_allclose(loop.positions(np.array([1.0, 2.0, period, period + 1.0])),
                               [[12, -5], [12, -3], [10, -5], [12, -5]], atol=1e-12)
    assert cart.positions(np.array([1.0, 4.0])).tolist() == [[10, 10], [11, 9]]
    assert once.velocity(0.5) == (0.0, 0.0) and once.velocity(1.5) == (1.0, 0.0) and once.velocity(5) == (0, 0)
    assert back.velocity(2.5) == (-1.0, 0.0)


def test_episodes_with_moving_obstacles_are_bit_for_bit_repeatable():
    sc = scenario(CROSSING % (3.0, 3.0) + "\n  - {type: box, name: cart, length: 0.8, width: 0.6, x: 2, "
                  "y: 4, motion: {velocity: [0, -0.8], start: 1}}")
    a, b = (simulate(sc, Straight(), seed=3) for _ in range(2))
    assert a.trajectory.pose.tobytes() == b.trajectory.pose.tobytes()
    assert a.trajectory.ranges.tobytes() == b.trajectory.ranges.tobytes()
    assert (a.end, a.safety_stop, a.collision) == (b.end, b.safety_stop, b.collision)


# ---------------------------------------------------------------- the format

def test_moving_obstacles_round_trip_and_static_files_hash_as_before():
    sc = scenario(CROSSING % (3.0, 3.0) + "\n  - {type: box, name: cart, length: 0.8, width: 0.6, x: 2, "
                  "y: 4, motion: {velocity: [0, -0.8], start: 1}}")
    again = loads_scenario(dump_scenario(sc))
    assert again == sc and content_hash(again) == content_hash(sc)
    walker = sc.obstacle("walker")
    assert (walker.radius, walker.height, walker.motion.speed) == (0.25, 1.7, 1.3)
    assert (walker.x, walker.y) == (3.0, -3.0)
    # a file without motion hashes as it did before motion existed (pinned)
    static = scenario("  - {type: box, name: crate, x: 3, y: 0, length: 1, width: 1}")
    assert content_hash(static) == "4499f94111b5cd39"   # computed with the code before issue 12


BAD = [
    ("{type: person, motion: {path: [[3, -3]]}}", "obstacles[0].motion.path",
     "a path needs at least two points, got 1 point"),
    ("{type: person, motion: {path: []}}", "obstacles[0].motion.path", "at least two points, got 0 points"),
    ("{type: person, motion: {path: [[3, -3], [3, -3]]}}", "obstacles[0].motion.path", "has no length"),
    ("{type: person, motion: {path: [[3, -3], [3, 4]], speed: 0}}", "obstacles[0].motion.speed",
     "must be > 0, got 0.0"),
    ("{type: person, motion: {path: [[3, -3], [3, 4]], speed: -1.0}}", "obstacles[0].motion.speed",
     "must be > 0, got -1.0"),
    ("{type: box, x: 1, y: 2, length: 1, width: 1, motion: {path: [[3, -3], [3, 4]]}}",
     "obstacles[0].motion.speed", "missing required field 'speed'"),
    ("{type: person, x: 1, motion: {path: [[3, -3], [3, 4]]}}", "obstacles[0].x", "given by the motion's path"),
    ("{type: person, motion: {path: [[3, -3], [3, 4]], mode: pingpong}}", "obstacles[0].motion.mode",
     "unknown mode 'pingpong'"),
    ("{type: person, motion: {path: [[3, -3], [3, 4]], start: -1}}", "obstacles[0].motion.start", "must be >= 0"),
    ("{type: person, motion: {path: [[3, -3], [3]]}}", "obstacles[0].motion.path[1]", "expected a point [x, y]"),
    ("{type: person, x: 1, y: 1, motion: {velocity: [1, 0], speed: 1}}", "obstacles[0].motion.speed",
     "does not go with 'velocity'"),
    ("{type: person, x: 1, y: 1, motion: {}}", "obstacles[0].motion.path", "missing required field 'path'"),
    ("{type: person, motion: {path: [[0, -0.2], [0, 3]]}}", "mission.start", "overlaps obstacle 'person1'"),
]


@pytest.mark.parametrize("obstacle, field, message", BAD, ids=[b[1] + ":" + b[2][:20] for b in BAD])
def test_bad_motion_input_names_file_line_and_field(obstacle, field, message):
    with pytest.raises(ScenarioError) as err:
        scenario("  - " + obstacle)
    text = str(err.value)
    assert "moving.yaml" in text and message in text and field in text, text
    assert err.value.line in (3, 5), text   # the obstacle's line (or the mission's for the start)


def test_a_moving_obstacle_may_cross_the_goal():
    sc = scenario("  - {type: person, motion: {path: [[6, -3], [6, 3]]}}")
    assert sc.obstacles[0].motion is not None


# ---------------------------------------------------------------- pictures, bags, search

def test_the_plot_draws_the_moving_obstacle_where_it_was_at_the_key_moments(tmp_path):
    pytest.importorskip("matplotlib")
    from pytest_navscenario.report.plots import (moving_key_moments, obstacle_polygon_at,
                                                 trajectory_figure)

    result = run_scenario(scenario(CROSSING % (0.0, 0.0)), Still)    # walked into at t ~ 2.4 s
    walker = result.scenario.obstacle("walker")
    moments = moving_key_moments(result, walker)
    assert [label.split()[0] for _, label in moments] == ["t=0", "collision"]  # closest = the end
    end = obstacle_polygon_at(walker, moments[-1][0])
    assert end.centroid.y == pytest.approx(-3 + 1.3 * (moments[-1][0] - 0.5), abs=1e-6)
    fig = trajectory_figure(result)
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.texts]
    assert "walker t=0" in texts and any(t.startswith("collision t=") for t in texts)
    assert "moving obstacle's way" in ax.get_legend_handles_labels()[1] or \
        any("moving obstacle's way" in t.get_text() for t in fig.legends[0].get_texts())
    assert any("robot standing" in " ".join(t.get_text().split()) for leg in fig.legends for t in leg.get_texts())
    fig.savefig(tmp_path / "walked.png")


def test_bags_carry_the_moving_obstacles_poses_over_time(tmp_path):
    pytest.importorskip("rosbags")
    from rosbags.highlevel import AnyReader

    from pytest_navscenario.ros.bag_writer import MOVING_TOPIC, write_episode_bag

    result = run_scenario(scenario(CROSSING % (0.0, 0.0)), Still)
    path = write_episode_bag(result, tmp_path / "bag")
    track = Track(result.scenario.obstacle("walker"))
    with AnyReader([path]) as reader:
        conns = [c for c in reader.connections if c.topic == MOVING_TOPIC]
        assert conns and conns[0].msgtype == "visualization_msgs/msg/MarkerArray"
        msgs = [(ts, reader.deserialize(raw, c.msgtype)) for c, ts, raw in reader.messages(connections=conns)]
        static = [c for c in reader.connections if c.topic == "/navscenario/obstacles"]
        latched = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=static)]
    assert len(msgs) > 50 and latched[0].markers == []       # the walker is not a static marker
    for ts, msg in msgs[::10]:
        (marker,) = msg.markers
        x, y = track.positions(np.array([ts / 1e9]))[0]
        assert (marker.pose.position.x, marker.pose.position.y) == pytest.approx((x, y))
        assert marker.ns == "moving_obstacles" and marker.type == 3 and marker.text == "walker"
    assert msgs[-1][1].markers[0].color.r == pytest.approx(0.9)   # red once it hit the robot


def test_the_search_space_moves_a_moving_obstacles_start_speed_and_path():
    from pytest_navscenario.search.space import SearchSpace

    sc = scenario(CROSSING % (3.0, 3.0) + "\n  - {type: box, name: cart, length: 0.8, width: 0.6, x: 2, "
                  "y: 4, motion: {velocity: [0, -0.8], start: 1}}")
    space = SearchSpace(sc)
    names = [p.name for p in space.params]
    assert "obstacles.walker.motion.start" in names and "obstacles.walker.motion.speed" in names
    assert "obstacles.cart.motion.speed" in names
    offsets = [0.0] * len(space)
    for name, value in (("obstacles.walker.dx", 0.5), ("obstacles.walker.motion.start", -2.0),
                        ("obstacles.walker.motion.speed", 0.4), ("obstacles.cart.motion.speed", 0.2)):
        offsets[space.index[name]] = value
    moved = space.apply(offsets)
    walker, cart = moved.obstacle("walker"), moved.obstacle("cart")
    assert walker.motion.path == ((3.5, -3.0), (3.5, 3.0)) and (walker.x, walker.y) == (3.5, -3.0)
    assert walker.motion.start == 0.0 and walker.motion.speed == pytest.approx(1.7)  # start clamped at 0
    assert cart.motion.velocity == pytest.approx((0.0, -1.0))
    assert space.apply(space.zero()) == sc
    # a seed without moving obstacles has the same space as before
    static = SearchSpace(scenario("  - {type: box, name: crate, x: 3, y: 0, length: 1, width: 1}"), {"insert": 0})
    assert [p.attr for p in static.params] == ["dx", "dy", "size", "yaw"]


# the content hashes of the five paper seeds, computed with the code before moving obstacles existed:
# the files load unchanged and mean the same (the same hash pairs them across results files)
SEED_HASHES = {"boxes1": "1bfa4415005c2e02", "boxes2": "aeb896a18fd92360", "corridor": "38b126911cdbd6fe",
               "cylinders": "40b0696933c5e63c", "L-corridor": "485472539df6322b"}


@pytest.mark.parametrize("name", sorted(SEED_HASHES))
def test_the_paper_seeds_hash_as_before(name):
    from pytest_navscenario.scenario.loader import load_scenario

    sc = load_scenario(Path(__file__).resolve().parents[2] / "scenarios" / f"{name}.yaml")
    assert content_hash(sc) == SEED_HASHES[name]
    assert all(o.motion is None for o in sc.obstacles)
