"""Load-time checks of a mission on terrain and of the body: a start or goal over a pit or standing
in a terrain face, a waypoint over a hole, the planar body with terrain, a wheeled body told to
drive omni: each a ScenarioError naming the field and the fix (check_scenario, run by the loader)."""
import pytest

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.scenario.ground import surface as ground
from pytest_navscenario.scenario.loader import check_scenario
from pytest_navscenario.scenario.model import Mission, Pose, Robot, Scenario
from pytest_navscenario.scenario.terrain import Pit, Platform, Ramp, Steps, WheeledBody

WHEELED = Robot(drive="diff", body=WheeledBody())


def scene(terrain, start=(0.0, 0.0), goal=(10.0, 0.0), waypoints=(), robot=WHEELED):
    return Scenario(mission=Mission(start=Pose(*start), goal=Pose(*goal),
                                    waypoints=tuple(Pose(*w) for w in waypoints)),
                    terrain=tuple(terrain), robot=robot)


def test_a_mission_on_the_ground_passes():
    check_scenario(scene([Pit("hole", 5.0, 0.0, length=1.0, width=1.0, depth=0.5),
                          Ramp("r", 5.0, 3.0, length=3.0, width=2.0, rise=0.3)]))


@pytest.mark.parametrize("where, field", [({"goal": (5.0, 0.0)}, "mission.goal"),
                                          ({"start": (5.2, 0.1)}, "mission.start"),
                                          ({"waypoints": [(5.0, 0.3)]}, "mission.waypoints[0]")])
def test_a_mission_point_over_a_pit_is_refused(where, field):
    with pytest.raises(ScenarioError) as err:
        check_scenario(scene([Pit("hole", 5.0, 0.0, length=1.0, width=1.0, depth=0.5)], **where))
    assert err.value.field == field and "lies over pit 'hole', 0.5 m below the floor" in err.value.message
    assert "move it onto the ground" in err.value.hint


def test_a_start_half_on_a_platform_stands_in_its_face_and_a_stairwell_is_a_hole():
    with pytest.raises(ScenarioError, match=r"mission.start: the robot's footprint at \(0, 0\) stands in a face "
                                            r"of platform 'dock'"):
        check_scenario(scene([Platform("dock", 1.5, 0.0, length=3.0, width=3.0, height=1.0)]))
    with pytest.raises(ScenarioError, match="lies over steps 'well'"):
        check_scenario(scene([Steps("well", 5.0, 0.0, count=3, rise=0.2, run=0.3, width=1.0, direction="down")],
                             goal=(5.0, 0.0)))


def test_the_body_and_the_drive_must_go_together():
    with pytest.raises(ScenarioError) as err:
        check_scenario(scene([Ramp("r", 5.0, 3.0, length=3.0, width=2.0, rise=0.3)], robot=Robot()))
    assert err.value.field == "robot.body" and "robot.body: {type: wheeled}" in err.value.hint
    with pytest.raises(ScenarioError, match="robot.drive: a wheeled body cannot drive 'omni'"):
        check_scenario(scene([], robot=Robot(drive="omni", body=WheeledBody())))


def test_ground_heights_of_each_element():
    terrain = (Ramp("r", 0.0, 0.0, length=2.0, width=1.0, rise=0.4), Platform("p", 3.0, 0.0, length=2.0, width=1.0, height=0.5),
               Pit("h", 6.0, 0.0, length=2.0, width=1.0, depth=0.7),
               Steps("s", 9.0, 0.0, count=2, rise=0.1, run=0.5, width=1.0))
    sc = scene(terrain, start=(0.0, 5.0), goal=(1.0, 5.0))
    h = ground.ground_height(sc, [-1.0, 0.0, 1.0, 3.0, 6.0, 8.75, 9.25, 12.0], [0.0] * 8)
    assert h.tolist() == pytest.approx([0.0, 0.2, 0.4, 0.5, -0.7, 0.1, 0.2, 0.0])
    yawed = scene((Ramp("r", 0.0, 0.0, length=2.0, width=1.0, rise=0.4, yaw=90.0),), start=(5, 5), goal=(6, 5))
    assert float(ground.ground_height(yawed, 0.0, 0.5)) == pytest.approx(0.3)


# ---------------------------------------------------------------- hostile and odd files (qa)

