"""The terrain additions to the scenario model: off by default, so every older file hashes the same;
when present they are content (a ramp's rise changes the hash), their names are labels."""
from dataclasses import replace

from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.scenario.model import content_hash
from pytest_navscenario.scenario.terrain import Lidar3D, PlanarBody, Ramp, WheeledBody

FLAT = """
version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 0, y: 10}}
obstacles:
  - {type: box, name: b, x: 1.5, y: 5, length: 1, width: 1}
"""


def test_the_defaults_are_todays_world_and_hash_as_before_they_existed():
    s = loads_scenario(FLAT)
    assert s.terrain == () and s.robot.body == PlanarBody() and s.robot.lidar3d is None
    assert s.robot.lidar.mount_height == 0.2 and s.obstacles[0].z is None
    # the hash of this file before terrain existed (pinned: results files pair scenarios by it)
    assert content_hash(s) == "344e09b311d56a84"


def test_terrain_bodies_and_the_3d_lidar_are_content_and_names_are_labels():
    s = loads_scenario(FLAT)
    ramp = Ramp("r", 0.0, 5.0, length=3.0, width=2.0, rise=0.5)
    with_ramp = replace(s, terrain=(ramp,))
    assert content_hash(with_ramp) != content_hash(s)
    assert content_hash(replace(s, terrain=(replace(ramp, rise=0.6),))) != content_hash(with_ramp)
    assert content_hash(replace(s, terrain=(replace(ramp, name="other"),))) == content_hash(with_ramp)
    assert content_hash(replace(s, robot=replace(s.robot, body=WheeledBody()))) != content_hash(s)
    assert content_hash(replace(s, robot=replace(s.robot, lidar3d=Lidar3D()))) != content_hash(s)
    assert round(ramp.slope, 2) == 9.46
