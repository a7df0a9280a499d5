"""The wheeled body on real MuJoCo terrain: a straight-driving planner climbs a 10 degree ramp,
crosses a low threshold, stalls at a step taller than it can climb, falls into a pit and off a
loading dock, tips on a steep side slope; the planar world is untouched."""
import dataclasses
import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.scenario.ground import surface as ground
from pytest_navscenario.scenario.model import BoxObstacle, Footprint, Mission, Pose, Robot, Safety, Scenario
from pytest_navscenario.scenario.bodies import WheeledBody
from pytest_navscenario.scenario.terrain import Pit, Platform, Ramp, Steps
from pytest_navscenario.sim.episode import simulate

sys.path.insert(0, str(Path(__file__).parents[1] / "search"))
from straight_planner import Straight  # noqa: E402


def scene(terrain, *, body=WheeledBody(clearance=0.1), start=(0.0, 0.0, 0.0), goal=(12.0, 0.0),
          footprint=Footprint(), obstacles=(), timeout=20.0, safety=True):
    return Scenario(mission=Mission(start=Pose(*start), goal=Pose(*goal), timeout=timeout),
                    terrain=tuple(terrain), obstacles=tuple(obstacles),
                    robot=Robot(footprint=footprint, drive="diff", body=body, safety=Safety(enabled=safety)))


def ramp_to(deg: float, length: float = 4.0) -> tuple:
    rise = length * math.tan(math.radians(deg))
    return (Ramp("ramp", 5.0, 0.0, length=length, width=3.0, rise=rise),
            Platform("top", 5.0 + length / 2 + 3.0, 0.0, length=6.0, width=3.0, height=rise))


def test_it_climbs_a_10_degree_ramp_onto_the_upper_level_and_a_slope_slows_it():
    res = simulate(scene(ramp_to(10.0), goal=(10.0, 0.0)), Straight(), 0)
    traj = res.trajectory
    assert res.end == "goal", (res.end, res.terrain_event)
    rise = 4.0 * math.tan(math.radians(10.0))
    assert traj.z[-1] == pytest.approx(rise, abs=0.02)           # on the upper level, really
    on_ramp = (traj.pose[:, 0] > 3.6) & (traj.pose[:, 0] < 6.4)
    assert 8.0 < math.degrees(-traj.pitch[on_ramp].mean()) < 16.0  # nose up (the casters' springs add a few)
    flat = traj.pose[:, 0] < 2.0
    assert traj.velocity[on_ramp, 0].mean() < traj.velocity[flat & (traj.t > 1.5), 0].mean()


def test_a_ramp_steeper_than_its_torque_allows_stalls_it_as_stuck_on_terrain():
    res = simulate(scene(ramp_to(25.0)), Straight(), 0)
    assert res.end == "stuck-terrain"
    assert res.terrain_event.kind == "stuck" and res.terrain_event.element == "ramp 'ramp'"
    assert "slope" in res.terrain_event.detail or "step" in res.terrain_event.detail


def test_it_crosses_a_low_threshold_and_stalls_at_a_step_its_casters_cannot_climb():
    low = simulate(scene([Steps("sill", 5.0, 0.0, count=1, rise=0.03, run=0.3, width=3.0)]), Straight(), 0)
    assert low.end == "goal"
    high = simulate(scene([Platform("kerb", 7.0, 0.0, length=4.0, width=3.0, height=0.15)],
                          body=WheeledBody(clearance=0.2)), Straight(), 0)
    assert high.end == "stuck-terrain"
    event = high.terrain_event
    assert event.element == "platform 'kerb'" and event.detail == "cannot climb the 0.15 m step"
    assert event.x == pytest.approx(5.0 - 0.45, abs=0.05)         # its front at the kerb's face
    assert event.time < 10.0


def test_it_falls_into_a_pit_and_off_a_loading_dock_with_the_drop():
    pit = simulate(scene([Pit("hole", 5.0, 0.0, length=2.0, width=3.0, depth=1.0)]), Straight(), 0)
    assert pit.end == "fell"
    assert pit.terrain_event.element == "into pit 'hole'" and pit.terrain_event.drop == pytest.approx(1.0)
    assert 4.0 < pit.terrain_event.x < 6.0 and pit.trajectory.z[-1] < -0.09   # really below the floor
    dock = simulate(scene([Platform("dock", 0.0, 0.0, length=6.0, width=4.0, height=1.2)]), Straight(), 0)
    assert dock.end == "fell" and dock.terrain_event.element == "off platform 'dock'"
    assert dock.terrain_event.drop == pytest.approx(1.2) and dock.trajectory.z[0] > 1.19


