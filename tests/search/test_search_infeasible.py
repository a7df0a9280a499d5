"""Issue 24: the search discards candidates whose shortest way cannot be driven within the timeout
at the robot's top speed, or whose moving obstacle walks through a static one, and counts them by
reason (the same checks as a hand-written scenario's, verdict/feasibility.py)."""
from __future__ import annotations

from pathlib import Path

from straight_planner import Straight

from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.search.engine import run_search
from pytest_navscenario.search.space import SearchSpace, invalid_reason


# scenario texts kept as .txt: as .yaml the project's own test run would collect them as scenarios
DATA = Path(__file__).resolve().parents[1] / "data" / "infeasible"
LONG = (DATA / "long.txt").read_text()                   # 50 m to drive in 30 s at 1.1 m/s
THROUGH_WALL = (DATA / "through_wall.txt").read_text()   # a person walking through a wall


def test_the_search_discards_such_candidates_and_counts_them():
    seed = loads_scenario(THROUGH_WALL.replace("[[1, 2], [5, 2]]", "[[1, 2], [1, 3.5], [5, 3.5]]")
                          .replace("  goal: {x: 6, y: 0}", "  goal: {x: 6, y: 0}\n  timeout: 14")
                          + "search: {obstacle_dy: [0, 1.5], obstacle_dx: 0, obstacle_size: 0, obstacle_yaw: 0, "
                            "insert: 2, insert_margin: 0.5, frozen: [person]}\n",
                          "s.yaml", name="s")
    assert invalid_reason(seed) is None
    space = SearchSpace(seed)
    moved = space.apply(tuple(1.0 if p.name.endswith("dy") else 0.0 for p in space.params))
    assert invalid_reason(moved) == "mover-through:person"       # the wall moved into the person's way
    report = run_search(seed, Straight, budget=8, seed_value=2, strategy="random", shrink_budget=0)
    assert report.discarded.get("mover-through", 0) > 0 and report.discarded.get("too-slow", 0) >= 0
    for c in report.candidates:
        assert invalid_reason(space.apply(c.offsets)) is None


def test_a_too_slow_candidate_is_discarded():
    seed = loads_scenario(LONG.replace("goal: {x: 50, y: 0}", "goal: {x: 20, y: 0}").replace("timeout: 30", "timeout: 18")
                          + "obstacles:\n  - {type: box, name: door, x: 10, y: 5, length: 0.4, width: 8}\n", "t.yaml")
    assert invalid_reason(seed) is None                          # the straight line is free: 19.7 m in 17.6 s
    space = SearchSpace(seed, {"obstacle_dy": [-5, 0], "obstacle_dx": 0, "obstacle_size": 0, "obstacle_yaw": 0,
                               "insert": 0})
    blocked = space.apply(tuple(-5.0 if p.name.endswith("dy") else 0.0 for p in space.params))
    assert invalid_reason(blocked) == "too-slow"                 # the door across the line: a detour too long
