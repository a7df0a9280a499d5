"""``navscenario from-bag`` with a 3D lidar keeps the ground: a bag recorded from a robot driving past a
ramp up to a loading dock, a pit and a crate (our own episode, written with /points, the 3D odometry
and the lidar's mount) comes back as a seed with the ramp and the dock as a heightfield, the pit as
a pit, the crate as the only obstacle, a body that rides the ground and the 3D lidar, every guess
said in the notes; the seed loads and runs."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.ros.bag_import import scenario_from_bag
from pytest_navscenario.ros.bag_writer import write_episode_bag
from pytest_navscenario.ros.world_import import write_seed
from pytest_navscenario.scenario.loader import load_scenario, loads_scenario
from pytest_navscenario.verdict.result import Outcome

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "sim"))
from test_sensors_riding import Straight  # noqa: E402

YARD = """
version: 1
robot:
  body: {type: wheeled}
  drive: diff
  lidar3d: {rings: 16, beams: 360, mount_z: 0.5}
mission: {start: {x: 0, y: 0}, goal: {x: 9, y: 0}, timeout: 20}
obstacles:
  - {type: box, name: crate, x: 6, y: -2.5, length: 0.8, width: 0.8, height: 0.8}
terrain:
  - {type: ramp, name: slope, x: 4, y: 2.2, length: 3, width: 2, rise: 0.4}
  - {type: platform, name: dock, x: 7, y: 2.2, length: 3, width: 2, height: 0.4}
  - {type: pit, name: hole, x: 4, y: -2.5, length: 2, width: 1.5, depth: 0.6}
"""


@pytest.fixture(scope="module")
def seed(tmp_path_factory):
    result = run_scenario(loads_scenario(YARD), Straight(0.6))
    assert result.outcome is Outcome.SUCCESS, result.message
    bag = write_episode_bag(result, tmp_path_factory.mktemp("bag") / "yard")
    return scenario_from_bag(bag, cloud_topic="/points", robot_radius=0.45)


def test_the_ramp_and_the_dock_become_a_heightfield_and_the_pit_a_pit(seed):
    kinds = {el.kind: el for el in seed.scenario.terrain}
    assert sorted(kinds) == ["heightfield", "pit"]
    field, pit = kinds["heightfield"], kinds["pit"]
    # the ramp (x 2.5..5.5) and the dock (5.5..8.5) at y 1.2..3.2: the ramp's lowest 5 cm is floor
    x0, x1 = field.x - field.length / 2, field.x + field.length / 2
    y0, y1 = field.y - field.width / 2, field.y + field.width / 2
    assert 2.5 <= x0 <= 3.2 and x1 == pytest.approx(8.5, abs=0.2)
    assert y0 == pytest.approx(1.2, abs=0.2) and y1 == pytest.approx(3.2, abs=0.2)
    assert field.max_height == pytest.approx(0.4, abs=0.03) and field.min_height == 0.0
    assert field.file in seed.files
    # the pit: the part the lidar saw into, inside the true one (x 3..5, y -3.25..-1.75)
    assert abs(pit.x - 4.0) < 0.3 and -3.25 < pit.y < -1.75 and pit.depth > 0.2


def test_the_crate_is_the_only_obstacle_and_the_guesses_are_said(seed):
    (crate,) = seed.scenario.obstacles
    assert (crate.x, crate.y) == pytest.approx((6.0, -2.5), abs=0.15)
    assert crate.height == pytest.approx(0.8, abs=0.05)
    robot = seed.scenario.robot
    assert robot.body.kind == "wheeled" and robot.lidar3d is not None and robot.lidar3d.mount_z == 0.5
    text = "\n".join(seed.notes)
    # the bag is ours: its /navscenario/scenario says the body (no guess), --robot-radius the footprint
    assert "robot.body: wheeled (a guess" not in text and "heightfield 'ground'" in text
    assert "from the scenario the bag recorded (/navscenario/scenario" in text
    assert robot.footprint.shape == "circle" and robot.footprint.radius == 0.45
    assert "pit 'ground-hole1'" in text and "were that ground seen in the obstacle band" in text


def test_the_seed_loads_with_its_heightfield_and_runs(seed, tmp_path):
    out = tmp_path / "seed" / "yard.yaml"
    write_seed(seed.scenario, out, extra_files=seed.files)
    loaded = load_scenario(out)
    field = next(el for el in loaded.terrain if el.kind == "heightfield")
    assert field.digest and (out.parent / field.file).is_file()
    assert run_scenario(loaded, Straight(0.6)).outcome is Outcome.SUCCESS


def test_a_flat_world_keeps_no_terrain(tmp_path):
    """The flat world of issue 17's cloud tests: no terrain, the planar body, no heightfield."""
    from ros_synthetic import robot_bag
    from test_import_clouds import CLOUD, LIDAR, WORLD, _drive

    flat = scenario_from_bag(robot_bag(tmp_path / "flat", WORLD, _drive(), scans=False, laser=LIDAR,
                                       cloud={**CLOUD, "layout": "velodyne"}))
    assert flat.scenario.terrain == () and flat.files == {}
    assert flat.scenario.robot.body.kind == "planar" and flat.scenario.robot.lidar3d is None
