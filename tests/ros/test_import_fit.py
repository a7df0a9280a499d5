"""Issue 24, the fit figure on a generated bag with a known answer: the seed ray-cast from the recorded
poses against the recorded ranges. The world itself as the seed agrees exactly; the world without
one pillar misses exactly the returns that pillar gave; a box added where the robot saw free space
blocks exactly the beams that crossed it."""
from __future__ import annotations

import math

import numpy as np
import pytest
from ros_synthetic import World, robot_bag

from pytest_navscenario.ros.bag_import.fit import TOL, fit_figure
from pytest_navscenario.ros.bag_import.mount import choose_mount
from pytest_navscenario.ros.bag_import.projection import beam_rays, map_scans
from pytest_navscenario.ros.bag_import.reading import read_bag
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle, Mission, Pose, Scenario

WORLD = World(pillars=[(2.0, 1.5, 0.3, 1.0), (-1.0, 2.5, 0.2, 1.0)],
              boxes=[(0.0, 4.0, 8.0, 0.2, 0.0, 1.0), (0.0, -2.0, 8.0, 0.2, 0.0, 1.0)])


def _seed(obstacles) -> Scenario:
    return Scenario(mission=Mission(start=Pose(-2.0, 0.0), goal=Pose(2.0, 0.0)), obstacles=tuple(obstacles))


def _truth_obstacles():
    return [CylinderObstacle(f"p{i}", x, y, r) for i, (x, y, r, _) in enumerate(WORLD.pillars)] + \
        [BoxObstacle(f"b{i}", x, y, ln, w, yaw) for i, (x, y, ln, w, yaw, _) in enumerate(WORLD.boxes)]


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    t = np.arange(40) * 0.1
    drive = np.stack([t, -2.0 + 0.1 * t, 0 * t, 0.2 * t], 1)
    path = robot_bag(tmp_path_factory.mktemp("fit") / "b", WORLD, drive, tf_map=False)
    data = read_bag(path)
    mount, _ = choose_mount(data, None)
    smap = map_scans(data, mount)
    return data, mount, smap


def _figure(bag, obstacles):
    data, mount, smap = bag
    return fit_figure(_seed(obstacles), data, mount, smap.sample, smap.first)


def test_the_world_itself_agrees_exactly(bag):
    fig = _figure(bag, _truth_obstacles())
    assert fig.blocked == 0.0 and fig.missed == 0.0 and fig.median_error < 1e-4 and fig.warnings == []
    assert fig.start_seed == pytest.approx(fig.start_scan, abs=0.02)


def test_a_pillar_left_out_misses_exactly_its_returns(bag):
    data, mount, smap = bag
    r = beam_rays(data, smap.sample, mount)
    rng = np.where(r.valid, r.range, np.nan)
    px, py = r.ox + rng * np.cos(r.angle), r.oy + rng * np.sin(r.angle)
    x, y, radius, _ = WORLD.pillars[0]
    on_pillar = np.abs(np.hypot(px - x, py - y) - radius) < 1e-3        # the returns the pillar gave
    known = on_pillar.sum() / r.valid.sum()
    fig = _figure(bag, [o for o in _truth_obstacles() if o.name != "p0"])
    assert known > 0.02 and fig.missed == pytest.approx(known, abs=1e-9) and fig.blocked == 0.0


def test_a_box_where_the_robot_saw_free_space_blocks_exactly_the_beams_that_crossed_it(bag):
    data, mount, smap = bag
    extra = BoxObstacle("ghost", 0.5, 2.6, 0.4, 0.4)
    r = beam_rays(data, smap.sample, mount)
    use = r.valid | r.none
    seen = np.where(r.valid, r.range, data.range_max)[use]
    from shapely.geometry import LineString

    from pytest_navscenario.scenario.geometry import obstacle_polygon
    ghost = obstacle_polygon(extra)
    ox, oy, ang = r.ox[use], r.oy[use], r.angle[use]
    crossed = sum(LineString([(a, b), (a + s * math.cos(g), b + s * math.sin(g))]).intersection(ghost).length > 0
                  for a, b, g, s in zip(ox, oy, ang, seen - TOL / 2))
    fig = _figure(bag, _truth_obstacles() + [extra])
    assert crossed > 0 and fig.blocked == pytest.approx(crossed / use.sum(), abs=2 / use.sum())
    assert any("disagrees with its own scans" in w for w in fig.warnings) == (fig.blocked > 0.05)


def test_the_figure_is_written_beside_the_seed(tmp_path):
    import json

    from pytest_navscenario.cli import main
    t = np.arange(30) * 0.1
    path = robot_bag(tmp_path / "b", WORLD, np.stack([t, -2.0 + 0.5 * t, 0 * t, 0 * t], 1), tf_map=False)
    assert main(["from-bag", str(path), "-o", str(tmp_path / "s.yaml"), "--no-plot"]) == 0
    body = json.loads((tmp_path / "s.fit.json").read_text())
    assert set(body) >= {"scans", "beams", "blocked", "missed", "median_error", "start_seed", "start_scan"}
    assert body["blocked"] < 0.02 and body["median_error"] < 0.05 and body["warnings"] == []


def test_a_seed_whose_start_is_much_clearer_than_the_first_scan_warns(bag):
    """Issue 37: the start clearance warns both ways; a seed missing the wall nearest the start is
    as wrong as one with a wall too near."""
    fig = _figure(bag, [o for o in _truth_obstacles() if o.name != "b1"])
    assert fig.start_seed > fig.start_scan + 0.5
    (warning,) = [w for w in fig.warnings if "at the start" in w]
    assert f"{fig.start_scan:.2f} m" in warning and "lacks what the robot saw nearest" in warning


def test_a_720_beam_laser_gives_the_seed_720_beams_and_says_so(tmp_path, capsys):
    """Issue 37: the beam count was capped at 360 without a word."""
    from pytest_navscenario.cli import main
    from pytest_navscenario.scenario.loader import load_scenario
    t = np.arange(20) * 0.1
    path = robot_bag(tmp_path / "b", WORLD, np.stack([t, -2.0 + 0.5 * t, 0 * t, 0 * t], 1), tf_map=False,
                     angles=np.radians(np.arange(-180.0, 180.0, 0.5)))
    assert main(["from-bag", str(path), "-o", str(tmp_path / "s.yaml"), "--no-plot"]) == 0
    lidar = load_scenario(tmp_path / "s.yaml").robot.lidar
    assert (lidar.beams, lidar.fov) == (720, 360.0)
    assert "robot.lidar: 720 beams over 360 deg, as /scan's scans" in capsys.readouterr().out
