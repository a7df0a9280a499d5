"""A public MJCF robot nobody here wrote (MuJoCo's own car, tests/data/mjcf/mujoco_car.xml: copied
byte for byte from google-deepmind/mujoco model/car/car.xml, Apache-2.0) with a small controller of
its own (tests/sim/mujoco_car_controller.py) gets the verdicts the built-in wheeled body gets in the
same scenario: flat, up a ramp, off a platform's edge (issue 36.2, the "done when" line). The car is
small (wheels of 3 cm radius, 0.54 kg, torque motors on two tendons, a floor, lights and an
`<option>`-less file of its own): the scenarios are scaled to it."""
import re
import shutil
import sys
from pathlib import Path

import pytest

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.sim.episode import simulate

sys.path.insert(0, str(Path(__file__).parents[1] / "search"))
from straight_planner import Straight  # noqa: E402

CAR_FILE = Path(__file__).parents[1] / "data" / "mjcf" / "mujoco_car.xml"
FOOTPRINT = "footprint: {shape: box, length: 0.2, width: 0.14}"
CAR = '{type: mjcf, file: mujoco_car.xml, controller: "mujoco_car_controller:Car"}\n  ' + FOOTPRINT
BUILT_IN = {
    "default": "{type: wheeled}",
    # the built-in body at the car's size: its wheels, mass and motor torque
    "car-sized": "{type: wheeled, wheel_radius: 0.03, wheel_width: 0.02, mass: 0.5, max_wheel_torque: 0.5, "
                 "clearance: 0.02}\n  " + FOOTPRINT,
}
TERRAIN = {
    "flat": "",
    # 4.8 deg, 5 cm up onto the upper level
    "ramp": """terrain:
  - {type: ramp, name: ramp, x: 1.0, y: 0, length: 0.6, width: 1.0, rise: 0.05}
  - {type: platform, name: upper, x: 2.3, y: 0, length: 2.0, width: 1.0, height: 0.05}""",
    # the robot starts on a 0.3 m platform and drives off its edge at x = 1 (a fall is a drop of
    # more than 0.1 m, the bodies' drop_limit)
    "edge": """terrain:
  - {type: platform, name: upper, x: 0, y: 0, length: 2.0, width: 1.0, height: 0.3}""",
    # a 0.15 m edge: the car noses down onto the floor, its rear still on the edge (4 wheel radii)
    "short edge": """terrain:
  - {type: platform, name: upper, x: 0, y: 0, length: 2.0, width: 1.0, height: 0.15}""",
    # a 5 cm edge: under the drop limit, no fall for either
    "low edge": """terrain:
  - {type: platform, name: upper, x: 0, y: 0, length: 2.0, width: 1.0, height: 0.05}""",
}


def scenario(folder: Path, body: str, terrain: str):
    shutil.copy(CAR_FILE, folder / "mujoco_car.xml")
    path = folder / "scene.yaml"
    path.write_text(f"""version: 1
mission: {{start: {{x: 0, y: 0}}, goal: {{x: 2.5, y: 0}}, timeout: 20}}
robot:
  drive: diff
  limits: {{max_speed: 0.3}}
  safety: {{enabled: false}}
  body: {body}
{TERRAIN[terrain]}
""")
    return load_scenario(path)


def kind(message: str) -> str:
    """The verdict without its times and places: "fell off platform 'upper', 0.3 m drop"."""
    return re.sub(r" (at|in|after) (t=)?-?[\d.]+ s|,? at \(-?[\d.]+, -?[\d.]+\)", "", message)


def test_the_file_is_mujocos_own_car_byte_for_byte():
    import hashlib
    data = CAR_FILE.read_bytes()
    blob = hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()
    assert blob == "0ab791f05ad6b022e573a7bb13af6aa0efdddc1d"     # git's blob id of model/car/car.xml


# the default built-in body (0.9 m long, wheels of 0.1 m) bridges a 0.15 m edge (it stalls across
# it), a different event; the car-sized one stalls at a 5 cm drop (its 3 cm casters)
PAIRS = [(t, b) for t in ("flat", "ramp", "edge") for b in BUILT_IN] + [("short edge", "car-sized"),
                                                                        ("low edge", "default")]


@pytest.mark.parametrize("terrain,built_in", PAIRS)
def test_the_public_car_gets_the_verdict_the_built_in_body_gets(tmp_path, terrain, built_in):
    car = run_scenario(scenario(tmp_path, CAR, terrain), Straight)
    ours = run_scenario(scenario(tmp_path, BUILT_IN[built_in], terrain), Straight)
    assert (car.outcome, kind(car.message)) == (ours.outcome, kind(ours.message)), (car.message, ours.message)
    expected = {"flat": "success", "ramp": "success", "edge": "fell off platform 'upper', 0.3 m drop",
                "short edge": "fell off platform 'upper', 0.15 m drop", "low edge": "success"}[terrain]
    assert kind(car.message) == expected, car.message


def test_up_the_ramp_it_ends_on_the_upper_level_and_off_the_edge_it_lands_on_the_floor(tmp_path):
    up = simulate(scenario(tmp_path, CAR, "ramp"), Straight(), 0)
    assert up.end == "goal" and up.trajectory.z[-1] == pytest.approx(0.05, abs=0.005)
    off = simulate(scenario(tmp_path, CAR, "edge"), Straight(), 0)
    assert off.end == "fell" and off.terrain_event.element == "off platform 'upper'"
    assert off.terrain_event.drop == pytest.approx(0.3)
    assert off.terrain_event.x > 1.0                                    # its centre past the edge


