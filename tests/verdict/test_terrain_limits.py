"""The verdict at the terrain's documented limits, in bounded time and memory (issue 38, part 1):
a platform of 999999 m (its barrier map took 23.5 GB), 5000 platforms (the element limit: over 300
s), steep ground found on a 1024^2 grid whatever its shape (a winding patch took minutes)."""
from __future__ import annotations

import math
import time
import tracemalloc
import warnings

import numpy as np
import pytest

from pytest_navscenario.scenario.ground.crossing import Capability, _label, steep_cells
from pytest_navscenario.scenario.model import Footprint, Mission, Pose, Robot, Scenario
from pytest_navscenario.scenario.bodies import LeggedBody
from pytest_navscenario.scenario.terrain import Platform
from pytest_navscenario.verdict.feasibility import impassable_reason
from pytest_navscenario.verdict.paths import shortest_path
from pytest_navscenario.scenario.ground.traversable import MAX_BARRIERS, TerrainTooFineWarning, barriers

LEGGED = LeggedBody(max_step=0.2, max_slope=30.0, max_gap=0.3)
CAP = Capability(0.2, 30.0, 0.3)


def scene(terrain, start=(-2.0, -2.0), goal=(12.0, 0.0)) -> Scenario:
    return Scenario(version=1, name="t", robot=Robot(footprint=Footprint(radius=0.25), drive="diff", body=LEGGED),
                    mission=Mission(start=Pose(*start), goal=Pose(*goal), timeout=600.0), terrain=tuple(terrain))


def test_a_platform_of_a_million_metres_has_its_four_faces_in_bounded_time_and_memory():
    huge = scene([Platform("slab", 0.0, 0.0, length=999999.0, width=999999.0, height=0.5)], start=(0, 0), goal=(5, 0))
    tracemalloc.start()
    t0 = time.perf_counter()
    walls = barriers(huge, CAP)
    took = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert took < 30 and peak < 600e6, (took, peak)
    assert len(walls) == 4 and all(w.length == pytest.approx(999999.0, rel=1e-6) for w in walls)


def test_a_long_edge_is_probed_finely_where_another_element_meets_it():
    """A 3000 m platform with a 2 m block of the same height against its side: its face stops
    where the block begins, to the 5 cm of the probing, as on a short edge."""
    side = scene([Platform("long", 0.0, 0.0, length=3000.0, width=4.0, height=0.5),
                  Platform("block", 1234.5, 3.0, length=2.0, width=2.0, height=0.5)])
    walls = [w for w in barriers(side, CAP) if w.name.startswith("platform 'long'") and abs(w.y - 2.0) < 0.05]
    assert len(walls) == 2
    ends = sorted([w.x - w.length / 2 for w in walls] + [w.x + w.length / 2 for w in walls])
    assert ends[1] == pytest.approx(1233.5, abs=0.06) and ends[2] == pytest.approx(1235.5, abs=0.06)


def test_5000_platforms_get_a_verdict_in_bounded_time_with_a_warning():
    side = 71
    plates = [Platform(f"p{i}", (i % side) * 1.2 + 0.3, (i // side) * 1.2 + (0.3 if (i % side) % 2 else 0.6),
                       length=0.5, width=0.5, height=0.3) for i in range(5000)]
    field = scene(plates, start=(-2, -2), goal=(side * 1.2 + 1, side * 1.2 + 1))
    t0 = time.perf_counter()
    with pytest.warns(TerrainTooFineWarning, match=f"more than {MAX_BARRIERS} stretches"):
        assert barriers(field) == ()
    assert shortest_path(field) is not None and impassable_reason(field) is None
    assert time.perf_counter() - t0 < 60


def _propagated(mask):
    """The labels by propagating minima (the former implementation): the reference."""
    big = mask.size
    labels = np.where(mask, np.arange(big).reshape(mask.shape), big)
    while True:
        padded = np.pad(labels, 1, constant_values=big)
        best = labels.copy()
        for oy in (-1, 0, 1):
            for ox in (-1, 0, 1):
                best = np.minimum(best, padded[1 + oy:1 + oy + mask.shape[0], 1 + ox:1 + ox + mask.shape[1]])
        best = np.where(mask, best, big)
        if np.array_equal(best, labels):
            return np.where(mask, labels, -1)
        labels = best


def test_steep_patches_are_labelled_as_before_and_a_winding_one_on_1024_squared_in_seconds():
    rng = np.random.default_rng(38)
    for _ in range(200):
        mask = rng.random(tuple(rng.integers(1, 30, 2))) < rng.random()
        assert np.array_equal(_label(mask), _propagated(mask))
    snake = np.zeros((1024, 1024), dtype=bool)
    snake[::2] = True
    for r in range(1, 1024, 2):
        snake[r, 1023 if (r // 2) % 2 == 0 else 0] = True
    h = np.where(snake, np.cumsum(snake.ravel()).reshape(snake.shape) * 1e-3, 0.0)   # rising along it
    t0 = time.perf_counter()
    steep = steep_cells(h * 50, 0.01, 0.01, CAP)
    assert time.perf_counter() - t0 < 30
    assert steep.any()
