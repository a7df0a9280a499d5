"""The legged body (a capability model) on real MuJoCo terrain: it climbs the stairs the wheeled body
cannot, is stopped by a step above its max_step and by a slope above its max_slope, strides over a
gap up to max_gap and falls into a wider one, walks down stairs and falls off a dock; its volume
meets obstacles; a YAML scenario with ``type: legged`` runs."""
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.scenario.ground.crossing import Capability, walk
from pytest_navscenario.scenario.model import BoxObstacle, Footprint, Mission, Pose, Robot, Safety, Scenario
from pytest_navscenario.scenario.bodies import LeggedBody, WheeledBody
from pytest_navscenario.scenario.terrain import Pit, Platform, Ramp, Steps
from pytest_navscenario.sim.episode import simulate

sys.path.insert(0, str(Path(__file__).parents[1] / "search"))
from straight_planner import Straight  # noqa: E402

LEGGED = LeggedBody(max_step=0.2, max_slope=30.0, max_gap=0.3, clearance=0.35)


def scene(terrain, *, body=LEGGED, start=(0.0, 0.0, 0.0), goal=(8.0, 0.0), obstacles=(), drive="diff",
          safety=True):
    return Scenario(mission=Mission(start=Pose(*start), goal=Pose(*goal), timeout=30.0),
                    terrain=tuple(terrain), obstacles=tuple(obstacles),
                    robot=Robot(footprint=Footprint(), drive=drive, body=body, safety=Safety(enabled=safety)))


STAIRS = (Steps("stairs", 5.0, 0.0, count=5, rise=0.17, run=0.3, width=3.0),
          Platform("landing", 7.75, 0.0, length=4.0, width=3.0, height=0.85))


def test_the_legged_body_climbs_the_stairs_the_wheeled_one_cannot():
    legged = simulate(scene(STAIRS), Straight(), 0)
    assert legged.end == "goal"
    traj = legged.trajectory
    assert traj.z[-1] == pytest.approx(0.85, abs=1e-6)              # on the landing, really
    on_stairs = (traj.pose[:, 0] > 4.6) & (traj.pose[:, 0] < 5.9)
    assert math.degrees(-traj.pitch[on_stairs].min()) == pytest.approx(29.5, abs=1.0)   # nose up the flight
    assert np.all(np.diff(traj.z) > -1e-9)                            # it never sinks on the way up
    wheeled = simulate(scene(STAIRS, body=WheeledBody()), Straight(), 0)
    # the chassis meets the first riser, or the safety layer halts it before the second (its lidar's
    # plane meets the 0.34 m one): either way it does not climb
    assert wheeled.end in ("collision", "stuck-terrain", "safety-stop") and wheeled.trajectory.z.max() < 0.17


def test_a_step_above_max_step_stops_it_at_the_face_and_a_lower_one_does_not():
    # (the safety layer off: it would halt before the face, which its lidar's plane meets)
    high = simulate(scene([Platform("kerb", 7.0, 0.0, length=4.0, width=3.0, height=0.3)], safety=False), Straight(), 0)
    assert high.end == "stuck-terrain"
    event = high.terrain_event
    assert event.element == "platform 'kerb'" and event.detail == "cannot climb the 0.30 m step"
    assert event.x == pytest.approx(5.0 - 0.45, abs=0.03)             # its front feet at the face
    low = simulate(scene([Platform("kerb", 7.0, 0.0, length=4.0, width=3.0, height=0.18)]), Straight(), 0)
    assert low.end == "goal" and low.trajectory.z[-1] == pytest.approx(0.18, abs=1e-6)


def test_a_ramp_within_max_slope_is_walked_and_a_steeper_one_stops_it():
    def ramp(deg):
        rise = 3.0 * math.tan(math.radians(deg))
        return [Ramp("ramp", 4.5, 0.0, length=3.0, width=3.0, rise=rise),
                Platform("top", 9.0, 0.0, length=6.0, width=3.0, height=rise)]
    up = simulate(scene(ramp(25.0)), Straight(), 0)
    assert up.end == "goal" and up.trajectory.z[-1] == pytest.approx(3.0 * math.tan(math.radians(25.0)), abs=1e-6)
    steep = simulate(scene(ramp(35.0)), Straight(), 0)
    assert steep.end == "stuck-terrain" and steep.terrain_event.detail == "cannot climb the 35 deg slope"


