"""The CPU batch engine (sim/batching/batch.py, lockstep.py, cohort.py): episodes stepped in lockstep with one
planner call a tick end at different ticks with exactly the trajectories and endings they have
alone, and a failing planner call fails the episodes of that call only (issue 27)."""
from __future__ import annotations

import dataclasses
import math
import os
import time

import pytest

from pytest_navscenario.harness.batch import NO_PROTOCOL, Batching, run_batch
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle, Mission, Pose, Robot, Scenario
from pytest_navscenario.scenario.terrain import WheeledBody
from pytest_navscenario.sim.batching.batch import BatchEpisode, batch_engine, simulate_batch
from pytest_navscenario.sim.episode import simulate
from pytest_navscenario.subjects.protocol import Command

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ARRAYS = ("t", "pose", "velocity", "tick_t", "command", "ranges")


def seed(name: str) -> Scenario:
    return load_scenario(os.path.join(ROOT, "scenarios", f"{name}.yaml"))


class GoTo:
    """Omni P-controller to the next target; ``speed`` caps it (a single planner)."""

    def __init__(self, heading: float | None = None):
        self.heading = heading

    def reset(self, scenario):
        pass

    def act(self, obs):
        if self.heading is not None:           # straight ahead, whatever is there
            return Command(1.0, 0.0, 0.0)
        tx, ty = obs.target
        x, y, yaw = obs.pose
        c, s = math.cos(yaw), math.sin(yaw)
        return Command(2 * (c * (tx - x) + s * (ty - y)), 2 * (-s * (tx - x) + c * (ty - y)), 0.3)


class BatchOf:
    """A batch planner made of one single planner per episode (what act_batch must be equal to),
    which can misbehave on purpose: raise at a tick, answer NaN for one id, the wrong number of
    commands, or sleep."""

    def __init__(self, make=GoTo, *, raise_at=None, nan_for=None, short_at=None, sleep_at=None):
        self.make, self.raise_at, self.nan_for, self.short_at, self.sleep_at = make, raise_at, nan_for, short_at, sleep_at
        self.calls = []

    def reset_batch(self, scenarios):
        self.planners = [self.make() for _ in scenarios]
        for p, s in zip(self.planners, scenarios):
            p.reset(s)

    def act_batch(self, ids, observations):
        tick = observations[0].tick
        self.calls.append(list(ids))
        if tick == self.raise_at:
            raise ZeroDivisionError(f"bug at tick {tick}")
        if tick == self.sleep_at:
            time.sleep(0.3)
        out = [self.planners[i].act(o) for i, o in zip(ids, observations)]
        if tick == 2 and self.nan_for in ids:
            out[list(ids).index(self.nan_for)] = (math.nan, 0.0, 0.0)
        if tick == self.short_at:
            out = out[:1]
        return out


def same(a, b) -> bool:
    ta, tb = a.trajectory, b.trajectory
    return (all(getattr(ta, k).tobytes() == getattr(tb, k).tobytes() for k in ARRAYS)
            and (a.end, a.ticks, a.collision, a.safety_stop, a.subject_failure and a.subject_failure.message)
            == (b.end, b.ticks, b.collision, b.safety_stop, b.subject_failure and b.subject_failure.message))


def with_robot(sc: Scenario, **parts) -> Scenario:
    robot = sc.robot
    changes = {k: dataclasses.replace(getattr(robot, k), **v) if isinstance(v, dict) else v for k, v in parts.items()}
    return dataclasses.replace(sc, robot=dataclasses.replace(robot, **changes))


