"""Issue 17, the robot: the footprint from the bag (the URDF on /robot_description: the collision
geometry of the base link or the link fixed to it; a Nav2 footprint), else the default, and the
note says which."""
from __future__ import annotations

import pytest
from ros_synthetic import World, loop_drive, robot_bag, stamp

from pytest_navscenario.ros.bag_import import scenario_from_bag
from pytest_navscenario.scenario.model import Footprint

WORLD = World(pillars=[(0.0, 0.0, 0.3, 1.0)])

URDF = """<?xml version="1.0"?>
<robot name="rover">
  <link name="base_link"/>
  <joint name="chassis_joint" type="fixed"><parent link="base_link"/><child link="chassis"/>
    <origin xyz="0 0 0.1"/></joint>
  <link name="chassis">
    <visual><geometry><mesh filename="package://rover/chassis.dae"/></geometry></visual>
    <collision><geometry>{geometry}</geometry></collision>
  </link>
  <joint name="wheel_joint" type="continuous"><parent link="chassis"/><child link="wheel"/></joint>
  <link name="wheel"><collision><geometry><cylinder radius="0.9" length="0.05"/></geometry></collision></link>
</robot>
"""


def _bag(tmp_path, extra):
    return robot_bag(tmp_path / "fp", WORLD, loop_drive(n=60, radius=1.5), extra=extra)


def _description(geometry):
    def write(bag):
        bag.write("/robot_description", "std_msgs/msg/String", 0.0, {"data": URDF.format(geometry=geometry)})
    return write


@pytest.mark.parametrize("geometry,want,why", [
    ('<box size="0.62 0.44 0.3"/>', Footprint(shape="box", length=0.62, width=0.44), "chassis: box 0.62 x 0.44 m"),
    ('<cylinder radius="0.27" length="0.3"/>', Footprint(shape="circle", radius=0.27), "chassis: cylinder of radius"),
])
def test_footprint_from_the_urdf(tmp_path, geometry, want, why):
    seed = scenario_from_bag(_bag(tmp_path, _description(geometry)))
    assert seed.scenario.robot.footprint == want
    assert any(n.startswith("footprint: the URDF on /robot_description") and why in n for n in seed.notes)


def test_a_mesh_only_urdf_is_a_warning_and_the_default(tmp_path):
    seed = scenario_from_bag(_bag(tmp_path, _description('<mesh filename="package://rover/c.stl"/>')))
    assert seed.scenario.robot.footprint == Footprint(shape="circle", radius=0.15)
    assert any("warning: /robot_description: chassis: collision geometry 'mesh'" in n for n in seed.notes)
    assert any(n.startswith("footprint: the default circle") for n in seed.notes)


def test_nav2_published_footprint_and_radius_option_wins(tmp_path):
    def nav2(bag):
        pts = [(0.35, 0.25), (0.35, -0.25), (-0.35, -0.25), (-0.35, 0.25)]
        bag.write("/local_costmap/published_footprint", "geometry_msgs/msg/PolygonStamped", 0.0, {
            "header": {"stamp": stamp(0.0), "frame_id": "base_link"},
            "polygon": {"points": [{"x": x, "y": y} for x, y in pts]}})
    path = _bag(tmp_path, nav2)
    seed = scenario_from_bag(path)
    assert seed.scenario.robot.footprint == Footprint(shape="box", length=0.7, width=0.5)
    assert any("footprint: the Nav2 footprint (/local_costmap/published_footprint)" in n for n in seed.notes)
    seed = scenario_from_bag(path, robot_radius=0.2)
    assert seed.scenario.robot.footprint == Footprint(shape="circle", radius=0.2)


def test_nav2_robot_radius_parameter(tmp_path):
    def params(bag):
        bag.write("/parameter_events", "rcl_interfaces/msg/ParameterEvent", 0.0, {
            "stamp": stamp(0.0), "node": "/local_costmap/local_costmap",
            "new_parameters": [{"name": "robot_radius", "value": {"type": 3, "double_value": 0.22}}]})
    seed = scenario_from_bag(_bag(tmp_path, params))
    assert seed.scenario.robot.footprint == Footprint(shape="circle", radius=0.22)
    assert any("parameter of /local_costmap/local_costmap" in n for n in seed.notes)
