"""The wheeled body stands on flat ground at its limits: for every footprint, shape, drive and set
of limits the loader accepts, full speed ahead, full reverse and full-rate turns leave it upright
(no wheelie, no tip-over); what cannot stand (wheels that do not fit, a robot too short or too
top-heavy for its acceleration or its turns) is refused at load with the field and the fix."""
import itertools
import math

import numpy as np
import pytest

from pytest_navscenario import ScenarioError, loads_scenario
from pytest_navscenario.scenario.bodies.chassis import wheeled_problem
from pytest_navscenario.scenario.model import Footprint, Limits, Mission, Pose, Robot, Safety, Scenario
from pytest_navscenario.scenario.bodies import WheeledBody
from pytest_navscenario.sim.episode import simulate


class FullThrottle:
    """Full ahead from rest, full reverse, full ahead turning left then right, stop: the hardest
    accelerations and turns the drive's limits allow."""
    name, version = "full-throttle", "1"

    def __init__(self, speed, yaw_rate, ahead=0.6):
        self.v, self.w, self.ahead = speed, yaw_rate, ahead

    def reset(self, scenario):
        pass

    def act(self, obs):
        t = obs.time
        if t < 3.0:
            return (self.v * self.ahead if t < 0.5 else self.v, 0.0, 0.0)
        if t < 4.0:
            return (-self.v, 0.0, 0.0)
        if t < 6.0:
            return (self.v, 0.0, self.w)
        if t < 7.0:
            return (self.v, 0.0, -self.w)
        return (0.0, 0.0, 0.0)


def scene(footprint, body, limits=Limits()):
    return Scenario(mission=Mission(start=Pose(0.0, 0.0, 0.0), goal=Pose(60.0, 0.0), timeout=8.0),
                    robot=Robot(footprint=footprint, drive="diff", body=body, limits=limits,
                                safety=Safety(enabled=False)))


FOOTPRINTS = [Footprint(shape="circle", radius=r) for r in (0.15, 0.2, 0.3, 0.5)] + \
             [Footprint(length=a, width=b) for a, b in ((0.3, 0.3), (0.9, 0.5), (0.3, 0.8), (1.5, 0.6))]
BODIES = [WheeledBody(), WheeledBody(drive_wheels="skid"), WheeledBody(mass=10.0, max_wheel_torque=40.0),
          WheeledBody(wheel_radius=0.05, clearance=0.05), WheeledBody(com_height=0.25)]
LIMITS = [Limits(), Limits(max_speed=2.0, max_accel=5.0, max_yaw_rate=180.0, max_yaw_accel=360.0)]


def test_every_accepted_body_stays_upright_at_its_limits_on_flat_ground():
    ran, worst = 0, (0.0, None)
    for footprint, body, limits in itertools.product(FOOTPRINTS, BODIES, LIMITS):
        sc = scene(footprint, body, limits)
        if wheeled_problem(sc) is not None:
            continue
        res = simulate(sc, FullThrottle(limits.max_speed, math.radians(limits.max_yaw_rate)), 0)
        ran += 1
        tilt = math.degrees(max(np.abs(res.trajectory.pitch).max(), np.abs(res.trajectory.roll).max()))
        assert res.end == "timeout", (footprint, body, limits, res.end, res.terrain_event)
        assert tilt < 12.0, (footprint, body, limits, tilt)
        worst = max(worst, (tilt, (footprint, body.drive_wheels, limits.max_accel)), key=lambda w: w[0])
    assert ran >= 50, ran                  # most of the grid is accepted: the checks refuse only what cannot stand
    assert worst[0] > 2.0                   # it does pitch: the casters' springs and the ground are real


def test_a_small_circle_robot_drives_off_without_a_wheelie():
    """The reported defect: a 0.15 m circle robot starting at 0.6 m/s pitched back past 45 degrees
    within 0.5 s (its mass 0.3 m up on soft casters, each tick's new wheel speed kicked at full torque)."""
    res = simulate(scene(Footprint(shape="circle", radius=0.15), WheeledBody()), FullThrottle(0.6, 0.0, ahead=1.0), 0)
    early = res.trajectory.t < 1.0
    assert res.end == "timeout"
    assert math.degrees(np.abs(res.trajectory.pitch[early]).max()) < 6.0
    assert res.trajectory.velocity[early, 0].max() < 0.75          # no lurch: it follows the drive's ramp