def a_mixed_batch() -> list[tuple[Scenario, dict, object]]:
    """(scenario, simulate's keyword arguments, single planner factory) of episodes that end in
    every way and take every path of the engine (cohort, alone; rollout, stepped again)."""
    b1 = seed("boxes1")
    start = b1.mission.start
    under = BoxObstacle("under", start.x, start.y, 1.0, 1.0)
    return [
        (b1, {}, GoTo),                                                        # goal
        (seed("boxes2"), {"max_ticks": 7}, GoTo),                              # max-ticks
        (dataclasses.replace(b1, obstacles=(under,)), {}, GoTo),              # collision at the start
        (with_robot(b1, safety={"enabled": False}), {}, lambda: GoTo(0.0)),   # collision (a tick again alone)
        (b1, {}, lambda: GoTo(0.0)),                                           # safety stop
        (seed("person-crossing"), {}, GoTo),                                   # moving obstacles: alone
        (with_robot(b1, latency={"observation": 1}), {}, GoTo),                # a sensor fault: alone
        (with_robot(b1, lidar={"noise_sigma": 0.02}), {"stuck_after": 3.0}, GoTo),   # noise: alone
    ]


class PerEpisode(BatchOf):
    """A batch planner whose episode i is made by ``makes[i]``."""

    def __init__(self, makes):
        super().__init__()
        self.makes = makes

    def reset_batch(self, scenarios):
        assert len(scenarios) == len(self.makes)
        self.planners = [make() for make in self.makes]
        for p, s in zip(self.planners, scenarios):
            p.reset(s)


def test_a_batch_ends_each_episode_as_alone_at_different_ticks():
    cases = a_mixed_batch()
    alone = [simulate(sc, make(), 0, **kw) for sc, kw, make in cases]
    # the collision at the start pose (case 2) never reaches the planner: reset_batch gets the others
    planner = PerEpisode([make for i, (_, _, make) in enumerate(cases) if i != 2])
    batched = simulate_batch([BatchEpisode(sc, 0, **kw) for sc, kw, _ in cases], planner)
    ends = [a.end for a in alone]
    assert {"goal", "max-ticks", "collision", "safety-stop"} <= set(ends) and alone[2].ticks == 0
    assert [same(a, b) for a, b in zip(alone, batched)] == [True] * len(cases), ends
    # one call a tick, for the episodes still running: fewer and fewer ids
    sizes = [len(ids) for ids in planner.calls]
    assert sizes[0] == len(cases) - 1 and sizes[-1] < sizes[0] and sizes == sorted(sizes, reverse=True)


def three() -> list[BatchEpisode]:
    b1 = seed("boxes1")
    return [BatchEpisode(b1, 0), BatchEpisode(b1, 1, max_ticks=1), BatchEpisode(seed("corridor"), 0)]


def test_act_batch_that_raises_fails_the_episodes_of_that_call_only():
    planner = BatchOf(raise_at=4)
    r = simulate_batch(three(), planner)
    assert r[1].end == "max-ticks" and r[1].subject_failure is None      # ended before the call
    for res in (r[0], r[2]):
        f = res.subject_failure
        assert res.end == "subject-error" and f.tick == 4
        assert f.message == "planner.act_batch raised ZeroDivisionError: bug at tick 4"
        assert "bug at tick" in f.traceback and "act_batch" in f.traceback
    assert planner.calls[-1] == [0, 2]


def test_one_bad_command_fails_its_episode_only():
    r = simulate_batch(three(), BatchOf(nan_for=2))
    assert r[2].end == "subject-error" and r[2].subject_failure.tick == 2
    assert r[2].subject_failure.message.startswith("planner.act_batch returned for this episode a non-finite "
                                                   "command (vx=nan")
    assert r[0].subject_failure is None and r[0].end == simulate(seed("boxes1"), GoTo(), 0).end


def test_the_wrong_number_of_commands_fails_the_call():
    r = simulate_batch(three(), BatchOf(short_at=3))
    assert [x.end for x in r] == ["subject-error", "max-ticks", "subject-error"]
    assert r[0].subject_failure.message == ("planner.act_batch returned 1 commands for 2 episodes; expected "
                                            "one command per id, in the order of ids")


