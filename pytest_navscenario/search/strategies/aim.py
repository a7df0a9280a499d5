"""The operators of ``evolve`` that aim at what the seed's episode showed (PHYS-FUZZ style): move an
obstacle onto the robot's path at or a moment after its closest approach (place), insert a new one
there (insert), squeeze one just beside the path (squeeze), wall the path off with two inserted
boxes (barrier), retime a moving obstacle to reach the path when the robot was there (retime);
carry a failure's inserted box along the route (shift) or crowd the start/goal footprint (crowd);
nudge the obstacle the planner reacted to a few centimetres where the robot hesitated (nudge).
Where they aim (which obstacle, which quarter of the route) is a novelty bandit, ``_Targets``.
A mixin of ``evolve.Evolve``: the methods read the strategy's archive, route and bandits.
"""
from __future__ import annotations

import math
import random
from typing import Any, Sequence

from ..space import FLAG_ON, INSERT_PREFIX, SearchSpace

QUARTERS = 4                   # route quarters: the places a target aims at (fitness.PLACE_BINS)
SQUEEZE_BAND = (1.0, 1.3)      # squeeze: obstacle centre at this many (robot half width + obstacle half)
                               # from the path: its face just clears the footprint's recorded pose
RETIME_STARTS = 21             # retime: start offsets tried across their range (and RETIME_SPEEDS speeds)
RETIME_SPEEDS = 5
RETIME_LAG = (-1.0, 0.5)       # s: the obstacle is aimed at where the robot was this much later
CROWD_GAP = 0.4                # m: crowd leaves at most this much between a box and the start/goal footprint
TARGET_PATHS = 256             # (parent, quarter, box) anchor lists _target remembers
SLOW_SHARE = 0.6               # nudge: a path step below this share of the median is a hesitation
NUDGE_SD = 0.04                # m: nudge's step across and along the robot's way (sd)
SHIFT_RADIUS = 2.0             # m: shift carries the inserted boxes this near the culprit along with it


class _Targets:
    """Novelty bandit over *where to put which obstacle*: one arm per (culprit, route quarter),
    culprit a movable seed obstacle or "inserted". An arm is rewarded for new failure signatures
    (a new way of failing), a little for a new closest call, and is divided down by the failures
    it re-created and by the known failing signatures already in its cell, so once a place has
    failed the budget moves on to places that have not."""

    def __init__(self, arms: Sequence[tuple[str, int]]):
        self.arms = list(arms)
        self.tries = {a: 0 for a in self.arms}
        self.credit = {a: 0.0 for a in self.arms}
        self.repeats = {a: 0 for a in self.arms}
        self.best = {a: math.inf for a in self.arms}

    def weight(self, arm: tuple[str, int], known: set[tuple]) -> float:
        filled = sum(1 for sig in known if _in_cell(sig, arm))
        return (self.credit[arm] + 1.0) / (self.tries[arm] + 2.0) / (1.0 + self.repeats[arm] + filled)

    def pick(self, rnd: random.Random, allowed: Sequence[tuple[str, int]], known: set[tuple]) -> tuple[str, int]:
        weights = [self.weight(a, known) for a in allowed]
        return _weighted_pick(allowed, weights, rnd.random() * sum(weights))

    def tell(self, arm: tuple[str, int], cand: Any, new_failure: bool) -> None:
        self.tries[arm] += 1
        if new_failure:
            self.credit[arm] += 1.0
        elif cand.failed:
            self.repeats[arm] += 1
        elif math.isfinite(cand.robustness) and cand.robustness < self.best[arm]:
            self.best[arm] = cand.robustness
            self.credit[arm] += 0.2


