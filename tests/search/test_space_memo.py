"""SearchSpace.apply remembers recent layouts (a proposal is applied by its validity check, its
ranking and its episode), bounded so that a seed of many obstacles does not hold hundreds of
copies of itself (issue 35)."""
from __future__ import annotations

import random
import tracemalloc

from pytest_navscenario import loads_scenario
from pytest_navscenario.search.space import SearchSpace

ROBOT = """
robot:
  footprint: {shape: box, length: 0.9, width: 0.5}
  drive: omni
  limits: {max_speed: 1.0, max_lateral_speed: 0.5, max_yaw_rate: 90.0, max_accel: 2.0, max_yaw_accel: 180.0}
mission:
  start: {x: 0.0, y: 0.0, yaw: 90.0}
  goal: {x: 0.0, y: 10.0, yaw: 90.0}
  timeout: 30.0
search: {insert: 0}
"""


def seed_with(n: int):
    rows = "\n".join(f"  - {{type: box, name: b{k}, x: {3 + (k % 40) * 0.6:.1f}, y: {(k // 40) * 0.6:.1f}, "
                     f"length: 0.3, width: 0.3}}" for k in range(n))
    return loads_scenario(f"version: 1\n{ROBOT}obstacles:\n{rows}\n", "many.yaml")


def layouts(space: SearchSpace, n: int, seed: int = 0) -> list[tuple[float, ...]]:
    rnd = random.Random(seed)
    return [space.clip(rnd.uniform(p.lo, p.hi) for p in space.params) for _ in range(n)]


def test_the_same_offsets_give_the_same_scenario_and_other_offsets_another():
    space = SearchSpace(seed_with(3))
    a, b = layouts(space, 2)
    first = space.apply(a)
    assert space.apply(a) is first
    assert space.apply(b) is not first and space.apply(b) != first


def test_a_seed_of_many_obstacles_holds_few_layouts():
    """1000 obstacles, 60 distinct layouts applied and dropped: what the space still holds stays
    near 20 layouts' worth (512 would be a quarter of a gigabyte at the obstacle limit)."""
    space = SearchSpace(seed_with(1000))
    todo = layouts(space, 61)
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        kept = space.apply(todo[0])
        one = tracemalloc.get_traced_memory()[0] - base
        del kept
        for offsets in todo[1:]:
            space.apply(offsets)
        held = tracemalloc.get_traced_memory()[0] - base
    finally:
        tracemalloc.stop()
    assert held < 30 * one, (held, one)