def test_it_tips_over_on_a_steep_side_slope_and_not_on_a_gentle_one():
    # a robot carrying its load high (its mass 0.3 m up, its wheels 0.35 m apart: it tips past ~30 deg)
    def bank(deg, com_height=0.3):
        rise = 6.0 * math.tan(math.radians(deg))
        return scene([Ramp("bank", 5.0, 0.0, length=6.0, width=10.0, rise=rise, yaw=90.0)],
                     start=(2.0, 0.5, 0.0), goal=(9.0, 0.5), footprint=Footprint(length=0.9, width=0.4),
                     body=WheeledBody(com_height=com_height))
    steep = simulate(bank(38.0), Straight(), 0)
    assert steep.end == "tipped" and steep.terrain_event.element == "ramp 'bank'"
    assert abs(steep.terrain_event.roll) > 45.0
    gentle = simulate(bank(12.0), Straight(), 0)
    assert gentle.end != "tipped" and np.degrees(np.abs(gentle.trajectory.roll)).max() < 20.0
    # the default body carries its mass at its axle: on the same bank it slides and stalls, upright
    low = simulate(bank(38.0, com_height=None), Straight(), 0)
    assert low.end == "stuck-terrain" and np.degrees(np.abs(low.trajectory.roll)).max() < 45.0


def test_the_chassis_hitting_an_obstacle_on_a_ramp_is_a_collision_and_the_obstacle_stands_on_it():
    crate = BoxObstacle("crate", 6.0, 0.0, 0.5, 0.5)
    sc = scene([Ramp("ramp", 5.0, 0.0, length=4.0, width=3.0, rise=0.4)], obstacles=[crate])
    sc = Scenario(mission=sc.mission, terrain=sc.terrain, obstacles=sc.obstacles,
                  robot=Robot(footprint=sc.robot.footprint, drive="diff", body=sc.robot.body,
                              safety=sc.robot.safety.__class__(enabled=False)))
    res = simulate(sc, Straight(), 0)
    assert res.end == "collision" and res.collision.obstacle == "crate" and not res.collision.terrain
    from pytest_navscenario.sim.world import compiled_world
    world = compiled_world(sc)
    gid = next(iter(world.obstacle_of_geom))
    bottom = world.model.geom_pos[gid][2] - world.model.geom_size[gid][2]
    assert bottom == pytest.approx(float(ground.ground_height(sc, 6.25, 0.25)), abs=1e-9)


def test_the_chassis_driving_into_a_platform_face_is_a_collision_with_the_terrain():
    # (the safety layer off: it would halt before the face, tests/sim/test_terrain_safety.py)
    res = simulate(scene([Platform("wall", 4.0, 0.0, length=1.0, width=3.0, height=0.6)],
                         body=WheeledBody(clearance=0.1), safety=False), Straight(), 0)
    assert res.end == "collision" and res.collision.terrain and res.collision.obstacle == "platform 'wall'"


# A frozen loading-dock failure (tutorial 5's search): dwa drives along the dock 5 cm inside its
# edge, a wheel drops off, the chassis rolls over the edge. MuJoCo 4.0.0 called it a tip-over,
# 4.0.1 a "collision with the face of platform 'dock'" (the chassis on the edge's corner, 0.06 s
# before the roll passed 45 deg): the verdict must not hang on which comes first.
DOCK_EDGE = """version: 1
robot:
  footprint: {shape: box, length: 0.9, width: 0.5}
  drive: diff
  body: {type: wheeled}
mission: {start: {x: 0, y: 0}, goal: {x: 10, y: 0}, timeout: 30}
obstacles:
  - {type: box, name: pallet_a, x: 2.0953, y: 0.6934, length: 1.1927, width: 0.7927, yaw: -16.7896, height: 1.0}
  - {type: box, name: pallet_b, x: 7.5607, y: 0.829, length: 1.2602, width: 0.8602, yaw: -7.3457, height: 1.0}
terrain:
  - {type: platform, name: dock, x: 4.9151, y: 0.5532, length: 14.0, width: 3.0, height: 1.1939}
"""


def test_going_over_the_side_edge_of_the_dock_it_drives_on_is_not_a_collision_with_its_face():
    """The edge of the ground the robot stands on is what it goes over, not terrain it drove into
    (that rises above it, as the test above): the same verdict under every MuJoCo patch release.
    With the wheel-speed loop's integral action (issue 36.1) the robot hangs tilted over the edge
    with a wheel off it (it rolled over it before): a level platform's side is named as an edge,
    not "the 0.0 deg slope of platform 'dock'"."""
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.scenario.loader import loads_scenario
    from pytest_navscenario.verdict.result import Outcome

    res = run_scenario(loads_scenario(DOCK_EDGE), "dwa")
    assert res.outcome is not Outcome.COLLISION, res.message
    assert re.search(r"tilted \d+ deg over the side edge of platform 'dock'", res.message), res.message


