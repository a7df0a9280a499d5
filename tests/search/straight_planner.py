"""Test subjects for the search tests: a straight-line driver that ignores obstacles (easy to
break: a small shift of an obstacle onto its line is a failure). Imported by test_search.py and
copied into pytester projects by test_search_plugin.py, so both drive the same planner."""
import math


class Straight:
    """Drives straight at its target at 1 m/s, blind to obstacles."""
    name = "straight"
    version = "1.0"

    def reset(self, scenario):
        pass

    def act(self, obs):
        x, y, yaw = obs.pose
        dx, dy = obs.target[0] - x, obs.target[1] - y
        dist = math.hypot(dx, dy) or 1.0
        c, s = math.cos(yaw), math.sin(yaw)
        return ((c * dx + s * dy) / dist, (-s * dx + c * dy) / dist, 0.0)


CALLS = [0]


def interrupted_after_five():
    """A subject whose sixth episode is interrupted as if by Ctrl-C."""
    CALLS[0] += 1
    if CALLS[0] > 5:
        raise KeyboardInterrupt
    return Straight()


class StraightBatch(Straight):
    """The straight driver with the batch protocol too (issue 27): one call a tick for a batch."""
    name = "straight-batch"
    calls = []          # the size of every act_batch call, for the tests

    def reset_batch(self, scenarios):
        self.count = len(scenarios)

    def act_batch(self, ids, observations):
        StraightBatch.calls.append(len(ids))
        return [self.act(obs) for obs in observations]