def test_the_watch_tells_a_tip_past_an_edge_from_one_on_its_ground_or_on_a_slope():
    """The rule, tick by tick (the built-in body's watch, no physics): pitched past tip_angle with
    its centre past the platform's edge (over the floor 0.3 m down, airborne or resting on it while
    its rear is on the platform) is a fall off the platform;
    pitched past it with its centre still on the platform, or on a steep ramp whose ground under it
    is as far below where it last stood (a slope, no edge), is a tip-over."""
    from pytest_navscenario.scenario.bodies import WheeledBody
    from pytest_navscenario.scenario.model import Mission, Pose, Robot, Scenario
    from pytest_navscenario.scenario.terrain import Platform, Ramp
    from pytest_navscenario.sim.bodies import body_model
    from pytest_navscenario.sim.ground.riding import GroundProbe, TerrainStop, TerrainWatch

    def end(terrain, x, z):
        sc = Scenario(mission=Mission(start=Pose(0.0, 0.0, 0.0), goal=Pose(2.5, 0.0), timeout=20.0),
                      terrain=(terrain,), robot=Robot(drive="diff", body=WheeledBody()))
        watch = TerrainWatch(sc, body_model(sc), 0.1, GroundProbe(sc))
        h0 = GroundProbe(sc).height(0.9, 0.0)
        watch.check(0.0, (0.9, 0.0, h0, 0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0), (0.2, 0.0, 0.0), False)
        with pytest.raises(TerrainStop):     # then at x, its base z above the floor, pitched 60 deg nose down
            watch.check(0.1, (x, 0.0, z, 0.0, 1.05, 0.0, 0.2, 0.0, 0.0, 0.0), (0.2, 0.0, 0.0), False)
        return watch.event

    platform = Platform("upper", 0.0, 0.0, length=2.0, width=1.0, height=0.3)
    past = end(platform, 1.05, 0.25)
    assert (past.kind, past.element, past.drop) == ("fell", "off platform 'upper'", pytest.approx(0.3))
    # nosed down onto the floor, its centre 5 cm over it (it "stands" on the floor now), its rear
    # still on the platform: a fall off the platform all the same
    nosed = end(platform, 1.03, 0.05)
    assert (nosed.kind, nosed.element, nosed.drop) == ("fell", "off platform 'upper'", pytest.approx(0.3))
    on = end(platform, 0.95, 0.4)
    assert (on.kind, on.element) == ("tipped", "platform 'upper'")
    bank = Ramp("bank", 1.5, 0.0, length=2.0, width=1.0, rise=1.2, yaw=180.0)   # 31 deg down from x = 0.5
    slope = end(bank, 1.15, 0.91)                                    # 0.15 m below, 0.1 m up
    assert (slope.kind, slope.element) == ("tipped", "ramp 'bank'")


SILL = "terrain:\n  - {type: steps, name: sill, x: 1.0, y: 0, count: 1, rise: %s, run: 0.3, width: 1.0}"


@pytest.mark.parametrize("rise,body,said", [
    (0.01, "car-sized", "cannot climb the 0.01 m step of steps 'sill'"),     # "the 6 deg slope", no element
    (0.015, "car-sized", "cannot climb the 0.015 m step of steps 'sill'"),   # "the 0.01 m step"
    (0.015, "car", "cannot climb the 0.015 m step of steps 'sill'"),         # "pitched 5 deg over the 0.01 m edge"
])
def test_a_sill_a_small_robot_cannot_climb_is_named_as_a_step_at_its_scale(tmp_path, rise, body, said):
    """#36: the stuck watch's sizes (a 1 cm step, 0.3 m ahead) were fixed, so a sill stopping a robot
    on 3 cm wheels read as a slope of no element, or as its own tilt over an edge; its height was
    rounded to the centimetre. They scale with the footprint now, and a robot held at a step it is
    climbing (its rear wheels at the riser, its front on top) cannot climb that step."""
    TERRAIN["sill"] = SILL % rise
    res = run_scenario(scenario(tmp_path, CAR if body == "car" else BUILT_IN[body], "sill"), Straight)
    assert res.outcome.value == "timeout", res.message
    assert said in res.message, res.message


@pytest.mark.parametrize("height", [0.10, 0.105, 0.11])
def test_off_an_edge_of_its_drop_limit_the_car_goes_over_it_not_into_its_face(tmp_path, height):
    """#36.3: off an edge of about its drop limit (0.1 m), the car's centre past it and its base 7 cm
    above the floor counted as standing on the floor (a fixed 8 cm, a 0.9 m robot's), so the
    chassis touching the edge's corner was "collision with the face of platform 'upper'". At its
    scale it has not landed there: it goes over the edge, a fall or a tip-over off it."""
    TERRAIN["drop"] = ("terrain:\n  - {type: platform, name: upper, x: 0, y: 0, length: 2.0, width: 1.0, "
                       f"height: {height}}}")
    res = run_scenario(scenario(tmp_path, CAR, "drop"), Straight)
    assert res.outcome.value == "fall", res.message
    assert ("fell off platform 'upper'" in res.message
            or "tipped over off the edge of platform 'upper'" in res.message), res.message