class AimedOperators:
    """The aimed operators of ``Evolve`` (see the module docstring)."""

    def _arms(self) -> _Targets:
        """The target arms: each movable seed obstacle in each route quarter it can reach (its
        dx/dy bounds around the seed route), and inserted boxes in every quarter."""
        if self.targets is None:
            route, space = self._route(), self.space
            samples = _route_samples(route)
            arms = []
            for group in self.movable:
                name = space.params[group[0]].part.split(":", 1)[1]
                x0, x1, y0, y1 = self._reach(group)
                arms += sorted({(name, _quarter(f)) for x, y, f in samples if x0 <= x <= x1 and y0 <= y <= y1})
            if self.slots:
                arms += [("inserted", q) for q in range(QUARTERS)]
            self.targets = _Targets(arms)
        return self.targets

    def _reach(self, group: Sequence[int]) -> tuple[float, float, float, float]:
        """Where the centre of the obstacle of ``group`` can go (x0, x1, y0, y1)."""
        space = self.space
        obs = space.seed.obstacle(space.params[group[0]].part.split(":", 1)[1])
        rng = {space.params[i].attr: (space.params[i].lo, space.params[i].hi) for i in group}
        return obs.x + rng["dx"][0], obs.x + rng["dx"][1], obs.y + rng["dy"][0], obs.y + rng["dy"][1]

    def _pick_arm(self, rnd: random.Random, inserted: bool) -> tuple[str, int] | None:
        arms = [a for a in self._arms().arms if (a[0] == "inserted") == inserted]
        if not arms:
            return None
        self.aim = self.targets.pick(rnd, arms, self._filled())
        self.aim_bandit = self.targets
        return self.aim

    def _target(self, parent: Any, rnd: random.Random, half: float, quarter: int | None,
                squeeze: bool = False, within: tuple | None = None) -> tuple[float, float, float, float]:
        """(x, y, path x, path y): a point beside the parent's path, in route quarter ``quarter`` (None: anywhere), where
        an obstacle of half size ``half`` would meet the robot: at or a moment after the closest
        approach (time-to-impact placement) when that lies in the quarter, else anywhere there
        (the seed's route where the parent never got). Sideways by up to 1.3 times the robot's
        half width plus ``half`` (overlapping the footprint: the robot must detour); with
        ``squeeze`` by 1.0-1.3 times that, so the obstacle just clears the recorded footprint and
        narrows the passage there. ``within`` (x0, x1, y0, y1): only path points in that box."""
        fp = self.space.seed.robot.footprint
        contact = (fp.radius if fp.shape == "circle" else fp.width / 2) + half
        path = self._target_path(parent, quarter, None if within is None else (within, contact))
        (px, py), (ux, uy) = self._anchor(parent, path, rnd)
        lateral = rnd.uniform(*SQUEEZE_BAND) * rnd.choice((-1.0, 1.0)) if squeeze else rnd.uniform(-1.3, 1.3)
        lateral *= contact
        return px - uy * lateral, py + ux * lateral, px, py

    def _target_path(self, parent: Any, quarter: int | None, within: tuple | None) -> list:
        """The points of the parent's path ``_target`` anchors at: in route quarter ``quarter``
        (the seed's route there where the parent never got), and with ``within`` (box, contact)
        those from which the band beside the path is in the box. The same for every proposal from
        one parent, so remembered (a parent's path is a tuple that never changes)."""
        memo = self._target_paths
        key = (id(parent.path), quarter, within)
        known = memo.get(key)
        if known is not None and known[0] is parent.path:
            return known[1]
        route = self._route()
        path = [p for p in parent.path[1:]] or [p[:2] for p in _route_samples(route)]
        if quarter is not None:
            inq = [p for p in path if _quarter(route.fraction(*p)) == quarter]
            path = inq or [p[:2] for p in _route_samples(route) if _quarter(p[2]) == quarter] or path
        if within is not None:   # path points from which the band beside the path is in the box
            box, contact = within
            path = [p for k, p in enumerate(path) if _beside_within(path, k, 1.15 * contact, box)] or path
        if len(memo) >= TARGET_PATHS:
            memo.clear()
        memo[key] = (parent.path, path)
        return path

    def _anchor(self, parent: Any, path: Sequence[tuple[float, float]], rnd: random.Random
                ) -> tuple[tuple[float, float], tuple[float, float]]:
        """A point of ``path`` and the unit direction of travel there: half the time at or a
        moment after the parent's closest approach (if it lies on ``path``), else anywhere."""
        route, n = self._route(), len(path)
        j = rnd.randrange(n)
        if parent.closest and rnd.random() < 0.5 and all(math.isfinite(v) for v in parent.closest[1:]):
            _, cx, cy = parent.closest
            j0 = min(range(n), key=lambda k: (path[k][0] - cx) ** 2 + (path[k][1] - cy) ** 2)
            if math.hypot(path[j0][0] - cx, path[j0][1] - cy) < 0.5:
                j = min(n - 1, j0 + rnd.randrange(0, max(2, n // 4)))
        a, b = path[max(0, j - 1)], path[min(n - 1, j + 1)]
        if a == b:   # a single point: along the route there
            f = route.fraction(*path[j])
            a, b = _route_point(route, f - 0.02), _route_point(route, f + 0.02)
        dx, dy = b[0] - a[0], b[1] - a[1]
        norm = math.hypot(dx, dy) or 1.0
        return (path[j][0], path[j][1]), (dx / norm, dy / norm)

    def _barrier(self, parent: Any, rnd: random.Random) -> tuple[float, ...]:
        """Two inserted boxes side by side across the parent's path (aligned with it, the gap
        between them narrower than the robot), in the quarter of a target arm: a wall wider than
        the robot that it must find its way around, where a reactive planner can be trapped."""
        space, offsets = self.space, list(parent.offsets)
        x0, y0, x1, y1 = space.region
        lo, hi = space.limits.insert_size
        arm = self._pick_arm(rnd, inserted=True)
        route = self._route()
        path = list(parent.path[1:]) or [p[:2] for p in _route_samples(route)]
        if arm is not None:
            path = [p for p in path if _quarter(route.fraction(*p)) == arm[1]] or \
                [p[:2] for p in _route_samples(route) if _quarter(p[2]) == arm[1]] or path
        (px, py), (ux, uy) = self._anchor(parent, path, rnd)
        fp = space.seed.robot.footprint
        robot_width = 2 * fp.radius if fp.shape == "circle" else fp.width
        sizes = [rnd.uniform(lo, hi) for _ in range(2)]
        gap = rnd.uniform(0.0, 0.8) * robot_width
        width = sum(sizes) + gap
        centre = rnd.uniform(-0.5, 0.5) * width      # the wall's middle, across the path
        laterals = (centre - width / 2 + sizes[0] / 2, centre + width / 2 - sizes[1] / 2)
        yaw = (math.degrees(math.atan2(uy, ux)) + 45.0) % 90.0 - 45.0   # a square's faces along the path
        for group, size, lateral in zip(self.slots[:2], sizes, laterals):
            values = {"on": 1.0, "size": size - lo, "yaw": yaw,
                      "x": px - uy * lateral - (x0 + x1) / 2, "y": py + ux * lateral - (y0 + y1) / 2}
            for i in group:
                offsets[i] = values.get(space.params[i].attr, offsets[i])
        return space.clip(offsets)

    def _nudge(self, parent: Any, rnd: random.Random) -> tuple[float, ...]:
        """Nudge the obstacle the parent's planner reacted to (its culprit, else the movable one
        nearest its closest approach) a few centimetres (NUDGE_SD) across and along the robot's
        way where the robot hesitated (its slowest moment, if it slowed: ``_hesitation``), else
        where it came closest. A reactive planner's failures lie on knife edges between passing
        at once and hesitating (``dwa`` at insert 0: a box whose face is 0.18 m from its way
        times it out, at 0.14 m or 0.22 m it hesitates 17 s and passes): a near miss, kept by
        the archive, is that close to one, far closer than a mutation's smallest step."""
        space, offsets = self.space, list(parent.offsets)
        route = self._route()
        path = list(parent.path[1:]) or [p[:2] for p in _route_samples(route)]
        slow = _hesitation(path)
        if slow is not None:
            (px, py), (ux, uy) = path[slow], _direction(path, slow)
        elif parent.closest and all(math.isfinite(v) for v in parent.closest[1:]):
            _, px, py = parent.closest
            j = min(range(len(path)), key=lambda k: (path[k][0] - px) ** 2 + (path[k][1] - py) ** 2)
            ux, uy = _direction(path, j)
        else:
            j = rnd.randrange(len(path))
            (px, py), (ux, uy) = path[j], _direction(path, j)
        names = {space.params[g[0]].part.split(":", 1)[1]: g for g in self.movable}
        name = parent.culprit if parent.culprit in names else min(
            names, key=lambda n: math.hypot(space.seed.obstacle(n).x - px, space.seed.obstacle(n).y - py))
        arm = (name, _quarter(route.fraction(px, py)))
        if arm in self._arms().arms:
            self.aim, self.aim_bandit = arm, self.targets
        across, along = rnd.gauss(0.0, NUDGE_SD), rnd.gauss(0.0, NUDGE_SD)
        step = {"dx": ux * along - uy * across, "dy": uy * along + ux * across}
        for i in names[name]:
            offsets[i] += step.get(space.params[i].attr, 0.0)
        return space.clip(offsets)

    def _place(self, parent: Any, rnd: random.Random, squeeze: bool = False) -> tuple[float, ...]:
        """Move the seed obstacle of a target arm (culprit, quarter) beside the parent's path there."""
        space, offsets = self.space, list(parent.offsets)
        arm = self._pick_arm(rnd, inserted=False)
        group = next(g for g in self.movable if space.params[g[0]].part == f"obstacle:{arm[0]}") \
            if arm else rnd.choice(self.movable)
        obs = space.seed.obstacle(space.params[group[0]].part.split(":", 1)[1])
        half = _half_size(obs)
        x0, x1, y0, y1 = self._reach(group)
        for _ in range(8):   # a point the obstacle can reach within its bounds (or its mirror image
            tx, ty, px, py = self._target(parent, rnd, half, arm[1] if arm else None, squeeze,   # across
                                          (x0, x1, y0, y1))
            if not (x0 <= tx <= x1 and y0 <= ty <= y1):                                      # the path)
                tx, ty = 2 * px - tx, 2 * py - ty
            if x0 <= tx <= x1 and y0 <= ty <= y1:
                break
        for i in group:
            attr = space.params[i].attr
            if attr == "dx":
                offsets[i] = tx - obs.x
            elif attr == "dy":
                offsets[i] = ty - obs.y
            elif attr == "removed":
                offsets[i] = 0.0
        return space.clip(offsets)

    def _insert(self, parent: Any, rnd: random.Random, squeeze: bool = False) -> tuple[float, ...]:
        """Add a box beside the parent's path in the quarter of a target arm ("inserted", quarter)."""
        space, offsets = self.space, list(parent.offsets)
        free = [g for g in self.slots if offsets[g[0]] < FLAG_ON]
        group = rnd.choice(free or self.slots)
        x0, y0, x1, y1 = space.region
        lo = space.limits.insert_size[0]
        values = {"on": 1.0, "size": rnd.uniform(0.0, space.limits.insert_size[1] - lo),
                  "yaw": rnd.uniform(-90.0, 90.0)}
        if squeeze:   # a box aligned with the path, so its face is where the band says
            values["yaw"] = 0.0
        arm = self._pick_arm(rnd, inserted=True)
        tx, ty, _, _ = self._target(parent, rnd, (lo + values["size"]) / 2, arm[1] if arm else None, squeeze)
        values["x"], values["y"] = tx - (x0 + x1) / 2, ty - (y0 + y1) / 2
        for i in group:
            offsets[i] = values.get(space.params[i].attr, offsets[i])
        return space.clip(offsets)

    def _squeeze(self, parent: Any, rnd: random.Random) -> tuple[float, ...]:
        """Narrow the passage: a seed obstacle or an inserted box just beside the parent's path,
        its face within 0.3 x (robot half width + its half size) of the recorded footprint, where a
        planner must pass closer than its clearance buffer likes or find another way."""
        if self.movable and (not self.slots or rnd.random() < 0.5):
            return self._place(parent, rnd, squeeze=True)
        return self._insert(parent, rnd, squeeze=True)

    def _crowd(self, parent: Any, rnd: random.Random) -> tuple[float, ...]:
        """Crowd an end of the route: an inserted box aligned with the robot, at a random bearing
        just beside the footprint at the start or the goal pose (at most CROWD_GAP from it), the
        end where inserted boxes have failed least. Where the robot must turn or stop in its
        final pose, or set off from its first, a box within reach is what a route-following
        operator never puts there (the robot's path ends at the goal), and a planner that needs
        room at the goal, or accelerates before it looks, fails there. On a failing parent's
        layout the robot would most likely fail as before: then on the seed's."""
        space = self.space
        offsets = list(space.zero() if parent.failed else parent.offsets)
        mission = space.apply(parent.offsets).mission
        ends = (0, QUARTERS - 1)
        weights = [1.0 / (1.0 + self._inserted_failures(q)) ** 2 for q in ends]
        end = _weighted_pick(ends, weights, rnd.random() * sum(weights))
        self.aim, self.aim_bandit = ("inserted", end), self._arms()
        pose = mission.start if end == ends[0] else mission.goal
        lo, hi = space.limits.insert_size
        size = rnd.uniform(lo, hi)
        bearing = rnd.uniform(-math.pi, math.pi)   # from the robot's heading
        gap = 0.02 + (CROWD_GAP - 0.02) * rnd.random() ** 2   # closer is likelier: half of them within 0.11 m
        heading = math.radians(pose.yaw)
        d = _distance_for_gap(space.seed.robot.footprint, pose.x, pose.y, heading, bearing, size, gap)
        x0, y0, x1, y1 = space.region
        free = [g for g in self.slots if offsets[g[0]] < FLAG_ON]
        group = rnd.choice(free or self.slots)
        values = {"on": 1.0, "size": size - lo, "yaw": (pose.yaw + 90.0) % 180.0 - 90.0,
                  "x": pose.x + d * math.cos(heading + bearing) - (x0 + x1) / 2,
                  "y": pose.y + d * math.sin(heading + bearing) - (y0 + y1) / 2}
        for i in group:
            offsets[i] = values.get(space.params[i].attr, offsets[i])
        return space.clip(offsets)

    def _inserted_failures(self, quarter: int) -> int:
        """Known failing signatures of an inserted box in that quarter of the route."""
        return sum(1 for sig in self._filled() if _in_cell(sig, ("inserted", quarter)))

    def _shiftable(self) -> list[Any]:
        """The archive's failures whose culprit is an inserted box (the parents ``shift`` uses)."""
        if not self.slots:
            return []
        return [self.cells.elites[k] for k in sorted(self.cells.elites, key=repr)
                if self.cells.elites[k].failed and self.cells.elites[k].culprit.startswith(INSERT_PREFIX)]

    def _shift_parent(self, rnd: random.Random) -> Any:
        """One of ``_shiftable``, the ones shifted least often first (weight 1 / (1 + shifts));
        None (nothing drawn) if there is none."""
        pool = self._shiftable()
        if not pool:
            return None
        weights = [1.0 / (1.0 + self.shifted.get(c.signature, 0)) for c in pool]
        cand = _weighted_pick(pool, weights, rnd.random() * sum(weights))
        self.shifted[cand.signature] = self.shifted.get(cand.signature, 0) + 1
        return cand

    def _shift(self, parent: Any, rnd: random.Random) -> tuple[float, ...]:
        """Carry a failure's trap to another quarter of the route: the inserted box it failed at
        (and every other inserted box within SHIFT_RADIUS of it, e.g. a barrier's other half) is
        moved along the seed's route to a quarter where inserted boxes have failed least, keeping
        its place and turn relative to the route's direction (a trap that worked once, met again
        somewhere else along the route: a new place, a new way of failing)."""
        space, route = self.space, self._route()
        offsets = list(parent.offsets)
        scenario = space.apply(parent.offsets)
        culprit = scenario.obstacle(parent.culprit)
        f = route.fraction(culprit.x, culprit.y)
        here = _quarter(f)
        others = [q for q in range(QUARTERS) if q != here]
        weights = [1.0 / (1.0 + self._inserted_failures(q)) ** 2 for q in others]
        there = _weighted_pick(others, weights, rnd.random() * sum(weights))
        g = f + (there - here) / QUARTERS + rnd.uniform(-0.3, 0.3) / QUARTERS
        if _quarter(g) != there:
            g = (there + rnd.uniform(0.1, 0.9)) / QUARTERS
        self.aim, self.aim_bandit = ("inserted", there), self._arms()
        (ax, ay), a = _route_point(route, f), _route_heading(route, f)
        (bx, by), b = _route_point(route, g), _route_heading(route, g)
        turn = b - a
        c, s = math.cos(turn), math.sin(turn)
        x0, y0, x1, y1 = space.region
        for k, group in enumerate(self.slots):
            at = {space.params[i].attr: i for i in group}
            if offsets[at["on"]] < FLAG_ON:
                continue
            box = scenario.obstacle(f"{INSERT_PREFIX}{k + 1}")
            if math.hypot(box.x - culprit.x, box.y - culprit.y) > SHIFT_RADIUS:
                continue
            rx, ry = box.x - ax, box.y - ay
            offsets[at["x"]] = bx + c * rx - s * ry - (x0 + x1) / 2
            offsets[at["y"]] = by + s * rx + c * ry - (y0 + y1) / 2
            offsets[at["yaw"]] = (box.yaw + math.degrees(turn) + 90.0) % 180.0 - 90.0
        return space.clip(offsets)

    def _timing_arms(self) -> _Targets:
        """The retime arms: each moving obstacle in each route quarter its track can come near
        (its positions over the episode, shifted within its dx/dy bounds)."""
        if self.timing is None:
            import numpy as np
            from ...scenario.motion import Track

            space, route = self.space, self._route()
            fp = space.seed.robot.footprint
            reach = (fp.radius if fp.shape == "circle" else fp.width / 2) + 0.5
            arms = []
            for group in self.moving:
                name = space.params[group[0]].part.split(":", 1)[1]
                obs = space.seed.obstacle(name)
                rng = {space.params[i].attr: (space.params[i].lo, space.params[i].hi) for i in group}
                (dx0, dx1), (dy0, dy1) = rng.get("dx", (0.0, 0.0)), rng.get("dy", (0.0, 0.0))
                t = np.linspace(0.0, space.seed.mission.timeout + 10.0, 200)
                pts = Track(obs).positions(t)
                arms += sorted({(name, _quarter(f)) for x, y, f in _route_samples(route)
                                if np.any((pts[:, 0] + dx0 - reach <= x) & (x <= pts[:, 0] + dx1 + reach)
                                          & (pts[:, 1] + dy0 - reach <= y) & (y <= pts[:, 1] + dy1 + reach))})
            self.timing = _Targets(arms or [(self.space.params[g[0]].part.split(":", 1)[1], 0)
                                            for g in self.moving])
        return self.timing

    def _retime(self, parent: Any, rnd: random.Random) -> tuple[float, ...]:
        """Time-to-impact for a moving obstacle: choose its start time and speed (from a grid over
        their ranges) so that it reaches a point of the parent's path when the robot was there
        (or up to RETIME_LAG later), then shift its path (dx, dy) by what is left of the gap."""
        import numpy as np
        from ...scenario.motion import Track

        space, route = self.space, self._route()
        timing = self._timing_arms()
        arm = self.aim = timing.pick(rnd, timing.arms, self._filled())
        self.aim_bandit = timing
        group = next(g for g in self.moving if space.params[g[0]].part == f"obstacle:{arm[0]}")
        at = {space.params[i].attr: i for i in group}
        n = len(parent.path)
        duration = float(parent.metrics.get("duration") or 0.0) or space.seed.mission.timeout
        times = np.array([k / max(1, n - 1) * duration for k in range(n)])
        robot = np.asarray(parent.path, dtype=float).reshape(-1, 2)
        aimed = [k for k in range(n) if _quarter(route.fraction(*parent.path[k])) == arm[1]] or list(range(n))
        times, robot = times[aimed] + rnd.uniform(*RETIME_LAG), robot[aimed]
        offsets = list(parent.offsets)
        starts = ([offsets[at["start"]]] + list(np.linspace(space.params[at["start"]].lo, space.params[at["start"]].hi,
                                                            RETIME_STARTS)) if "start" in at else [None])
        speeds = ([offsets[at["speed"]]] + [rnd.uniform(space.params[at["speed"]].lo, space.params[at["speed"]].hi)
                                            for _ in range(RETIME_SPEEDS - 1)] if "speed" in at else [None])
        obs = space.seed.obstacle(arm[0])
        fp = space.seed.robot.footprint
        contact = (fp.radius if fp.shape == "circle" else fp.width / 2) + _half_size(obs)
        tried = []
        for start in starts:
            for speed in speeds:
                trial = list(offsets)
                if start is not None:
                    trial[at["start"]] = start
                if speed is not None:
                    trial[at["speed"]] = speed
                pos = Track(space.apply(trial).obstacle(arm[0])).positions(times)
                gap = robot - pos
                k = int(np.argmin(np.hypot(gap[:, 0], gap[:, 1])))
                tried.append((float(np.hypot(*gap[k])), trial, (float(gap[k, 0]), float(gap[k, 1]))))
        meeting = [t for t in tried if t[0] < contact]
        _, trial, (gx, gy) = rnd.choice(meeting) if meeting else min(tried, key=lambda t: t[0])
        jitter = rnd.uniform(0.0, 0.8) * contact
        angle = rnd.uniform(0.0, 2 * math.pi)
        for attr, shift in (("dx", gx + jitter * math.cos(angle)), ("dy", gy + jitter * math.sin(angle))):
            if attr in at and not meeting:
                trial[at[attr]] += shift
            elif attr in at:
                trial[at[attr]] += jitter * (math.cos(angle) if attr == "dx" else math.sin(angle))
        if "removed" in at:
            trial[at["removed"]] = 0.0
        return space.clip(trial)



def _weighted_pick(items: Sequence[Any], weights: Sequence[float], ticket: float) -> Any:
    """The item whose stretch of the running total of ``weights`` holds ``ticket`` (a uniform
    draw times their sum); the last item if rounding leaves the ticket past the end."""
    for item, w in zip(items, weights):
        if ticket < w:
            return item
        ticket -= w
    return items[-1]


def _in_cell(sig: tuple, arm: tuple[str, int]) -> bool:
    """Whether a failing cause signature belongs to a target arm's cell: an inserted box in that
    quarter, or a seed obstacle (placed by its name) with the robot failing in that quarter."""
    if arm[0] == "inserted":
        return sig[1] == "inserted" and sig[2] == arm[1]
    return sig[1] == arm[0] and sig[3] == arm[1]


def _beside_within(path: Sequence[tuple[float, float]], k: int, lateral: float, box: tuple) -> bool:
    """Whether a point ``lateral`` to either side of ``path[k]`` lies in ``box`` (x0, x1, y0, y1)."""
    a, b = path[max(0, k - 1)], path[min(len(path) - 1, k + 1)]
    dx, dy = b[0] - a[0], b[1] - a[1]
    norm = math.hypot(dx, dy) or 1.0
    x0, x1, y0, y1 = box
    return any(x0 <= path[k][0] - dy / norm * s <= x1 and y0 <= path[k][1] + dx / norm * s <= y1
               for s in (lateral, -lateral, 0.0))


def _hesitation(path: Sequence[tuple[float, float]]) -> int | None:
    """The index of the path sample (evenly spaced in time) where the robot moved least, leaving
    out its start and end, if it moved less than SLOW_SHARE of its median step there; else None."""
    steps = [math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(path, path[1:])]
    inner = steps[3:-3]
    if len(inner) < 3:
        return None
    median = sorted(inner)[len(inner) // 2]
    k = min(range(len(inner)), key=inner.__getitem__)
    return k + 3 if inner[k] < SLOW_SHARE * median else None


def _direction(path: Sequence[tuple[float, float]], j: int) -> tuple[float, float]:
    a, b = path[max(0, j - 1)], path[min(len(path) - 1, j + 1)]
    dx, dy = b[0] - a[0], b[1] - a[1]
    norm = math.hypot(dx, dy)
    return (dx / norm, dy / norm) if norm > 1e-9 else (1.0, 0.0)


def _key(offsets: Sequence[float]) -> tuple:
    return tuple(round(float(v), 6) for v in offsets)


def _quarter(fraction: float) -> int:
    return min(QUARTERS - 1, max(0, int(fraction * QUARTERS)))


def _route_point(route: Any, fraction: float) -> tuple[float, float]:
    """The point at arc-length ``fraction`` (clamped to 0..1) of the seed's route."""
    import numpy as np

    s = min(1.0, max(0.0, fraction)) * route.length
    return (float(np.interp(s, route.cum, route.points[:, 0])), float(np.interp(s, route.cum, route.points[:, 1])))


def _distance_for_gap(footprint: Any, x: float, y: float, heading: float, bearing: float, size: float,
                      gap: float) -> float:
    """How far from (x, y), at ``bearing`` from ``heading`` (rad), to centre a square box of side
    ``size`` turned with the robot so that it is ``gap`` from the robot's footprint there."""
    from ...scenario.geometry import footprint_polygon, rectangle

    robot = footprint_polygon(footprint, x, y, heading)
    c, s = abs(math.cos(bearing)), abs(math.sin(bearing))
    reach = (footprint.radius if footprint.shape == "circle" else footprint.length / 2 * c + footprint.width / 2 * s)
    d = reach + size / 2 * (c + s) + gap      # a separating line ``gap`` from the footprint: at least gap
    for _ in range(4):                        # the true distance is monotone in d: a few corrections
        box = rectangle(x + d * math.cos(heading + bearing), y + d * math.sin(heading + bearing), size, size, heading)
        d += gap - robot.distance(box)
    return d


def _route_heading(route: Any, fraction: float) -> float:
    """The direction (radians) of the seed's route at arc-length ``fraction``."""
    a, b = _route_point(route, fraction - 0.02), _route_point(route, fraction + 0.02)
    return math.atan2(b[1] - a[1], b[0] - a[0])


def _route_samples(route: Any, n: int = 40) -> list[tuple[float, float, float]]:
    """(x, y, fraction) of ``n`` points evenly spaced along the seed's route."""
    return [(*_route_point(route, k / (n - 1)), k / (n - 1)) for k in range(n)]


def _half_size(obs: Any) -> float:
    """Half the smallest extent of an obstacle's outline (its radius for a cylinder or person)."""
    if getattr(obs, "radius", None):
        return obs.radius
    if hasattr(obs, "length"):
        return min(obs.length, obs.width) / 2
    from ...scenario.geometry import obstacle_polygon
    x0, y0, x1, y1 = obstacle_polygon(obs).bounds
    return min(x1 - x0, y1 - y0) / 2


def _has(space: SearchSpace, group: Sequence[int], attr: str) -> bool:
    return any(space.params[i].attr == attr for i in group)