def test_an_answer_that_is_a_mapping_or_cannot_be_listed_fails_the_call_saying_what_it_got():
    # a dict {id: command} has the right length, and listing it gave its keys: "returned for this episode
    # int 0"; an answer whose len() or iteration raised escaped the batch and ended every episode in it
    class Keyed(BatchOf):
        def act_batch(self, ids, observations):
            return dict(zip(ids, super().act_batch(ids, observations)))

    class Broken:
        def __len__(self):
            return 3

        def __iter__(self):
            raise ValueError("lazy answers failed")

    class Lazy(BatchOf):
        def act_batch(self, ids, observations):
            return Broken()

    r = simulate_batch(three(), Keyed())
    assert [x.end for x in r] == ["subject-error"] * 3 and r[0].subject_failure.tick == 0
    assert r[0].subject_failure.message.startswith("planner.act_batch returned dict {0: ")
    assert r[0].subject_failure.message.endswith("for 3 episodes; expected a list of one command per id, in the "
                                                 "order of ids")
    r = simulate_batch(three(), Lazy())
    assert [x.end for x in r] == ["subject-error"] * 3
    assert r[2].subject_failure.message == ("planner.act_batch's answer cannot be read as a list: ValueError: "
                                            "lazy answers failed")


def test_reset_batch_that_raises_fails_every_episode_that_started():
    class Broken(BatchOf):
        def reset_batch(self, scenarios):
            raise RuntimeError("no model file")

    b1 = seed("boxes1")
    start = b1.mission.start
    inside = dataclasses.replace(b1, obstacles=(BoxObstacle("under", start.x, start.y, 1.0, 1.0),))
    r = simulate_batch([BatchEpisode(b1, 0), BatchEpisode(inside, 0)], Broken())
    assert r[0].end == "subject-error" and r[0].subject_failure.message == \
        "planner.reset_batch raised RuntimeError: no model file"
    assert r[1].end == "collision" and r[1].subject_failure is None       # never reached the planner


def test_the_tick_limit_of_a_batch_call_is_the_limit_times_its_episodes():
    b1 = seed("boxes1")
    r = simulate_batch([BatchEpisode(b1, 0, tick_limit=0.05), BatchEpisode(b1, 1, tick_limit=0.05)],
                       BatchOf(sleep_at=2))
    for res in r:
        assert res.end == "subject-error" and res.subject_failure.tick == 2
        assert "0.1 s (0.05 s for each of the call's 2 episodes)" in res.subject_failure.message


def test_a_batch_only_planner_runs_alone_as_a_batch_of_one():
    class OnlyBatch(BatchOf):
        name, version = "only-batch", "2"

    alone = run_scenario(seed("boxes1"), OnlyBatch())
    single = run_scenario(seed("boxes1"), GoTo())
    assert (alone.outcome, alone.metrics) == (single.outcome, single.metrics)
    assert (alone.subject, alone.subject_version) == ("only-batch", "2")


def test_run_batch_runs_alone_what_it_cannot_batch_and_says_why():
    wheeled = Scenario(mission=Mission(start=Pose(0.0, 0.0, 0.0), goal=Pose(3.0, 0.0), timeout=5.0),
                       robot=Robot(drive="diff", body=WheeledBody(clearance=0.1)))
    assert batch_engine().unsupported(wheeled) is not None
    scenarios = [seed("boxes1"), wheeled, seed("corridor")]
    batching = Batching()
    results = run_batch(scenarios, "dwa", batching=batching, seeds=[0, 0, 0])
    alone = [run_scenario(s, "dwa", seed=0) for s in scenarios]
    assert [(r.outcome, r.message, r.metrics) for r in results] == [(a.outcome, a.message, a.metrics) for a in alone]
    assert (batching.batched, batching.batches, batching.alone) == (2, 1, 1)
    assert "rides the ground" in batching.describe()
    plain = Batching()
    run_batch(scenarios[:1], "potential-field", batching=plain)
    assert plain.why_alone == {NO_PROTOCOL: 1}


