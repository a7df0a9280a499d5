"""The built-in planners on the five seed scenarios and on hand-made cases, in real MuJoCo."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry import Point

from pytest_navscenario.scenario.geometry import footprint_polygon
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.subjects.protocol import Command, Observation
from pytest_navscenario.subjects.loading import load_subject
from pytest_navscenario.subjects.planners import DynamicWindowPlanner, PotentialFieldPlanner
from pytest_navscenario.subjects.planners.dwa import footprint_distance
from pytest_navscenario.verdict.result import Outcome
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.model import BoxObstacle, Footprint, GoalTolerance, Limits, Mission, Pose, Robot, Scenario

SEEDS_DIR = Path(__file__).resolve().parents[2] / "scenarios"
SEEDS = ["boxes1", "boxes2", "corridor", "cylinders", "L-corridor"]


@pytest.fixture(scope="module")
def seeds() -> dict[str, Scenario]:
    return {name: load_scenario(SEEDS_DIR / f"{name}.yaml") for name in SEEDS}


class Recording:
    """Wraps a planner and keeps its raw answers (before the drive's limits clip them)."""

    def __init__(self, inner):
        self.inner, self.answers = inner, []

    def reset(self, scenario):
        self.inner.reset(scenario)

    def act(self, obs):
        answer = self.inner.act(obs)
        self.answers.append(answer)
        return answer


def test_seed_files_are_the_papers_ten_metre_task(seeds):
    for name, s in seeds.items():
        assert (s.mission.start.x, s.mission.start.y, s.mission.start.yaw) == (0.0, 0.0, 90.0), name
        assert (s.mission.goal.x, s.mission.goal.y, s.mission.goal.yaw) == (0.0, 10.0, 90.0), name
        assert s.robot == Robot(), f"{name}: the seeds use the default (ANYmal-like) robot"
        assert (SEEDS_DIR / f"{name}.yaml").read_text().startswith("# "), "comment on what it tests"


@pytest.mark.parametrize("name", SEEDS)
def test_dwa_succeeds_on_every_seed(seeds, name):
    result = run_scenario(seeds[name], "dwa")
    assert result.outcome is Outcome.SUCCESS, result.message
    assert result.metrics.min_clearance > 0.2   # footprint-aware: never brushes an obstacle


def test_potential_field_fails_boxes2_by_a_safety_stop_but_passes_open_gaps(seeds):
    # reacts only within 1 m and does not slow down: drives at the box on the straight line
    result = run_scenario(seeds["boxes2"], "potential-field")
    assert result.outcome is Outcome.SAFETY_STOP, result.message
    assert result.safety_stop.obstacle == "box_near"
    assert run_scenario(seeds["boxes1"], "potential-field").outcome is Outcome.SUCCESS


def narrowed(scenario: Scenario, gap: float) -> Scenario:
    """boxes1 with the two boxes moved towards each other until their faces are ``gap`` apart."""
    shift = (2.0 - gap) / 2.0
    return dataclasses.replace(scenario, obstacles=tuple(
        dataclasses.replace(o, x=o.x - math.copysign(shift, o.x)) for o in scenario.obstacles))


def test_potential_field_stalls_in_a_gap_under_one_and_a_half_metres_where_dwa_passes(seeds):
    tight = narrowed(seeds["boxes1"], 1.3)
    pf = run_scenario(tight, "potential-field")
    assert pf.outcome is Outcome.TIMEOUT, pf.message
    assert pf.trajectory.pose[-1, 1] < 5.0        # stuck in front of the gap
    dwa = run_scenario(tight, "dwa")
    assert dwa.outcome is Outcome.SUCCESS, dwa.message


def small_scenario(**mission_kw) -> Scenario:
    kw = dict(start=Pose(0.0, 0.0, 90.0), goal=Pose(0.0, 3.0, 90.0), timeout=15.0)
    kw.update(mission_kw)
    return Scenario(mission=Mission(**kw), name="small")


@pytest.mark.parametrize("spec", ["dwa", "potential-field"])
def test_yaw_rates_are_converted_from_degrees_and_limits_respected(spec):
    robot = Robot(limits=Limits(max_speed=0.6, max_lateral_speed=0.2, max_yaw_rate=30.0))
    scenario = dataclasses.replace(small_scenario(goal=Pose(-2.0, -1.0, 0.0)), robot=robot)
    rec = Recording(load_subject(spec)())
    result = run_scenario(scenario, rec)
    answers = np.array([tuple(a) for a in rec.answers])
    assert np.all(np.abs(answers[:, 2]) <= math.radians(30.0) + 1e-9)   # rad/s, not deg/s
    assert np.all(np.abs(answers[:, 1]) <= 0.2 + 1e-9)
    assert np.all(answers[:, 0] <= 0.6 + 1e-9)
    assert np.abs(answers[:, 2]).max() > math.radians(25.0)   # it did turn (goal behind it)
    assert result.outcome is Outcome.SUCCESS, result.message


def test_dwa_with_a_differential_drive_never_strafes_and_reaches_a_goal_to_the_side():
    scenario = dataclasses.replace(small_scenario(goal=Pose(2.0, 1.0, 0.0)), robot=Robot(drive="diff"))
    rec = Recording(DynamicWindowPlanner())
    result = run_scenario(scenario, rec)
    assert result.outcome is Outcome.SUCCESS, result.message
    assert all(a.vy == 0.0 for a in rec.answers)


@pytest.mark.parametrize("spec", ["dwa", "potential-field"])
def test_turns_to_the_goal_yaw_when_the_mission_checks_it(spec):
    scenario = small_scenario(goal=Pose(0.0, 3.0, 0.0), goal_tolerance=GoalTolerance(0.3, 10.0))
    result = run_scenario(scenario, spec)
    assert result.outcome is Outcome.SUCCESS, result.message
    assert abs(result.metrics.goal_yaw_error) <= 10.0


def observation(ranges: np.ndarray, angles: np.ndarray, goal=(0.0, 5.0), velocity=(0.0, 0.0, 0.0)):
    return Observation(tick=0, time=0.0, pose=np.array([0.0, 0.0, math.pi / 2]),
                       velocity=np.array(velocity, dtype=float), ranges=ranges.astype(np.float32),
                       angles=angles, goal=np.array([goal[0], goal[1], math.pi / 2]),
                       waypoints=np.zeros((0, 2)), obstacles=())


def wall_ranges(angles: np.ndarray, distance: float, range_max: float = 8.0) -> np.ndarray:
    """Lidar ranges of an infinite wall ``distance`` ahead of the robot (robot frame +x)."""
    with np.errstate(divide="ignore"):
        r = np.where(np.cos(angles) > 1e-6, distance / np.cos(angles), range_max)
    return np.minimum(r, range_max)


def test_dwa_does_not_drive_into_a_wall_right_ahead_but_drives_on_in_the_open():
    scenario = small_scenario(goal=Pose(0.0, 5.0, 90.0))
    angles = np.linspace(-math.pi, math.pi, 72, endpoint=False)
    planner = DynamicWindowPlanner()
    planner.reset(scenario)
    blocked = planner.act(observation(wall_ranges(angles, 0.7), angles, velocity=(0.4, 0.0, 0.0)))
    assert isinstance(blocked, Command)
    assert blocked.vx < 0.4                         # brakes: the wall is 0.25 m from its nose
    planner.reset(scenario)
    free = planner.act(observation(np.full(72, 8.0), angles, velocity=(0.4, 0.0, 0.0)))
    assert free.vx > 0.4 and abs(free.wz) < 1e-9    # accelerates straight at the goal


def test_footprint_distance_matches_shapely_for_box_and_circle():
    rng = np.random.default_rng(1)
    pts = rng.uniform(-2, 2, size=(200, 2))
    x, y, th = 0.3, -0.2, 0.7
    for fp in (Footprint("box", 0.9, 0.5), Footprint("circle", radius=0.3)):
        poly = footprint_polygon(fp, x, y, th)
        want = np.array([poly.distance(Point(p)) for p in pts])
        if fp.shape == "box":
            got = footprint_distance(pts[:, 0], pts[:, 1], x, y, th, 0.45, 0.25)
        else:
            got = footprint_distance(pts[:, 0], pts[:, 1], x, y, th, 0.0, 0.0, 0.3)
        assert np.allclose(got, want, atol=2e-3)    # shapely's circle is a 64-gon


def test_planners_explain_act_before_reset():
    angles = np.linspace(-math.pi, math.pi, 8, endpoint=False)
    for planner in (DynamicWindowPlanner(), PotentialFieldPlanner()):
        with pytest.raises(RuntimeError, match=r"before reset\(scenario\)"):
            planner.act(observation(np.full(8, 8.0), angles))


def test_the_same_planner_object_can_run_several_episodes_and_gives_the_same_bits(seeds):
    planner = DynamicWindowPlanner()
    first = run_scenario(seeds["cylinders"], planner)
    again = run_scenario(seeds["cylinders"], planner)
    assert np.array_equal(first.trajectory.pose, again.trajectory.pose)
    assert first.outcome is Outcome.SUCCESS


def test_dwa_detours_around_a_box_centred_on_the_line_instead_of_stalling_in_front_of_it(seeds):
    s = seeds["boxes2"]
    centred = dataclasses.replace(s, obstacles=(dataclasses.replace(s.obstacles[0], x=0.0),) + s.obstacles[1:])
    # plain DWA (no detour lanes, no stall recovery): the local minimum in front of the box
    stalled = run_scenario(centred, DynamicWindowPlanner(lookahead=0.0, stall_time=0.0))
    assert stalled.outcome is Outcome.TIMEOUT and stalled.trajectory.pose[-1, 1] < 3.5
    detour = run_scenario(centred, DynamicWindowPlanner())
    assert detour.outcome is Outcome.SUCCESS, detour.message
    assert detour.metrics.min_clearance > 0.2


def test_dwa_shares_precomputed_rollouts_only_between_identical_settings(seeds):
    a, b, c = DynamicWindowPlanner(), DynamicWindowPlanner(), DynamicWindowPlanner(turn_weight=0.5)
    for planner in (a, b, c):
        planner.reset(seeds["boxes1"])
    assert a._t is b._t and a._t is not c._t


def test_dwa_brakes_in_front_of_a_dead_end_instead_of_running_into_the_safety_layer(seeds):
    s = seeds["corridor"]
    dead_end = dataclasses.replace(
        s, obstacles=s.obstacles + (BoxObstacle("cap", 0.0, 7.6, 2.4, 0.2),),
        mission=dataclasses.replace(s.mission, timeout=12.0))
    result = run_scenario(dead_end, DynamicWindowPlanner(stall_time=0.0))   # no stall recovery
    assert result.outcome is Outcome.TIMEOUT, result.message        # not a safety stop
    assert result.safety_stop is None and result.collision is None
    last_3s = result.trajectory.pose[-300:, :2]
    assert np.ptp(last_3s, axis=0).max() < 0.1                       # it has stopped
    nose = result.trajectory.pose[:, 1].max() + 0.45
    assert nose < 7.5 - 0.2                                           # well short of the cap
    # with stall recovery (the default) it backs out of the dead end again, just as safely
    escaped = run_scenario(dead_end, "dwa")
    assert escaped.safety_stop is None and escaped.collision is None, escaped.message
    assert escaped.trajectory.pose[:, 1].max() + 0.45 < 7.5 - 0.2
    y = escaped.trajectory.pose[:, 1]
    assert y[-1] < y.max() - 0.4                                      # on its way back out


def test_dwa_escapes_the_corner_of_a_jittered_l_corridor_where_plain_dwa_stalls(seeds):
    # examples/pictures/suite/L-corridor/L-corridor-v07.yaml: the straight line to the waypoint
    # at the bend crosses the first leg's inner wall, so plain DWA stops at the corridor's mouth
    s = seeds["L-corridor"]
    layout = {"leg1_outer": (4.326, 3.182, 45.0), "leg1_inner": (1.98, 3.692, 64.8),
              "leg2_outer": (4.652, 7.231, 145.31), "leg2_inner": (1.957, 6.508, 146.43)}
    jittered = dataclasses.replace(s, obstacles=tuple(
        dataclasses.replace(o, x=layout[o.name][0], y=layout[o.name][1], yaw=layout[o.name][2])
        for o in s.obstacles))
    stalled = run_scenario(jittered, DynamicWindowPlanner(stall_time=0.0))
    assert stalled.outcome is Outcome.TIMEOUT and not stalled.trajectory.waypoint_times
    result = run_scenario(jittered, DynamicWindowPlanner())
    assert result.outcome is Outcome.SUCCESS, result.message
    assert result.metrics.min_clearance > 0.15


def test_a_factory_that_calls_sys_exit_is_a_load_error_not_the_end_of_the_run():
    """Issue 15 item 2: sys.exit() in a planner's constructor is a SubjectLoadError."""
    import sys as _sys

    from pytest_navscenario.core.errors import SubjectLoadError
    from pytest_navscenario.subjects.loading import make_planner

    class Quits:
        def __init__(self):
            _sys.exit("no licence")

    with pytest.raises(SubjectLoadError, match="raised SystemExit: no licence"):
        make_planner(Quits)
