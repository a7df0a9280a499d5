"""Issue 17, a seed small enough to search: neighbouring pieces merged into one simplified polygon,
the obstacles near the driven path searchable, the rest a fixed background (``search: frozen``)
that the search does not move. Checked against the known world the bag was generated from."""
from __future__ import annotations

import math

import numpy as np
import pytest
from ros_synthetic import World, robot_bag
from shapely.geometry import Point, box
from shapely.ops import unary_union

from pytest_navscenario.cli import main
from pytest_navscenario.ros.bag_import import scenario_from_bag
from pytest_navscenario.scenario.geometry import obstacle_polygon
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.scenario.model import CylinderObstacle, PolygonObstacle
from pytest_navscenario.search.space import SearchSpace

ROW = [(0.5, 1.0, 1.6, 0.3, 0.0, 1.0), (1.15, 0.55, 0.3, 0.6, 0.0, 1.0)]   # an L-shaped counter
WORLD = World(pillars=[(1.5, -0.8, 0.2, 1.0), (4.0, 4.0, 0.3, 1.0)], boxes=ROW)


def _drive():
    t = np.arange(60) * 0.1
    return np.stack([t, -1.0 + 0.6 * t, 0 * t, 0 * t], 1)   # along y = 0, x from -1 to 2.5


@pytest.fixture(scope="module")
def seed_file(tmp_path_factory):
    folder = tmp_path_factory.mktemp("size")
    bag = robot_bag(folder / "row", WORLD, _drive())
    out = folder / "row.yaml"
    assert main(["from-bag", str(bag), "-o", str(out)]) == 0
    return out


def test_an_l_shaped_counter_becomes_one_polygon_on_the_truth(seed_file):
    """Seen from the path, the counter is five wall pieces (the fit without merging); merged, one
    simplified polygon whose outline lies on the counter."""
    obs = load_scenario(seed_file).obstacles
    row = [o for o in obs if 0.2 < o.y < 1.2 and -0.4 < o.x < 1.4]
    assert len(row) == 1 and isinstance(row[0], PolygonObstacle), obs
    poly = obstacle_polygon(row[0])
    truth = unary_union([box(x - ln / 2, y - w / 2, x + ln / 2, y + w / 2) for x, y, ln, w, _, _ in ROW])
    # on the counter; wall pieces are 0.15 m thick behind the seen face, so an end seen edge-on may
    # stick out by up to that
    assert truth.buffer(0.16).contains(poly)
    # and it holds the faces the robot saw: A's south face and B's south and west faces
    from shapely.geometry import LineString
    for face in (LineString([(-0.25, 0.85), (0.95, 0.85)]), LineString([(1.05, 0.25), (1.25, 0.25)]),
                 LineString([(1.0, 0.3), (1.0, 0.8)])):
        assert poly.buffer(0.04).contains(face), face
    x0, y0, x1, _ = poly.bounds
    assert (x0, y0, x1) == pytest.approx((-0.3, 0.25, 1.3), abs=0.16)   # the wall thickness again
    # simplified, not a cell outline (14 since issue 37: the end seen edge-on keeps the cells grazing beams carved)
    assert len(row[0].points) <= 16


def test_near_obstacles_are_searchable_and_far_ones_a_fixed_background(seed_file):
    seed = load_scenario(seed_file)
    far = [o for o in seed.obstacles if math.hypot(o.x - 4.0, o.y - 4.0) < 0.3]
    near = [o for o in seed.obstacles if o not in far]
    assert len(far) == 1 and isinstance(far[0], CylinderObstacle)
    assert seed.search == {"frozen": [far[0].name]}
    space = SearchSpace(seed)
    moved = {p.part for p in space.params}
    assert f"obstacle:{far[0].name}" not in moved
    assert {f"obstacle:{o.name}" for o in near} <= moved
    pillar = [o for o in near if isinstance(o, CylinderObstacle)]
    assert len(pillar) == 1 and (pillar[0].x, pillar[0].y) == pytest.approx((1.5, -0.8), abs=0.04)


def test_the_notes_say_which_are_searchable(tmp_path):
    seed = scenario_from_bag(robot_bag(tmp_path / "b", WORLD, _drive()))
    # the counter's faces come out as one wall outline (before issue 24: five wall boxes, then merged)
    assert any(n.endswith("-> 3 clusters -> 2 cylinders, 0 boxes, 1 wall outlines") for n in seed.notes), seed.notes
    assert any(n.startswith("2 obstacle(s) within 1 m of the driven path are searchable; 1 are a fixed background")
               for n in seed.notes), seed.notes
    # every obstacle lies on a true object
    truth = [Point(x, y).buffer(r) for x, y, r, _ in WORLD.pillars] + \
        [box(x - ln / 2, y - w / 2, x + ln / 2, y + w / 2) for x, y, ln, w, _, _ in WORLD.boxes]
    for o in seed.scenario.obstacles:
        assert min(obstacle_polygon(o).distance(t) for t in truth) < 0.02, o


def test_map_background_takes_the_window_near_the_path_of_a_turned_map():
    """A map turned 90 degrees with its origin at (1, 2): a block of cells (rows 10-11, columns
    20-23 of 0.1 m) lies at (-0.1, 4.2) in the world, 0.4 m along the map's x (now world y); a block
    30 m away is outside the window and left out."""
    from pytest_navscenario.ros.bag_import.known_map import KnownMap, map_background

    occ = np.zeros((400, 400), bool)
    occ[10:12, 20:24] = True
    occ[300:302, 300:302] = True
    m = KnownMap(frame="map", topic="/map", occupied=occ, resolution=0.1, origin=(1.0, 2.0, math.pi / 2))
    boxes = map_background(m, np.array([[0.0, 3.0], [0.5, 4.0]]), reach=3.0)
    assert len(boxes) == 1
    b = boxes[0]
    assert (b.x, b.y, b.length, b.width, b.yaw) == pytest.approx((-0.1, 4.2, 0.4, 0.2, 90.0), abs=1e-9)


def test_a_gap_the_robot_drove_through_is_not_closed():
    """Two crates 0.28 m apart (closer than the merge gap) with the robot driving between them: a
    merged outline would cover its path, so they stay two obstacles."""
    from pytest_navscenario.ros.bag_import.simplify import merge_neighbours
    from pytest_navscenario.scenario.model import BoxObstacle

    crates = [BoxObstacle("a", -0.34, 1.0, 0.4, 0.4), BoxObstacle("b", 0.34, 1.0, 0.4, 0.4)]
    path = np.stack([np.zeros(21), np.linspace(0.0, 2.0, 21)], 1)        # north along x = 0
    kept, n = merge_neighbours(crates, path, clearance=0.1)
    assert n == 0 and [o.name for o in kept] == ["a1", "b1"]
    elsewhere = np.stack([np.full(21, 3.0), np.linspace(0.0, 2.0, 21)], 1)
    merged, n = merge_neighbours(crates, elsewhere, clearance=0.1)
    assert n == 1 and len(merged) == 1 and isinstance(merged[0], PolygonObstacle)
    assert obstacle_polygon(merged[0]).area == pytest.approx(0.4 * (0.68 + 0.4), rel=0.02)   # the gap closed
