"""Opt-in perturbations of an episode (``simulation.perturb``, issue 29): each episode draws its
start pose and moving obstacles' timing from its noise seed, within the declared bounds, never
onto an obstacle; absent, nothing changes (files, hashes and episodes stay as they were)."""
from __future__ import annotations

import math

import pytest

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.dump import dump_scenario
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.scenario.model import content_hash, randomness
from pytest_navscenario.scenario.perturb import perturbed

BASE = """version: 1
mission: {start: {x: 0, y: 0, yaw: 0}, goal: {x: 4, y: 0, yaw: 0}, timeout: 12}
obstacles:
  - {type: box, name: wall, x: 0.0, y: 0.62, length: 1.0, width: 0.2}
  - {type: cylinder, name: walker, radius: 0.25,
     motion: {path: [[2.0, -2.0], [2.0, 2.0]], speed: 1.0, start: 0.5}}
"""
PERTURB = "simulation: {perturb: {start_xy: 0.3, start_yaw: 10, motion_time: 2.0}}\n"


def test_each_seed_draws_its_own_start_and_timing_within_the_bounds_and_off_obstacles():
    s = loads_scenario(BASE + PERTURB, "p.yaml")
    assert randomness(s) == ("start perturbation", "timing perturbation")
    draws = [perturbed(s, seed) for seed in range(200)]
    assert perturbed(s, 7) == perturbed(s, 7)                              # a pure function of the seed
    starts = {(d.mission.start.x, d.mission.start.y, d.mission.start.yaw) for d in draws}
    assert len(starts) == 200
    for d in draws:
        start = d.mission.start
        assert abs(start.x) <= 0.3 and abs(start.y) <= 0.3 and abs(start.yaw) <= 10
        assert not (abs(start.x) <= 0.5 + 0.45 and start.y + 0.25 >= 0.52)   # never onto the wall (y >= 0.52)
        assert 0.0 <= d.obstacle("walker").motion.start <= 2.5
        assert d.obstacle("wall") == s.obstacle("wall")
    assert min(d.obstacle("walker").motion.start for d in draws) == 0.0      # clamped at 0, never before
    assert max(abs(d.mission.start.y) for d in draws) > 0.2


def test_absent_it_changes_nothing_and_it_round_trips():
    plain = loads_scenario(BASE, "b.yaml")
    assert perturbed(plain, 5) is plain and randomness(plain) == ()
    s = loads_scenario(BASE + PERTURB, "p.yaml")
    assert loads_scenario(dump_scenario(s), "p.yaml") == s
    assert "perturb" not in dump_scenario(plain)
    assert content_hash(s) != content_hash(plain)


def test_the_episode_runs_judges_and_reports_the_perturbed_draw():
    s = loads_scenario(BASE + PERTURB, "p.yaml")
    a, b = run_scenario(s, "dwa", seed=1), run_scenario(s, "dwa", seed=2)
    assert a.scenario is s                                   # reported as written: its hash pairs results
    first = [tuple(r.trajectory.pose[0][:2]) for r in (a, b)]
    assert first[0] != first[1] and all(math.hypot(*p) > 0 for p in first)
    again = run_scenario(s, "dwa", seed=1)
    assert (again.trajectory.pose == a.trajectory.pose).all() and again.outcome == a.outcome


@pytest.mark.parametrize("text, message", [
    ("simulation: {perturb: {start_xy: 2}}\n", "simulation.perturb.start_xy: must be <= 1"),
    ("simulation: {perturb: {start_yaw: -1}}\n", "simulation.perturb.start_yaw: must be >= 0"),
    ("simulation: {perturb: {timing: 1}}\n", "unknown key 'timing'"),
])
def test_bad_perturbations_are_scenario_errors_with_the_line(text, message):
    with pytest.raises(ScenarioError, match=message.replace(".", r"\.").replace("(", r"\(")) as info:
        loads_scenario(BASE + text, "p.yaml")
    assert info.value.line == 7
