"""Issue 17, the map frame: a bag generated from a known world whose odometry drifts (and once
slips by half a metre), with the exact map -> odom correction on /tf, as AMCL publishes it.
In the odometry frame the pillars smear; in the map frame they come out where they are."""
from __future__ import annotations

import math

import numpy as np
import pytest
from ros_synthetic import World, loop_drive, pose_msg, robot_bag, stamp

from pytest_navscenario.ros.bag_import import BagImportError, scenario_from_bag
from pytest_navscenario.scenario.model import CylinderObstacle

WORLD = World(pillars=[(0.0, 0.0, 0.3, 1.0), (3.4, 0.0, 0.2, 1.0), (0.0, 3.4, 0.2, 1.0), (-3.4, 0.0, 0.2, 1.0),
                       (0.0, -3.4, 0.2, 1.0), (2.6, 2.6, 0.25, 1.0)])
SLIP_T = 15.0


def _drift(truth):
    """map -> odom: a slow drift (2 cm/s, 0.4 deg/s) and a 0.5 m slip at SLIP_T."""
    t = truth[:, 0]
    slip = np.where(t >= SLIP_T, 1.0, 0.0)
    return np.stack([0.02 * t + 0.5 * slip, -0.015 * t, np.radians(0.4 * t)], 1)


@pytest.fixture(scope="module")
def drift_bag(tmp_path_factory):
    truth = loop_drive(n=300, dt=0.1, radius=1.8)
    path = tmp_path_factory.mktemp("drift") / "drift"
    robot_bag(path, WORLD, truth, drift=_drift(truth))
    return path, truth


def _pillar_errors(seed):
    pillars = [(o.x, o.y, o.radius) for o in seed.scenario.obstacles if isinstance(o, CylinderObstacle)]
    errs = []
    for x, y, r, _ in WORLD.pillars:
        near = [math.hypot(px - x, py - y) + abs(pr - r) for px, py, pr in pillars]
        errs.append(min(near) if near else math.inf)
    return errs, len(seed.scenario.obstacles)


def test_map_frame_puts_the_pillars_where_they_are(drift_bag):
    path, truth = drift_bag
    seed = scenario_from_bag(path)
    errs, n = _pillar_errors(seed)
    assert max(errs) < 0.04 and n == len(WORLD.pillars), (errs, seed.scenario.obstacles)
    m = seed.scenario.mission
    assert (m.start.x, m.start.y) == pytest.approx(tuple(truth[0, 1:3]), abs=0.01)
    assert (m.goal.x, m.goal.y) == pytest.approx(tuple(truth[-1, 1:3]), abs=0.01)
    assert any("world frame: map, odometry corrected with map -> odom on /tf" in n for n in seed.notes)
    jump = [n for n in seed.notes if "relocalisation jump" in n]
    assert len(jump) == 1 and f"t={SLIP_T:.1f} s" in jump[0] and "0.50 m" in jump[0]
    assert "frame map" in seed.scenario.description


def test_odometry_frame_smears_them(drift_bag):
    path, _ = drift_bag
    seed = scenario_from_bag(path, frame="odom")
    errs, n = _pillar_errors(seed)
    assert max(errs) > 0.2 or n != len(WORLD.pillars)
    assert any("drift not corrected" in n for n in seed.notes)


def test_pose_topic_instead_of_tf(tmp_path):
    """No map -> odom on /tf but /amcl_pose (PoseWithCovarianceStamped in map): the same result."""
    truth = loop_drive(n=300, dt=0.1, radius=1.8)
    drift = _drift(truth)

    def amcl(bag):
        for t, x, y, yaw in truth[::5]:
            bag.write("/amcl_pose", "geometry_msgs/msg/PoseWithCovarianceStamped", t, {
                "header": {"stamp": stamp(t), "frame_id": "map"}, "pose": {"pose": pose_msg(x, y, yaw)}})
    path = robot_bag(tmp_path / "amcl", WORLD, truth, drift=drift, extra=amcl, tf_map=False)
    seed = scenario_from_bag(path)
    assert any("pose in map on /amcl_pose" in n for n in seed.notes)
    errs, n = _pillar_errors(seed)
    assert max(errs) < 0.05 and n == len(WORLD.pillars)


def test_no_correction_says_so_and_map_demanded_is_an_error(tmp_path, capsys):
    truth = loop_drive(n=100, dt=0.1, radius=1.8)
    path = robot_bag(tmp_path / "plain", WORLD, truth, tf_map=False)
    seed = scenario_from_bag(path)
    assert any("world frame: odom (odometry): no map -> odom" in n for n in seed.notes)
    with pytest.raises(BagImportError, match="--frame map, but the bag has no map -> odom"):
        scenario_from_bag(path, frame="map")