def test_it_strides_over_a_gap_up_to_max_gap_and_falls_into_a_wider_one():
    narrow = simulate(scene([Pit("gap", 5.0, 0.0, length=0.25, width=3.0, depth=1.0)]), Straight(), 0)
    assert narrow.end == "goal" and narrow.trajectory.z.min() > -1e-6   # never below the floor
    wide = simulate(scene([Pit("gap", 5.0, 0.0, length=0.5, width=3.0, depth=1.0)]), Straight(), 0)
    assert wide.end == "fell"
    event = wide.terrain_event
    assert event.element == "into pit 'gap'" and event.drop == pytest.approx(1.0)
    assert 4.75 <= event.x <= 5.25                                     # its centre over the gap


def test_it_walks_down_stairs_and_falls_off_a_dock():
    down = [Platform("landing", 0.0, 0.0, length=4.0, width=3.0, height=0.85),
            Steps("stairs", 2.75, 0.0, count=5, rise=0.17, run=0.3, width=3.0, z=0.85, direction="down")]
    walked = simulate(scene(down, goal=(6.0, 0.0)), Straight(), 0)
    assert walked.end == "goal" and walked.trajectory.z[-1] == pytest.approx(0.0, abs=1e-6)
    dock = simulate(scene([Platform("dock", 0.0, 0.0, length=6.0, width=4.0, height=1.2)]), Straight(), 0)
    assert dock.end == "fell" and dock.terrain_event.element == "off platform 'dock'"
    assert dock.terrain_event.x == pytest.approx(3.0, abs=0.2)


def test_its_volume_meets_an_obstacle_lower_than_its_clearance():
    low = BoxObstacle("sill", 4.0, 0.0, 0.3, 2.0, height=0.2)
    res = simulate(scene([], obstacles=[low], safety=False), Straight(), 0)
    assert res.end == "collision" and res.collision.obstacle == "sill" and not res.collision.terrain


def test_omni_legged_climbs_stairs_sideways_and_same_bits_twice():
    side = scene([Steps("stairs", 0.0, 5.0, count=5, rise=0.17, run=0.3, width=3.0, yaw=90.0),
                  Platform("landing", 0.0, 7.75, length=3.0, width=4.0, height=0.85)], goal=(0.0, 8.0), drive="omni")
    a, b = simulate(side, Straight(), 0), simulate(side, Straight(), 0)
    assert a.end == "goal" and a.trajectory.z[-1] == pytest.approx(0.85, abs=1e-6)
    for name in ("pose", "velocity", "z", "roll", "pitch", "command"):
        assert getattr(a.trajectory, name).tobytes() == getattr(b.trajectory, name).tobytes()


def test_the_crossing_rule_on_profiles():
    cap = Capability(max_step=0.2, max_slope=30.0, max_gap=0.3)
    flat_then = lambda tail: [0.0] * 10 + tail                       # noqa: E731
    _, b = walk(flat_then([0.3] * 10), 0.02, 0.0, cap)
    assert (b.kind, b.index, round(b.height, 6)) == ("step", 9, 0.3)
    support, b = walk(flat_then([-1.0] * 10 + [0.0] * 10), 0.02, 0.0, cap)   # 0.2 m gap: strode over
    assert b is None and min(support) == 0.0
    _, b = walk(flat_then([-1.0] * 20 + [0.0] * 10), 0.02, 0.0, cap)         # 0.4 m gap: a drop
    assert b.kind == "drop" and b.height == 1.0
    ramp = [0.02 * k * math.tan(math.radians(35.0)) for k in range(40)]
    _, b = walk(flat_then(ramp), 0.02, 0.0, cap)
    assert b.kind == "slope"
    assert walk(flat_then([0.02 * k * math.tan(math.radians(25.0)) for k in range(40)]), 0.02, 0.0, cap)[1] is None


def test_a_yaml_scenario_with_a_legged_body_runs(tmp_path):
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.verdict.result import Outcome

    path = tmp_path / "stairs.yaml"
    path.write_text("""
version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 8, y: 0}, timeout: 30}
robot:
  drive: diff
  body: {type: legged, max_step: 0.12}
  safety: {enabled: false}    # on, it halts before the second riser (its lidar's plane meets it)
terrain:
  - {type: steps, name: stairs, x: 5.0, y: 0, count: 5, rise: 0.17, run: 0.3, width: 3.0}
  - {type: platform, name: landing, x: 7.75, y: 0, length: 4.0, width: 3.0, height: 0.85}
""")
    sc = load_scenario(path)
    assert sc.robot.body == LeggedBody(max_step=0.12)
    res = run_scenario(sc, Straight)
    assert res.outcome is Outcome.TIMEOUT
    assert "stuck on terrain" in res.message and "cannot climb the 0.17 m step of steps 'stairs'" in res.message


