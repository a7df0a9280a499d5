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


class Wobbly(Straight):
    """The straight driver, but in one episode out of five (drawn from its first, noisy scan: a
    different draw under each noise seed) it passes the middle of its way (y from 1 to 4 m) on a
    line 0.25 m to the right (+x). A crate near its line stops it every time; one a little further
    right only when it wobbles: a knife-edge, failing about once in five runs."""
    SHIFT = 0.25
    CHANCE = 0.2

    def reset(self, scenario):
        self.shift = None

    def act(self, obs):
        if self.shift is None:
            draw = (hash(tuple(round(float(r), 6) for r in obs.ranges)) % 10_000) / 10_000
            self.shift = self.SHIFT if draw < self.CHANCE else 0.0
        x, y, yaw = obs.pose
        lane = self.shift if 1.0 <= y <= 4.0 else 0.0
        vx, vy = max(-1.0, min(1.0, 4.0 * (lane - x))), 1.0 if y < obs.target[1] else 0.0
        if y >= obs.target[1] - 0.05:
            vx, vy = obs.target[0] - x, obs.target[1] - y
        norm = max(1.0, math.hypot(vx, vy))
        c, s = math.cos(yaw), math.sin(yaw)
        vx, vy = vx / norm, vy / norm
        return (c * vx + s * vy, -s * vx + c * vy, 0.0)


class Picky(Straight):
    """Gives up (raises, a subject error) at its first tick when the crate is near its line: always
    when the crate's centre is less than 0.6 m right of it, in one episode out of five (drawn from
    its first, noisy scan: a different draw under each noise seed) when it is 0.6 to 1.2 m right:
    a knife-edge. Otherwise it drives straight to the goal. Every failure looks the same (a subject
    error at the start), so a robust failure and a knife-edge one share their cause signature."""
    CHANCE = 0.2

    def act(self, obs):
        if obs.tick == 0:
            crate = next(o for o in obs.obstacles if o.name == "crate")
            draw = (hash(tuple(round(float(r), 6) for r in obs.ranges)) % 10_000) / 10_000
            if crate.x < 0.6 or (crate.x < 1.2 and draw < self.CHANCE):
                raise RuntimeError(f"the crate at x = {crate.x:.2f} is in the way")
        return super().act(obs)


class Careful:
    """A later version of the planner: it avoids the crate (the built-in DWA), but gives up at its
    first tick in about one run out of three (a draw from its noisy first scan)."""
    CHANCE = 0.35

    def __init__(self):
        from pytest_navscenario.subjects.planners.dwa import DynamicWindowPlanner
        self.inner = DynamicWindowPlanner()

    def reset(self, scenario):
        self.inner.reset(scenario)

    def act(self, obs):
        if obs.tick == 0 and (hash(tuple(round(float(r), 6) for r in obs.ranges)) % 10_000) / 10_000 < self.CHANCE:
            raise RuntimeError("gave up")
        return self.inner.act(obs)


class StraightBatch(Straight):
    """The straight driver with the batch protocol too (issue 27): one call a tick for a batch."""
    name = "straight-batch"
    calls = []          # the size of every act_batch call, for the tests

    def reset_batch(self, scenarios):
        self.count = len(scenarios)

    def act_batch(self, ids, observations):
        StraightBatch.calls.append(len(ids))
        return [self.act(obs) for obs in observations]


class PickyBatch(Picky):
    """``Picky`` with the batch protocol: one call a tick for a batch, each episode deciding from
    its own noisy first scan. Where Picky gives up it stands still (the episode ends stuck, the
    same batched or not) rather than raising, which would fail the whole batch call."""
    name = "picky-batch"
    calls = []          # the size of every act_batch call, for the tests

    def reset(self, scenario):
        self.stay = {}

    def act(self, obs, key=0):
        if obs.tick == 0:
            try:
                super().act(obs)
                self.stay[key] = False
            except RuntimeError:
                self.stay[key] = True
        return (0.0, 0.0, 0.0) if self.stay[key] else super().act(obs)

    def reset_batch(self, scenarios):
        self.stay = {}

    def act_batch(self, ids, observations):
        PickyBatch.calls.append(len(ids))
        return [self.act(obs, i) for i, obs in zip(ids, observations)]