def test_broken_chain_is_a_warning(tmp_path):
    """/tf has map -> odom_slam (another localiser's frame), never map -> odom."""
    truth = loop_drive(n=100, dt=0.1, radius=1.8)

    def other(bag):
        for t in truth[::10, 0]:
            bag.write("/tf", "tf2_msgs/msg/TFMessage", t, {"transforms": [
                {"header": {"stamp": stamp(t), "frame_id": "map"}, "child_frame_id": "odom_slam",
                 "transform": {"rotation": {"w": 1.0}}}]})
    path = robot_bag(tmp_path / "broken", WORLD, truth, tf_map=False, extra=other)
    seed = scenario_from_bag(path)
    assert any("warning: /tf has map -> odom_slam but no map -> odom" in n for n in seed.notes)
    assert any("world frame: odom (odometry)" in n for n in seed.notes)


def test_late_first_correction_and_a_missing_pose_topic(tmp_path):
    """map -> odom starts 1 s into the bag (the localiser was still starting): used before it too,
    and said; --pose-topic naming a topic the bag does not have is an error listing the pose topics."""
    truth = loop_drive(n=100, dt=0.1, radius=1.8)

    def late(bag):
        for t in truth[10:, 0]:
            bag.write("/tf", "tf2_msgs/msg/TFMessage", t, {"transforms": [
                {"header": {"stamp": stamp(t), "frame_id": "map"}, "child_frame_id": "odom",
                 "transform": {"translation": {"x": 0.0}, "rotation": {"w": 1.0}}}]})
    path = robot_bag(tmp_path / "late", WORLD, truth, tf_map=False, extra=late)
    seed = scenario_from_bag(path)
    assert any("the first correction is at t=1.0 s: it is used before it too" in n for n in seed.notes)
    with pytest.raises(BagImportError, match=r"no pose messages on '/amcl_pose' \(pose topics: none\); fix --pose-topic"):
        scenario_from_bag(path, pose_topic="/amcl_pose")


def _bag_with_map_missing_a_pillar(path):
    """A drifting loop around WORLD whose bag carries a /map (0.05 m cells, map frame) with every
    pillar but the one at (2.6, 2.6): the pillar put there that day."""
    truth = loop_drive(n=300, dt=0.1, radius=1.8)
    res, size = 0.05, 200
    ys, xs = np.mgrid[0:size, 0:size]
    cx, cy = -5 + (xs + 0.5) * res, -5 + (ys + 0.5) * res
    grid = np.zeros((size, size), np.int8)
    for x, y, r, _ in WORLD.pillars:
        if (x, y) != (2.6, 2.6):
            grid[np.hypot(cx - x, cy - y) <= r] = 100

    def known(bag):
        bag.write("/map", "nav_msgs/msg/OccupancyGrid", 0.0, {
            "header": {"stamp": stamp(0.0), "frame_id": "map"},
            "info": {"resolution": res, "width": size, "height": size,
                     "origin": {"position": {"x": -5.0, "y": -5.0}, "orientation": {"w": 1.0}}},
            "data": grid.reshape(-1)})
    return robot_bag(path, WORLD, truth, drift=_drift(truth), extra=known)


def test_obstacles_not_on_the_bags_map_are_named(tmp_path):
    """The bag's /map has every pillar but the one at (2.6, 2.6), put there that day: the note names it."""
    seed = scenario_from_bag(_bag_with_map_missing_a_pillar(tmp_path / "m"))
    note = next(n for n in seed.notes if n.startswith("/map (200 x 200 cells of 0.05 m)"))
    assert "1 of 6 obstacles were not on the map that day" in note and "at (2.60, 2.60)" in note, note
    # in the odometry frame the map is not compared (another frame), and that is said
    seed = scenario_from_bag(tmp_path / "m", frame="odom")
    assert any("/map is in frame 'map' and the seed in 'odom'" in n for n in seed.notes)


def test_the_bags_map_is_the_fixed_background_and_the_new_pillar_searchable(tmp_path):
    """With the /map in the seed's frame: the map's pillars are a fixed background (search: frozen),
    of the scans' obstacles only the pillar put there that day is kept, and the search moves only it."""
    from pytest_navscenario.scenario.geometry import obstacle_polygon
    from pytest_navscenario.search.space import SearchSpace
    from shapely.geometry import Point

    seed = scenario_from_bag(_bag_with_map_missing_a_pillar(tmp_path / "m"))
    obs = seed.scenario.obstacles
    frozen = set(seed.scenario.search["frozen"])
    from_map = [o for o in obs if o.name in frozen]
    kept = [o for o in obs if o.name not in frozen]
    assert all(o.name.startswith("map") for o in from_map) and len(from_map) == 5   # one polygon per pillar
    for x, y, r, _ in WORLD.pillars:
        if (x, y) != (2.6, 2.6):
            hits = [o for o in from_map if obstacle_polygon(o).intersection(Point(x, y).buffer(r)).area > 0.8 * math.pi * r * r]
            assert len(hits) == 1, (x, y)
    assert len(kept) == 1 and isinstance(kept[0], CylinderObstacle)
    assert (kept[0].x, kept[0].y, kept[0].radius) == pytest.approx((2.6, 2.6, 0.25), abs=0.05)
    assert {p.part for p in SearchSpace(seed.scenario).params if p.part.startswith("obstacle:")} == {f"obstacle:{kept[0].name}"}
    assert any("/map is the fixed background: 5 obstacles within 3 m of the driven path; of the sensors' "
               "obstacles the 1 not on the map are kept" in n for n in seed.notes), seed.notes