class Seeing(GoTo):
    """``GoTo`` that keeps every field of every observation it is handed."""

    def reset(self, scenario):
        self.seen = []

    def act(self, obs):
        fields = {}
        for name in ("tick", "time", "pose", "velocity", "ranges", "angles", "goal", "waypoints", "obstacles",
                     "points", "attitude"):
            value = getattr(obs, name)
            fields[name] = (type(value).__name__, value.dtype.str, value.shape, value.tobytes(), value.flags.writeable) \
                if hasattr(value, "tobytes") else value
        self.seen.append(fields)
        return super().act(obs)


def test_a_batch_hands_each_planner_the_observations_it_gets_alone():
    cases = [seed("boxes1"), seed("corridor"), seed("boxes2"), seed("boxes1")]
    alone = []
    for sc in cases:
        planner = Seeing()
        simulate(sc, planner, 0)
        alone.append(planner.seen)
    batch = BatchOf(Seeing)
    simulate_batch([BatchEpisode(sc, 0) for sc in cases], batch)
    for mine, theirs in zip(alone, (p.seen for p in batch.planners)):
        assert len(mine) == len(theirs)
        assert mine == theirs      # attitude (0, 0) of the planar body, points None, read-only rows


class Straight:
    """Full speed ahead, whatever is there."""

    def reset(self, scenario):
        pass

    def act(self, obs):
        return (0.8, 0.0, 0.0)


def test_a_batch_finds_a_collision_at_every_physics_step_of_a_tick_as_alone():
    # a wall a little farther each time: the first contact falls on every state of a tick, the
    # tick's final state included (whose contacts the engine looks at only near an obstacle)
    b1 = with_robot(seed("boxes1"), safety={"enabled": False})
    start = b1.mission.start
    cases = [dataclasses.replace(b1, obstacles=(BoxObstacle("wall", start.x + 1.0 + 0.0037 * n, start.y, 0.3, 3.0),),
                                 mission=dataclasses.replace(b1.mission, start=Pose(start.x, start.y, 0.0)))
             for n in range(30)]
    alone = [simulate(sc, Straight(), 0) for sc in cases]
    batched = simulate_batch([BatchEpisode(sc, 0) for sc in cases], PerEpisode([Straight] * len(cases)))
    assert {a.end for a in alone} == {"collision"}
    assert {len(a.trajectory.t) % 10 for a in alone} == set(range(10))     # spt = 10: every state
    assert [same(a, b) for a, b in zip(alone, batched)] == [True] * len(cases)


class Ahead:
    """Straight ahead at ``speed``, turning at ``turn``."""

    def __init__(self, speed: float, turn: float = 0.0):
        self.speed, self.turn = speed, turn

    def reset(self, scenario):
        pass

    def act(self, obs):
        return (self.speed, 0.0, self.turn)


def test_a_batch_halts_each_robot_where_its_safety_layer_does_alone():
    # round robots driving at posts at several speeds, the safety layer on: the cohort skips the
    # checks of robots with nothing within reach, and must never skip one that halts (circles on
    # circles: the layer's reach is tight, a skip one tick too many moves the halt)
    b1 = with_robot(seed("boxes1"), footprint={"shape": "circle", "radius": 0.3})
    start = b1.mission.start
    cases, makes = [], []
    for n in range(24):
        posts = (CylinderObstacle("post", start.x + 1.5 + 0.013 * n, start.y + 0.05 * (n % 3), 0.2),)
        cases.append(dataclasses.replace(b1, obstacles=posts,
                                         mission=dataclasses.replace(b1.mission, start=Pose(start.x, start.y, 0.0))))
        makes.append(lambda speed=0.3 + 0.05 * n: Ahead(speed))
    alone = [simulate(sc, make(), 0) for sc, make in zip(cases, makes)]
    batched = simulate_batch([BatchEpisode(sc, 0) for sc in cases], PerEpisode(makes))
    assert {a.end for a in alone} == {"safety-stop"}
    assert [same(a, b) for a, b in zip(alone, batched)] == [True] * len(cases)
