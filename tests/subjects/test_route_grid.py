"""The route on the lidar grid (subjects/planners/_route.py) that ``dwa`` follows when stalled: its
wavefront is a breadth-first search, and the carrot follows it downhill, whatever the grid."""
from __future__ import annotations

from collections import deque

import numpy as np
import pytest

from pytest_navscenario.subjects.planners._route import _STEPS, LidarGrid, _wavefront


def reference_wavefront(open_, seed, near, limit, ahead):
    """Plain breadth-first search (8-connected) over every cell, then the planner's cut-off: the
    field keeps the steps up to ``ahead`` after the wave first reaches a near cell (or ``limit``)."""
    h, w = open_.shape
    dist = np.full((h, w), -1, dtype=np.int64)
    queue = deque()
    for i, j in zip(*np.nonzero(seed)):
        dist[i, j] = 0
        queue.append((i, j))
    while queue:
        i, j = queue.popleft()
        for di, dj in _STEPS:
            ni, nj = i + di, j + dj
            if 0 <= ni < h and 0 <= nj < w and open_[ni, nj] and dist[ni, nj] < 0:
                dist[ni, nj] = dist[i, j] + 1
                queue.append((ni, nj))
    reached = dist[near & (dist >= 0)]
    first = int(reached.min()) if reached.size else None
    extra = None if first is None or max(first, 1) > limit else max(first, 1) + ahead
    cut = min(extra if extra is not None else limit, limit)
    field = np.where((dist >= 0) & (dist <= cut), dist, -1)
    return extra, field


@pytest.mark.parametrize("trial", range(40))
def test_the_wavefront_is_a_breadth_first_search_with_the_planners_cut_off(trial):
    rng = np.random.default_rng(trial)
    h, w = rng.integers(3, 40, size=2)
    free = rng.random((h, w)) > rng.uniform(0.0, 0.5)
    seed = np.zeros((h, w), dtype=bool)
    seed[rng.integers(h), rng.integers(w)] = True
    near = np.zeros((h, w), dtype=bool)
    if trial % 5:                                  # every fifth: the robot's surroundings are off the grid
        ri, rj = rng.integers(h), rng.integers(w)
        near[max(ri - 2, 0):ri + 3, max(rj - 2, 0):rj + 3] = True
    limit, ahead = int(rng.integers(1, 4 * (h + w))), int(rng.integers(0, 15))
    field = np.full((h, w), -1, dtype=np.int32)
    field[seed] = 0
    extra, flat = _wavefront(field, free & ~seed, seed, near, limit, ahead)
    want_extra, want = reference_wavefront(free & ~seed, seed, near, limit, ahead)
    assert extra == want_extra
    assert np.array_equal(field, want)
    # the flat copy the carrot walks: the field with a border of -1
    assert np.array_equal(flat.reshape(h + 2, w + 2), np.pad(field, 1, constant_values=-1))


def test_the_carrot_follows_the_route_downhill_round_a_wall():
    """A wall between robot and target with a gap at one end: the route and the carrot go
    through the gap, not straight at the target."""
    grid = LidarGrid(np.array([[0.0, 0.0], [4.0, 0.0]]), border=2.0, inflation=0.1)
    wall = np.array([[2.0, y] for y in np.arange(-2.0, 1.0, 0.05)])     # x = 2 from y = -2 to 1
    grid.mark(0.0, 0.0, 1.0, 0.0, wall.T)
    assert grid.plan((0.0, 0.0), (4.0, 0.0), 0.2)
    x, y = grid.carrot((0.0, 0.0), 1.5)
    assert y > 1.0                      # through the gap above the wall's end (y = 1), not at y = 0
    # steps to the target fall by one per cell along the way the carrot went
    f = grid.field
    i, j = grid.cell(x, y)
    ri, rj = grid.cell(0.0, 0.0)
    i0, j0 = grid.box
    assert 0 <= f[i - i0, j - j0] < f[ri - i0, rj - j0]


@pytest.mark.parametrize("trial", range(4))
def test_a_robot_off_the_route_heads_for_the_nearest_route_cell(trial):
    # in a gap too narrow for the route, the carrot is the nearest reached cell (the first in
    # row-major order on ties), looked for in a growing window: the answer the whole field gives
    from pytest_navscenario.subjects.planners._route import _closest_reached

    rng = np.random.default_rng(trial)
    for _ in range(2000):
        h, w = (int(v) for v in rng.integers(1, 50, size=2))
        field = np.full((h, w), -1, dtype=np.int32)
        field[rng.random((h, w)) < rng.choice([0.0, 0.002, 0.02, 0.3])] = 5
        ri, rj = int(rng.integers(-20, h + 20)), int(rng.integers(-20, w + 20))   # inside or beyond it
        reached = np.argwhere(field >= 0)
        want = (tuple(int(v) for v in reached[np.argmin(((reached - (ri, rj)) ** 2).sum(axis=1))])
                if len(reached) else None)
        assert _closest_reached(field, ri, rj, int(rng.integers(1, 10))) == want
