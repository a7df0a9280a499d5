"""evolve's ``nudge`` (search/strategies/aim.py): what the parent's episode showed decides what moves
and where. The obstacle its planner reacted to moves a few centimetres across and along the way
where the robot hesitated; nothing else moves."""
import math
import random

from pytest_navscenario.search.strategies.aim import NUDGE_SD, _hesitation
from pytest_navscenario.search.strategies.evolve import Evolve
from pytest_navscenario.search.space import SearchSpace

from test_search_loop import _parent, _report, lane  # noqa: F401  (the lane seed and its episode)


def test_a_hesitation_is_the_slowest_moment_between_start_and_end():
    steady = [(0.0, 0.25 * k) for k in range(40)]
    assert _hesitation(steady) is None                         # the same speed throughout
    slowed = list(steady)
    for k in range(21, 40):
        slowed[k] = (0.0, slowed[k][1] - 0.2)                  # from sample 21 on, 0.2 m less: sample 20->21 crawls
    assert _hesitation(slowed) == 20
    braking = steady[:37] + [(0.0, 9.0), (0.0, 9.01), (0.0, 9.02)]   # slow only at the very end: arriving
    assert _hesitation(braking) is None


def test_nudge_moves_the_obstacle_the_planner_reacted_to_a_few_centimetres(lane):  # noqa: F811
    space = SearchSpace(lane, {"insert": 0, "remove": 0})
    evo = Evolve(space, _report(space), 10, 0)
    parent = _parent(lane, space)
    assert parent.culprit == "crate"
    before = space.apply(parent.offsets).obstacle("crate")
    steps = []
    for k in range(40):
        offsets = evo._nudge(parent, random.Random(k))
        assert space.clip(offsets) == offsets
        after = space.apply(offsets)
        crate = after.obstacle("crate")
        steps.append(math.hypot(crate.x - before.x, crate.y - before.y))
        assert (crate.length, crate.width, crate.yaw) == (before.length, before.width, before.yaw)
    assert 0 < max(steps) <= 5 * NUDGE_SD and sum(steps) / len(steps) < 2 * NUDGE_SD
