"""The terrain additions to the scenario model: off by default, so every older file hashes the same;
when present they are content (a ramp's rise changes the hash), their names are labels."""
from dataclasses import replace

from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.scenario.model import content_hash
from pytest_navscenario.scenario.bodies import PlanarBody, WheeledBody
from pytest_navscenario.scenario.terrain import Lidar3D, Ramp

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


def test_bodies_written_before_com_height_and_the_mjcf_limits_hash_as_before():
    """Hashes taken on the branch before com_height (wheeled) and max_step/max_slope/max_gap (mjcf)
    existed: at their defaults (none) the new keys are left out."""
    from pytest_navscenario.scenario.model import Mission, Pose, Scenario
    from pytest_navscenario.scenario.bodies import LeggedBody, MjcfBody

    base = Scenario(mission=Mission(start=Pose(0.0, 0.0, 0.0), goal=Pose(5.0, 0.0)))
    hashes = {}
    for body in (WheeledBody(), WheeledBody(drive_wheels="skid", clearance=0.05), LeggedBody(),
                 MjcfBody(file="cart.xml", controller="cart_controller:Cart", digest="abc")):
        hashes[repr(body)] = content_hash(replace(base, robot=replace(base.robot, body=body)))
    assert list(hashes.values()) == ["861c2a897ad5f32f", "97afe35e171d6d94", "ecb750da7c07d160", "6570665ac1f18709"]
    declared = MjcfBody(file="cart.xml", controller="cart_controller:Cart", digest="abc", max_step=0.05,
                        max_slope=15.0)
    assert content_hash(replace(base, robot=replace(base.robot, body=declared))) != "6570665ac1f18709"


MJCF = """version: 1
mission: {{start: {{x: 0, y: 0}}, goal: {{x: 5, y: 0}}}}
robot:
  drive: diff
  body: {{type: mjcf, file: cart.xml, controller: "m:C"{limits}}}
"""


def test_an_mjcf_bodys_step_and_slope_are_declared_together(tmp_path):
    import pytest

    from pytest_navscenario import ScenarioError
    from pytest_navscenario.scenario.loader import load_scenario

    (tmp_path / "cart.xml").write_text(
        (__import__("pathlib").Path(__file__).parents[1] / "data" / "mjcf" / "cart.xml").read_text())
    path = tmp_path / "s.yaml"
    path.write_text(MJCF.format(limits=", max_step: 0.05, max_slope: 15"))
    body = load_scenario(path).robot.body
    assert (body.max_step, body.max_slope, body.max_gap) == (0.05, 15.0, None)
    path.write_text(MJCF.format(limits=", max_step: 0.05, max_gap: 0.1"))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.field == "robot.body.max_slope" and info.value.line == 5, info.value
    assert "declare max_step and max_slope together" in str(info.value), info.value
