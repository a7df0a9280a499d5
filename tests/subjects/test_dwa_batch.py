"""The batched dwa (``act_batch``) gives every episode exactly the commands ``act`` gives it alone:
on every shipped seed, on search candidates, and on batches that mix robots, lidars, noise and a
goal yaw (issue 27: batching changes speed and nothing else)."""
from __future__ import annotations

import dataclasses
import glob
import os

import numpy as np
import pytest

from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.sim.batching.batch import BatchEpisode, simulate_batch
from pytest_navscenario.sim.body_world import rides_the_ground
from pytest_navscenario.sim.episode import simulate
from pytest_navscenario.subjects.planners.dwa import DynamicWindowPlanner
from pytest_navscenario.subjects.protocol import is_batch_planner

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ARRAYS = ("t", "pose", "velocity", "tick_t", "command", "ranges")


def shipped() -> list:
    out = []
    for path in sorted(glob.glob(os.path.join(ROOT, "scenarios", "*.yaml"))):
        sc = load_scenario(path)
        if not rides_the_ground(sc):
            out.append(sc)
    return out


def same_episode(a, b) -> bool:
    ta, tb = a.trajectory, b.trajectory
    return (all(getattr(ta, k).tobytes() == getattr(tb, k).tobytes() and getattr(ta, k).shape == getattr(tb, k).shape
                for k in ARRAYS)
            and (a.end, a.ticks, a.collision, a.safety_stop, ta.waypoint_times)
            == (b.end, b.ticks, b.collision, b.safety_stop, tb.waypoint_times))


def alone_and_batched(scenarios, seeds, **kw):
    alone = [simulate(s, DynamicWindowPlanner(), seed, **kw) for s, seed in zip(scenarios, seeds)]
    batched = simulate_batch([BatchEpisode(s, seed, **kw) for s, seed in zip(scenarios, seeds)],
                             DynamicWindowPlanner())
    return alone, batched


def test_dwa_answers_the_batch_protocol():
    assert is_batch_planner(DynamicWindowPlanner())


def test_batched_dwa_gives_every_shipped_seed_its_own_commands_bit_for_bit():
    scenarios = shipped()
    assert len(scenarios) >= 5
    alone, batched = alone_and_batched(scenarios, [s.simulation.seed for s in scenarios])
    differ = [s.name for s, a, b in zip(scenarios, alone, batched) if not same_episode(a, b)]
    assert not differ
    assert len({a.ticks for a in alone}) > 1      # the episodes ended at different ticks


@pytest.mark.heavy
def test_batched_dwa_matches_alone_on_search_candidates():
    """The candidates a short search simulates (obstacles moved, inserted and removed), its
    failures among them, and a layout a squeeze once drew: a box touching the footprint at the
    start beside another (a collision in the first tick; dwa's own searches rarely collide, so it is written out
    rather than left to the search's draws)."""
    from pytest_navscenario.scenario.model import BoxObstacle
    from pytest_navscenario.search.engine import run_search

    seed = load_scenario(os.path.join(ROOT, "scenarios", "cylinders.yaml"))
    report = run_search(seed, DynamicWindowPlanner, budget=24, seed_value=3, shrink_budget=0)
    touching = dataclasses.replace(seed, obstacles=(
        *seed.obstacles, BoxObstacle(name="behind", x=-0.4947, y=0.0, length=0.4601, width=0.4601, height=1.0),
        BoxObstacle(name="touching", x=0.3058, y=0.7303, length=0.4591, width=0.4591, yaw=42.6565, height=1.0)))
    cands = [c.scenario for c in report.candidates] + [touching]
    alone, batched = alone_and_batched(cands, [0] * len(cands), stuck_after=15.0)
    assert [same_episode(a, b) for a, b in zip(alone, batched)] == [True] * len(cands)
    assert {"goal", "collision"} <= {a.end for a in alone}     # a collision: a tick stepped again alone


def _robot(sc, **parts):
    robot = sc.robot
    changes = {k: dataclasses.replace(getattr(robot, k), **v) if isinstance(v, dict) else v for k, v in parts.items()}
    return dataclasses.replace(sc, robot=dataclasses.replace(robot, **changes))


def test_batched_dwa_matches_alone_on_a_mixed_batch():
    """Different lidars (beam counts, a partial fov, noise), drives, footprints and a goal yaw in
    one batch: each episode still gets its own commands."""
    boxes1, corridor = (load_scenario(os.path.join(ROOT, "scenarios", f"{n}.yaml")) for n in ("boxes1", "corridor"))
    yaw_goal = dataclasses.replace(boxes1.mission, goal_tolerance=dataclasses.replace(
        boxes1.mission.goal_tolerance, yaw=10.0))
    mixed = [
        boxes1,
        _robot(boxes1, lidar={"beams": 36}),
        _robot(corridor, lidar={"beams": 31, "fov": 120.0}),
        _robot(boxes1, lidar={"noise_sigma": 0.03, "dropout": 0.05}),
        _robot(corridor, drive="diff"),
        _robot(boxes1, footprint=dataclasses.replace(boxes1.robot.footprint, shape="circle", radius=0.35)),
        dataclasses.replace(boxes1, mission=yaw_goal),
    ]
    alone, batched = alone_and_batched(mixed, [0, 1, 2, 3, 4, 5, 6])
    assert [same_episode(a, b) for a, b in zip(alone, batched)] == [True] * len(mixed)