def test_the_planar_body_refuses_terrain_and_a_wheeled_body_refuses_omni_drive():
    sc = scene([Pit("hole", 5.0, 0.0, length=2.0, width=3.0, depth=1.0)])
    planar = Scenario(mission=sc.mission, terrain=sc.terrain)
    with pytest.raises(ScenarioError, match="planar body .* cannot ride terrain"):
        simulate(planar, Straight(), 0)
    omni = Scenario(mission=sc.mission, robot=Robot(drive="omni", body=WheeledBody()))
    with pytest.raises(ScenarioError, match="robot.drive: a wheeled body cannot drive 'omni'"):
        simulate(omni, Straight(), 0)


def test_same_bits_twice():
    sc = scene(ramp_to(10.0), goal=(10.0, 0.0))
    a, b = simulate(sc, Straight(), 0), simulate(sc, Straight(), 0)
    for name in ("pose", "velocity", "z", "roll", "pitch", "command"):
        assert getattr(a.trajectory, name).tobytes() == getattr(b.trajectory, name).tobytes()


def test_the_verdict_names_what_happened_where_and_the_metrics_see_height():
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.verdict.result import Outcome

    dock = run_scenario(scene([Platform("dock", 0.0, 0.0, length=6.0, width=4.0, height=1.2)]), Straight)
    assert dock.outcome is Outcome.FALL
    assert dock.message.startswith("fell off platform 'dock' at t=3.") and "1.2 m drop" in dock.message
    stuck = run_scenario(scene([Platform("kerb", 7.0, 0.0, length=4.0, width=3.0, height=0.15)],
                               body=WheeledBody(clearance=0.2)), Straight)
    assert stuck.outcome is Outcome.TIMEOUT
    assert "stuck on terrain at t=" in stuck.message and "cannot climb the 0.15 m step of platform 'kerb'" in stuck.message
    bank = run_scenario(scene([Ramp("bank", 5.0, 0.0, length=6.0, width=10.0, rise=6.0 * math.tan(math.radians(38)),
                                    yaw=90.0)], start=(2.0, 0.5, 0.0), goal=(9.0, 0.5),
                              footprint=Footprint(length=0.9, width=0.4), body=WheeledBody(com_height=0.3)),
                        Straight)
    assert bank.outcome is Outcome.FALL and bank.message.startswith("tipped over on ramp 'bank'")
    up = run_scenario(scene(ramp_to(10.0), goal=(10.0, 0.0)), Straight)
    assert up.outcome is Outcome.SUCCESS
    m = up.metrics
    assert 8.0 < m.max_pitch < 20.0 and m.climb == pytest.approx(4.0 * math.tan(math.radians(10.0)), abs=0.03)
    xy = np.hypot(*np.diff(up.trajectory.pose[:, :2], axis=0).T).sum()
    assert m.path_length > xy                    # over the ground: the climb counts
    wall = run_scenario(scene([Platform("wall", 4.0, 0.0, length=1.0, width=3.0, height=0.6)], safety=False),
                        Straight)
    assert wall.outcome is Outcome.COLLISION and wall.message.startswith("collision with the face of platform 'wall'")


def test_a_heightfield_dipping_below_the_floor_cuts_a_hole_in_it(tmp_path):
    """A hollow 0.3 m deep in a height file: the floor has a hole over it, so the robot drives down
    into it (the ground function and MuJoCo agree), instead of riding over a floor at z = 0."""
    from pytest_navscenario.scenario.terrain import Heightfield
    from pytest_navscenario.sim.body_world import compiled_body_world

    u = np.linspace(-1.0, 1.0, 41)
    bowl = -0.3 * np.clip(1.0 - (u[None, :] ** 2 + u[:, None] ** 2), 0.0, None) ** 2
    np.save(tmp_path / "bowl.npy", bowl)
    el = Heightfield("bowl", 5.0, 0.0, file="bowl.npy", length=4.0, width=4.0, min_height=-0.3, max_height=0.0)
    sc = scene([el])
    sc = Scenario(mission=sc.mission, terrain=sc.terrain, robot=sc.robot, source=str(tmp_path / "s.yaml"))
    assert float(ground.ground_height(sc, 5.0, 0.0)) == pytest.approx(-0.3, abs=0.01)
    assert ground.lowest(sc) == pytest.approx(-0.3, abs=0.01)
    floor = [g for g, e in compiled_body_world(sc).terrain_of_geom.items() if e == -1]
    assert len(floor) > 1                                     # slabs round the hole, not one plane
    res = simulate(sc, Straight(), 0)
    assert res.trajectory.z.min() < -0.2 and res.trajectory.pose[-1, 0] > 9.0   # down into it, and out