def test_moving_obstacles_walk_on_the_ground_or_at_their_own_height():
    """A person walking up a ramp has its base on the ramp at every step; one with an explicit z
    keeps it; the robot standing beside sees the first where it is."""
    import mujoco

    from pytest_navscenario.scenario.ground import surface as ground
    from pytest_navscenario.scenario.model import CylinderObstacle, Motion
    from pytest_navscenario.sim.body_world import compiled_body_world
    from pytest_navscenario.sim.moving import MovingObstacles

    walk = Motion(path=((2.0, 4.0), (8.0, 4.0)), speed=1.0)
    terrain = [Ramp("ramp", 5.0, 4.0, length=6.0, width=2.0, rise=0.6)]
    people = [CylinderObstacle("walker", 2.0, 4.0, 0.3, motion=walk),
              CylinderObstacle("drone", 2.0, 6.0, 0.3, z=1.5, motion=walk)]
    sc = scene(terrain, obstacles=people, goal=(1.0, 0.0))
    world = compiled_body_world(sc)
    d = mujoco.MjData(world.model)
    moving = MovingObstacles(sc, d.mocap_pos, sc.simulation.timestep, 10)
    rows = moving.rows_for_tick(300)                       # t = 3 s: the walker is up the ramp
    x = rows[0, 0, 0]
    assert 4.9 < x < 5.1
    edge = float(ground.ground_height(sc, x + 0.3, 4.0))    # its outline's highest ground
    assert rows[0, 0, 2] == pytest.approx(edge, abs=1e-9) and 0.3 < rows[0, 0, 2] < 0.4
    assert rows[0, 1, 2] == 1.5
    res = simulate(sc, Straight(), 0, max_ticks=2)           # the episode writes them so
    assert res.ticks == 2


def test_a_slope_steeper_than_max_slope_stops_it_across_its_way_as_the_path_search_says():
    """Diagonally across a bank (rising 38 deg toward +y; max_slope 30) the ground rises only 29 deg
    along its way: it used to walk up it although the path search calls the bank a wall. Now it stops
    at the bank's low edge, stuck, and a 25 deg bank is walked."""
    from pytest_navscenario.verdict.paths import shortest_path

    def bank(deg):
        rise = 6.0 * math.tan(math.radians(deg))
        return scene([Ramp("bank", 5.0, 0.0, length=6.0, width=6.0, rise=rise, yaw=90.0)],
                     start=(2.0, -5.0, 45.0), goal=(7.0, 0.0))

    assert shortest_path(bank(38.0)) is None
    steep = simulate(bank(38.0), Straight(), 0)
    assert steep.end == "stuck-terrain", steep.end
    event = steep.terrain_event
    assert event.element == "ramp 'bank'" and event.detail == "cannot walk the 38 deg slope across its way", event
    assert -3.6 < event.y < -3.0 and event.z == pytest.approx(0.0, abs=1e-6)   # at the low edge, not on it
    gentle = simulate(bank(25.0), Straight(), 0)
    assert gentle.end == "goal" and shortest_path(bank(25.0)).length == pytest.approx(math.hypot(5.0, 5.0))


def test_a_legged_body_held_on_the_plain_ground_is_not_said_to_slip_its_wheels():
    """#36: a legged body driven and making no headway with no step, slope or gap ahead is not
    'its wheels slip' (it has none) nor stuck on terrain: held still it did not move; moved back
    and forth as dwa told it on a flat floor, nothing of the terrain holds it (no event)."""
    from pytest_navscenario.sim.bodies import body_model
    from pytest_navscenario.sim.ground.riding import GroundProbe, TerrainStop, TerrainWatch

    sc = scene([Platform("far", 20.0, 10.0, length=2.0, width=2.0, height=0.3)])
    watch = TerrainWatch(sc, body_model(sc), 0.1, GroundProbe(sc))
    still = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    with pytest.raises(TerrainStop):
        for tick in range(100):
            watch.check(tick * 0.1, still, (0.5, 0.0, 0.0), False)
    assert "wheel" not in watch.event.detail
    assert watch.event.kind == "still" and "covered 0.00 m of the 1.50 m asked" in watch.event.detail
    # moved to and fro as it was told (dwa dithering): the terrain holds nothing, the watch says nothing
    watch = TerrainWatch(sc, body_model(sc), 0.1, GroundProbe(sc))
    for tick in range(100):
        v = 0.5 if (tick // 5) % 2 == 0 else -0.5
        x = 0.05 * (tick % 5) if (tick // 5) % 2 == 0 else 0.25 - 0.05 * (tick % 5)
        watch.check(tick * 0.1, (x, *still[1:]), (v, 0.0, 0.0), False)
    assert watch.event is None