def write_scene(tmp_path, terrain: str, obstacles: str = "", body: str = "{type: wheeled}"):
    path = tmp_path / "scene.yaml"
    path.write_text(f"""version: 1
robot:
  drive: diff
  body: {body}
mission:
  start: {{x: 0, y: 0}}
  goal: {{x: 8, y: 0}}
terrain:
{terrain}
obstacles:
{obstacles}
""")
    return path


def test_an_obstacle_floating_above_the_ground_or_buried_under_it_is_refused(tmp_path):
    """The verdict, the safety layer and the paths treat an obstacle as standing on the ground
    (a box 3 m above the robot's route made the safety layer halt it, with nothing in its way)."""
    from pytest_navscenario.scenario.loader import load_scenario

    dock = "  - {type: platform, name: dock, x: 4, y: 3, length: 2, width: 2, height: 1.2}"
    with pytest.raises(ScenarioError) as err:
        load_scenario(write_scene(tmp_path, dock, "  - {type: box, name: sign, x: 4, y: 0, length: 0.5, width: 0.5, "
                                                   "z: 3}"))
    assert err.value.field == "obstacles[0].z" and err.value.line == 11
    assert "box 'sign' floats 3 m above the ground under it" in err.value.message and "leave z out" in err.value.hint
    with pytest.raises(ScenarioError, match=r"obstacles\[0\].z: box 'crate' lies under the ground"):
        load_scenario(write_scene(tmp_path, dock, "  - {type: box, name: crate, x: 4, y: 0, length: 0.5, width: 0.5, "
                                                   "height: 1, z: -1.5}"))
    # on the dock at its own height, and half sunk into the floor: fine
    load_scenario(write_scene(tmp_path, dock, "  - {type: box, name: crate, x: 4, y: 3, length: 0.5, width: 0.5, z: 1.2}\n"
                                              "  - {type: box, name: kerb, x: 4, y: -2, length: 0.5, width: 0.5, z: -0.5}"))


def test_an_obstacle_z_on_the_flat_floor_of_the_planar_body_is_refused_not_ignored(tmp_path):
    from pytest_navscenario.scenario.loader import load_scenario

    path = tmp_path / "flat.yaml"
    path.write_text("version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 8, y: 0}}\nobstacles:\n"
                    "  - {type: box, name: shelf, x: 4, y: 2, length: 0.5, width: 0.5, z: 3}\n")
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert err.value.field == "obstacles[0].z" and err.value.line == 4 and "floats 3 m" in err.value.message


def test_terrain_whose_blocks_or_holes_would_take_minutes_to_build_is_refused(tmp_path):
    """100 flights of 1000 steps took 17 s to build and 0.5 GB; 1000 pits at random places 9 s
    (the floor around them)."""
    from pytest_navscenario.scenario.loader import load_scenario

    flights = "\n".join(f"  - {{type: steps, x: {3 * i}, y: 20, count: 1000, rise: 0.001, run: 0.002, width: 1}}"
                        for i in range(6))
    with pytest.raises(ScenarioError) as err:
        load_scenario(write_scene(tmp_path, flights))
    assert err.value.field == "terrain" and "6000 blocks" in err.value.message
    pits = "\n".join(f"  - {{type: pit, x: {3 * (i % 20)}, y: {20 + 3 * (i // 20)}, length: 1, width: 1, depth: 0.5}}"
                     for i in range(ground.MAX_HOLES + 1))
    with pytest.raises(ScenarioError, match=rf"terrain: {ground.MAX_HOLES + 1} elements cut holes in the floor"):
        load_scenario(write_scene(tmp_path, pits))


def test_a_terrain_element_may_not_take_an_obstacles_name(tmp_path):
    """search: {frozen: [crate]} would name both."""
    from pytest_navscenario.scenario.loader import load_scenario

    with pytest.raises(ScenarioError) as err:
        load_scenario(write_scene(tmp_path, "  - {type: pit, name: crate, x: 4, y: 3, length: 1, width: 1, depth: 0.5}",
                                  "  - {type: box, name: crate, x: 4, y: -3, length: 1, width: 1}"))
    assert err.value.field == "terrain[0].name" and "already used by obstacles[0]" in err.value.message
    sc = load_scenario(write_scene(tmp_path, "  - {type: pit, x: 4, y: 3, length: 1, width: 1, depth: 0.5}",
                                   "  - {type: box, name: pit1, x: 4, y: -3, length: 1, width: 1}"))
    assert sc.terrain[0].name == "pit2"                    # a generated name skips the obstacles' names