def test_a_10_degree_ramp_pitches_the_chassis_by_its_slope():
    from pytest_navscenario.scenario.terrain import Platform, Ramp
    rise = 4.0 * math.tan(math.radians(10.0))
    sc = Scenario(mission=Mission(start=Pose(0.0, 0.0, 0.0), goal=Pose(10.0, 0.0), timeout=20.0),
                  terrain=(Ramp("ramp", 5.0, 0.0, length=4.0, width=3.0, rise=rise),
                           Platform("top", 10.0, 0.0, length=6.0, width=3.0, height=rise)),
                  robot=Robot(drive="diff", body=WheeledBody()))
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).parents[1] / "search"))
    from straight_planner import Straight

    traj = simulate(sc, Straight(), 0).trajectory
    on_ramp = (traj.pose[:, 0] > 4.2) & (traj.pose[:, 0] < 5.8)
    # the slope, plus the casters' springs giving to the climbing torque's reaction: the wheels push
    # m g sin(10 deg) r (8.5 N m) into the chassis, which two springs of stiffness k at +-d resist,
    # k = m g / (d tan SUSPENSION_SLOPE) (0.7 deg more; 12.5 deg before the mass went to the axle)
    from pytest_navscenario.sim.bodies.wheeled import SUSPENSION_SLOPE
    m, g, r, d = 50.0, 9.81, 0.1, 0.4
    k = m * g / (d * math.tan(math.radians(SUSPENSION_SLOPE)))
    give = math.degrees(m * g * math.sin(math.radians(10.0)) * r / (2 * k * d * d))
    assert math.degrees(-traj.pitch[on_ramp].mean()) == pytest.approx(10.0 + give, abs=0.3)


YAML = """\
version: 1
robot:
  footprint: {footprint}
  drive: diff
  body: {body}
  limits: {limits}
mission:
  start: {{x: 0, y: 0}}
  goal: {{x: 5, y: 0}}
"""


@pytest.mark.parametrize("footprint, body, limits, field, fragments", [
    ("{shape: circle, radius: 0.1}", "{type: wheeled}", "{}", "robot.body.wheel_width",
     ["leave no track between them in a circle of radius 0.1 m", "smaller or narrower wheels"]),
    ("{shape: box, length: 0.9, width: 0.5}", "{type: wheeled, track: 0.6}", "{}", "robot.body.track",
     ["stick out of a footprint 0.9 x 0.5 m", "narrower track"]),
    ("{shape: box, length: 0.3, width: 0.3}", "{type: wheeled, drive_wheels: skid}", "{max_accel: 5}",
     "robot.limits.max_accel", ["would tip over accelerating or braking at 5 m/s²", "at most 3.92"]),
    ("{shape: box, length: 0.9, width: 0.5}", "{type: wheeled, com_height: 0.6, max_wheel_torque: 100}",
     "{max_accel: 8}", "robot.limits.max_accel", ["its mass 0.6 m up and its casters 0.4 m ahead"]),
    # the wheels' grip limits it (torque to spare, max_accel above it): max_accel is the key to lower
    ("{shape: box, length: 0.3, width: 0.3}", "{type: wheeled, drive_wheels: skid, max_wheel_torque: 1000}",
     "{max_accel: 20}", "robot.limits.max_accel", ["accelerating or braking at 9.81 m/s²", "at most 3.92"]),
    # the torque limits it: the torque is the key to lower
    ("{shape: box, length: 0.3, width: 0.3}", "{type: wheeled, drive_wheels: skid, max_wheel_torque: 8}",
     "{max_accel: 20}", "robot.body.max_wheel_torque", ["accelerating or braking at 6.4 m/s²",
                                                         "lower max_wheel_torque to at most 4.9 N m"]),
    ("{shape: box, length: 0.9, width: 0.3}", "{type: wheeled, com_height: 0.5}",
     "{max_speed: 2, max_yaw_rate: 180}", "robot.limits.max_yaw_rate", ["would roll over turning", "widen the track"]),
])
def test_a_body_that_cannot_stand_is_refused_with_the_field_and_the_fix(footprint, body, limits, field, fragments):
    text = YAML.format(footprint=footprint, body=body, limits=limits)
    with pytest.raises(ScenarioError) as info:
        loads_scenario(text)
    err = info.value
    assert err.field == field, err
    for fragment in fragments:
        assert fragment in str(err), err
    parent = field.split(".")[1]          # "body" or "limits": the line that holds the key
    assert text.splitlines()[err.line - 1].lstrip().startswith(parent + ":"), err


def test_the_wheels_of_a_default_body_fit_every_footprint_the_checks_accept():
    from pytest_navscenario.scenario.bodies.chassis import wheeled_layout
    for footprint, body in itertools.product(FOOTPRINTS, BODIES):
        sc = scene(footprint, body)
        if wheeled_problem(sc) is not None:
            continue
        lay = wheeled_layout(body, footprint)
        for x, y in lay.wheels:
            corner = (abs(x) + lay.radius, abs(y) + lay.wheel_width / 2)
            if footprint.shape == "circle":
                assert math.hypot(*corner) <= footprint.radius + 1e-9
            else:
                assert corner[0] <= footprint.length / 2 + 1e-9 and corner[1] <= footprint.width / 2 + 1e-9
