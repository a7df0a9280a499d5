"""Load-time checks of a mission on terrain and of the body: a start or goal over a pit or standing
in a terrain face, a waypoint over a hole, the planar body with terrain, a wheeled body told to
drive omni: each a ScenarioError naming the field and the fix (check_scenario, run by the loader)."""
import pytest

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.scenario import ground
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