class Slow:
    """Drives straight along +x at 0.25 m/s."""

    def reset(self, scenario):
        pass

    def act(self, obs):
        return (0.25, 0.0, 0.0)


def test_caught_in_a_trench_it_names_the_gap_and_the_pit():
    """#36: a robot whose wheels drop into a 0.15 m trench across its way is stuck in a gap of
    0.15 m of that pit, not at 'the 1.00 m step' of no element (the trench's far wall)."""
    trench = Pit("trench", 2.075, 0.0, length=0.15, width=3.0, depth=1.0)
    res = simulate(scene([trench], goal=(4.0, 0.0)), Slow(), 0)
    assert res.end == "stuck-terrain", res.end
    event = res.terrain_event
    assert event.element == "pit 'trench'"
    assert event.detail == "its wheels are caught in the 0.15 m gap"


def test_off_a_ramps_side_it_names_the_ramp_not_a_slope_it_cannot_climb():
    """#36: driven 8 cm inside the side edge of a 6.2 deg ramp, a wheel drops off the side. It said
    'cannot climb the 11 deg slope' (the body's own tilt, stalled); with the wheel-speed loop's
    integral action the robot slides off the ramp's side onto the floor and scrapes the side of the
    upper level: the verdict names the terrain it met, never a slope the ramp does not have."""
    rise = 4.0 * math.tan(math.radians(6.2))
    terrain = (Ramp("ramp", 5.0, 0.0, length=4.0, width=2.0, rise=rise),
               Platform("top", 10.0, 0.0, length=6.0, width=2.0, height=rise))
    res = simulate(scene(terrain, start=(0.0, 0.92, 0.0), goal=(10.0, 0.92)), Straight(), 0)
    assert res.end in ("collision", "fell"), res.end
    assert res.trajectory.pose[-1, 1] > 1.0 + 0.2       # off the ramp's side (at y = 1), on the floor
    named = res.collision.obstacle if res.end == "collision" else res.terrain_event.element
    assert named in ("ramp 'ramp'", "platform 'top'")


@pytest.mark.parametrize("height", [0.15])
def test_hung_over_an_edge_it_names_the_edge_not_a_slope_it_cannot_climb(height):
    """Driven slowly off a 0.15 m edge, the 0.9 m body stalls across it, nose down on flat
    ground: it did not meet a slope it cannot climb (it said "cannot climb the 15 deg slope"), it
    hangs over the edge of the platform it drove off (issue 36.3). (Off a 0.2 m edge it stalled
    too until the wheel-speed loop held its speed under load, issue 36.1: it now drives on and
    falls off, the next test.)"""
    from pytest_navscenario.scenario.robot import Limits
    sc = scene([Platform("upper", 0.0, 0.0, length=2.0, width=1.0, height=height)], body=WheeledBody(),
               goal=(2.5, 0.0))
    sc = dataclasses.replace(sc, robot=dataclasses.replace(sc.robot, limits=Limits(max_speed=0.3)))
    res = simulate(sc, Straight(), 0)
    assert res.end == "stuck-terrain"
    event = res.terrain_event
    assert "cannot climb" not in event.detail
    assert re.fullmatch(rf"pitched \d+ deg over the {height:.2f} m edge", event.detail), event.detail
    assert event.element == "platform 'upper'"


def test_driven_on_over_a_02_m_edge_it_falls_off_the_platform():
    """The wheel-speed loop holds the commanded 0.3 m/s with the nose down over a 0.2 m edge, so the
    body goes over it: a fall off the platform it drove off, named, with the drop."""
    from pytest_navscenario.scenario.robot import Limits
    sc = scene([Platform("upper", 0.0, 0.0, length=2.0, width=1.0, height=0.2)], body=WheeledBody(),
               goal=(2.5, 0.0))
    sc = dataclasses.replace(sc, robot=dataclasses.replace(sc.robot, limits=Limits(max_speed=0.3)))
    res = simulate(sc, Straight(), 0)
    assert res.end == "fell"
    assert res.terrain_event.element == "off platform 'upper'"
    assert res.terrain_event.drop == pytest.approx(0.2, abs=0.03)
