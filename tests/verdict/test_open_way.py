"""``open_way`` (verdict/open_way.py) answers as paths.py does: a layout it calls open at a margin
has a way there (passage_room passes that margin, path_exists is True) no longer than the length it
gives; it calls the sparse layouts a search mostly meets open, and never a closed one."""
import random

import pytest

from pytest_navscenario.scenario.model import (BoxObstacle, CylinderObstacle, Footprint, Mission, Pose,
                                               PolygonObstacle, Robot, Scenario)
from pytest_navscenario.verdict import paths
from pytest_navscenario.verdict.open_way import open_way

LEVELS = (0.05, 0.1, 0.15, 0.2, 0.3, 0.45, 0.6)


def layout(rnd, n, footprint, spread=2.5, ys=(1.0, 9.0), waypoints=()):
    obstacles = []
    for k in range(n):
        x, y = rnd.uniform(-spread, spread), rnd.uniform(*ys)
        kind = rnd.random()
        if kind < 0.45:
            obstacles.append(BoxObstacle(f"b{k}", x, y, rnd.uniform(0.3, 1.5), rnd.uniform(0.3, 1.5),
                                         yaw=rnd.uniform(-90, 90)))
        elif kind < 0.9:
            obstacles.append(CylinderObstacle(f"c{k}", x, y, rnd.uniform(0.15, 0.7)))
        else:
            obstacles.append(PolygonObstacle(f"p{k}", x, y, ((0, 0), (0.8, 0), (0.2, 0.6))))
    return Scenario(mission=Mission(start=Pose(0, 0, 90), goal=Pose(0, 10, 90), timeout=60.0,
                                    waypoints=tuple(Pose(*w) for w in waypoints)),
                    obstacles=tuple(obstacles), robot=Robot(footprint=footprint))


@pytest.mark.parametrize("footprint", [Footprint(), Footprint(shape="circle", radius=0.3)])
@pytest.mark.parametrize("n", [2, 4, 8])
def test_an_open_layout_has_the_way_paths_finds_no_longer_than_said(footprint, n):
    rnd = random.Random(n)
    opened = 0
    for k in range(150):
        sc = layout(rnd, n, footprint, waypoints=[(1.5, 5.0)] if k % 3 == 0 else ())
        for margin in (0.0, max(LEVELS)):
            length = open_way(sc, margin)
            if length is None:
                continue
            opened += 1
            best = paths.shortest_path(sc)
            assert best is not None and best.length <= length + 1e-9
            if margin:
                assert paths.passage_room(sc, LEVELS) == margin
    assert opened >= 20, opened


def test_sparse_layouts_are_open_and_a_closed_ring_never_is():
    rnd = random.Random(3)
    sparse = [layout(rnd, 2, Footprint(), spread=3.0, ys=(3.5, 6.5)) for _ in range(30)]   # stops clear
    assert all(open_way(sc, 0.6) is not None for sc in sparse)
    ring = tuple(BoxObstacle(f"w{k}", x, y, 0.8, 0.8) for k, (x, y) in enumerate(
        [(-1, -1), (0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0)]))
    closed = Scenario(mission=Mission(start=Pose(0, 0, 90), goal=Pose(0, 10, 90)), obstacles=ring,
                      robot=Robot(footprint=Footprint()))
    assert not paths.path_exists(closed)
    assert open_way(closed, 0.0) is None
