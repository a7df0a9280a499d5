"""``evolve`` (the default strategy): a quality-diversity search. A MAP-Elites archive keyed by the cause
signature (fitness.py) keeps the closest-to-failing candidate of each behaviour; parents are
picked from it with a penalty on cells picked often, so the budget spreads over ways of
failing instead of one failure's neighbours. Operators: uniform exploration, Gaussian
mutation, and six that use what the episode showed (PHYS-FUZZ style): move an obstacle onto
the robot's path at or a moment after its closest approach, insert a new obstacle there,
squeeze one just beside the path (narrowing the passage to little more than the footprint),
wall the path off with two inserted boxes (barrier), or retime a moving obstacle so that it
reaches the robot's path when the robot was there (time-to-impact in time as well as space), or
where no box can be inserted, nudge the obstacle the planner reacted to a few centimetres where
the robot hesitated (a near miss is that close to a knife edge: what finds failures where only
the seed's obstacles move; where boxes can be inserted it found fewer per CPU second).
Two more move toward cells of the signature space that are not filled yet: shift carries a
failure's inserted box (its trap) along the route to a quarter where inserted boxes have failed
least, crowd puts a box just beside the footprint at the start or goal pose (the least-failed
end), where no path-following operator reaches.
The first generation is uniform layouts, the likeliest to fail first, then the seed; the
second can aim at the seed's episode. Until a failure is known, each generation is the
likeliest to fail of HUNT_DRAWS times as many proposals, those simulated first: likeliest by
what is cheap to know before an episode, the room the narrowest passage leaves the footprint
less how deep the obstacles cut into the robot's expected way (a uniform draw that fails at
once where failures are common, a tight one where they are rare). Those proposals' path checks
(validity) and room are answered without a path search where the layout is open
(verdict/open_way.py; the same answers).
Operator shares follow which operator has been finding new failing signatures; where the
aimed operators put an obstacle (which obstacle, which quarter of the route) is a second
bandit rewarded for new failing signatures and divided down by re-created ones.
Hypothesis draws each proposal's random stream (which picks its operator, parent and values):
one seeded ``ConjectureData`` draw per proposal (until #35, a whole engine run per generation).

The operators that aim at the episode (place, insert, squeeze, barrier, retime, shift, crowd) and
the bandit over where they aim are in aim.py.
"""
from __future__ import annotations

import math
import random
from typing import Any, Sequence

from ..space import SearchSpace
from .aim import AimedOperators, _has, _key, _route_samples, _Targets, _weighted_pick
from .admission import Admission, uniform
from .protocol import GENERATION, BaseStrategy

MUTATION_SCALES = (0.05, 0.15, 0.3)   # Gaussian step sd as a fraction of the parameter's range
OPERATORS = ("explore", "mutate", "place", "insert", "squeeze", "retime", "barrier", "shift", "crowd", "nudge")
PATH_OPERATORS = frozenset({"place", "insert", "squeeze", "retime", "barrier", "nudge"})   # aim at the parent's path
MIN_SHARE = 0.04               # every usable operator keeps at least this share
EXPLORE_SHARE = 0.2            # uniform exploration keeps at least this share: never far below random
PICK_PENALTY = 0.03            # robustness added per earlier pick of an archive cell (novelty)
FAILURE_CREDIT = 3.0           # an operator's credit for a new way of failing (that holds)
NEAR_COPY = 0.5                # m: a failure's child whose culprit moved less (same quarter) is skipped
FAILURE_FLOOR = -0.3           # failure cells compete for parenthood as if this robust
STREAM_BITS = 16               # Hypothesis-drawn bits seeding each proposal's random stream (with the
                               # generation, attempt and slot: 65 536 streams a slot; 3.4 us a bit)
TRIES_PER_PROPOSAL = 10        # draws per proposal wanted before a batch gives up (ask draws again)
HUNT_DRAWS = 4                 # no failure known yet: proposals drawn per one simulated (the likeliest kept);
                               # 8 found as many failures per CPU s (32 vs 28 in 90 searches at insert 0, p = 0.71)
                               # for 17 % own work against 12 % (#35)
ROOM_LEVELS = (0.05, 0.1, 0.15, 0.2, 0.3, 0.45, 0.6)   # m: footprint growth tried by paths.passage_room
WAY_DISTANCES_KEPT = 4096      # obstacles whose distance to the expected way _intrusion remembers


class _Cells:
    """MAP-Elites archive: the elite (lowest robustness) of each cause signature; a cell whose
    failure did not hold (``fragile``) competes as a near miss (robustness at least 0)."""

    def __init__(self):
        self.elites: dict[tuple, Any] = {}
        self.picks: dict[tuple, int] = {}
        self.fragile: set[tuple] = set()

    def add(self, cand: Any) -> bool:
        """Keep ``cand`` if its cell is new or it beats the elite; True for a new cell."""
        if cand.outcome == "harness-error" or not math.isfinite(cand.robustness):
            return False
        key = cand.signature
        old = self.elites.get(key)
        if old is None or cand.robustness < old.robustness:
            self.elites[key] = cand
        return old is None

    def pick(self, rnd: random.Random) -> Any:
        """Tournament of three cells on robustness plus a penalty per earlier pick."""
        keys = sorted(self.elites, key=repr)
        best = min((keys[rnd.randrange(len(keys))] for _ in range(3)),
                   key=lambda k: max(self.elites[k].robustness, 0.0 if k in self.fragile else FAILURE_FLOOR)
                   + PICK_PENALTY * self.picks.get(k, 0))
        self.picks[best] = self.picks.get(best, 0) + 1
        return self.elites[best]


class Evolve(AimedOperators, BaseStrategy):
    """See the module docstring. Each proposal's random stream is one seeded Hypothesis draw."""

    def __init__(self, space: SearchSpace, report: Any, budget: int, seed_value: int):
        self.space, self.report, self.seed_value = space, report, seed_value
        self.admission = Admission(space, report, budget, margin=max(ROOM_LEVELS))   # open at it: room known
        self.cells = _Cells()
        self.generation = 0
        self.stats = {op: [0, 0.0] for op in OPERATORS}   # tries, credit
        self.movable = [g for g in space.groups if _has(space, g, "dx") and _has(space, g, "dy")
                        and space.params[g[0]].part.startswith("obstacle:")]
        self.slots = [g for g in space.groups if space.params[g[0]].part.startswith("inserted[")]
        self.moving = [g for g in space.groups if _has(space, g, "start") or _has(space, g, "speed")]
        self.timing: _Targets | None = None
        self.failure_signatures: set[tuple] = set()
        self.fragile: set[tuple] = set()                # failed, did not hold (holding.py), none held since
        self.held_early: set[tuple] = set()             # proposals known to hold before they are told
        self.credited: dict[tuple, tuple[str, Any]] = {}   # a new failure under test -> (operator, aim)
        self.route: Any = None
        self.targets: _Targets | None = None
        self.aims: dict[tuple, tuple[Any, tuple[str, int]]] = {}   # proposal -> (bandit, arm) it aimed at
        self._target_paths: dict[tuple, tuple] = {}       # aim.AimedOperators._target_path's memo
        self.aim: tuple[str, int] | None = None         # the arm of the proposal being drawn
        self.aim_bandit: _Targets | None = None          # and the bandit it belongs to
        self.told = 0                                   # generations told so far
        self.shifted: dict[tuple, int] = {}             # signature -> times its failure was shifted
        self.seed_episode: Any = None                   # the seed's own episode (generation 1)
        self._way: tuple | None = None   # (from the episode?, points, times, distances, points as shapely): _expected_way

    @property
    def lag(self) -> int:
        """0 until the first generation (with the seed's episode, whose path the aimed operators
        use) is told, then 1: generation g+2 is drawn knowing the results up to generation g."""
        return 1 if self.told else 0

    def weights(self) -> list[float]:
        usable = {"explore": True, "mutate": bool(self.cells.elites),
                  "place": bool(self.cells.elites and self.movable), "insert": bool(self.cells.elites and self.slots),
                  "squeeze": bool(self.cells.elites and (self.movable or self.slots)),
                  "retime": bool(self.cells.elites and self.moving),
                  "barrier": bool(self.cells.elites and len(self.slots) >= 2),
                  "shift": bool(self._shiftable()), "crowd": bool(self.cells.elites and self.slots),
                  "nudge": bool(self.cells.elites and self.movable and not self.slots)}
        rates = {op: (self.stats[op][1] + 1.0) / (self.stats[op][0] + 2.0) for op in OPERATORS if usable[op]}
        total = sum(rates.values())
        return [max(EXPLORE_SHARE if op == "explore" else MIN_SHARE, rates[op] / total) if op in rates else 0.0
                for op in OPERATORS]

    def ask(self, room: int) -> list[tuple[tuple[float, ...], str]]:
        """The next generation. The first: GENERATION - 1 uniform layouts, the likeliest to fail
        first, then the seed (a budget below GENERATION gets the likeliest layouts only). Until a
        failure is known, HUNT_DRAWS proposals are drawn per candidate and the likeliest to fail
        are simulated, those first. What is drawn does not depend on ``room``: a search of a
        smaller budget begins like one of a larger budget."""
        self.generation += 1
        size = GENERATION - 1 if self.generation == 1 else GENERATION   # + the seed in the first
        hunting = not self.failure_signatures
        draw = size * HUNT_DRAWS if hunting else min(room, size)
        out: list[tuple[tuple[float, ...], str]] = []
        attempt = 0
        self.admission.clear.clear()
        while len(out) < draw:   # ends: the admission gives up (GaveUp) after too many misses
            out.extend(self._hypothesis_batch(draw - len(out), attempt))
            attempt += 1
        out = self._likeliest_first(out[:draw]) if hunting else out
        for offsets, _ in out[min(room, size):]:   # drawn, never simulated: as if never drawn
            self.admission.seen.discard(_key(offsets))
            self.aims.pop(_key(offsets), None)
        out = out[:min(room, size)]
        if self.generation == 1 and room > size and self.admission.admit(self.space.zero()):
            out.append((self.space.zero(), "seed"))
        return out

    def _likeliest_first(self, proposals: list[tuple[tuple[float, ...], str]]
                         ) -> list[tuple[tuple[float, ...], str]]:
        """``proposals`` ordered by what is cheap to know before an episode about how likely
        each is to fail: the least room to spare first, room being how much the footprint could
        grow and still find a way (``paths.passage_room``; at once for an open layout: ``open_way``)
        less how deep the layout's obstacles cut into the robot's expected way (``_intrusion``);
        ties keep the drawing order."""
        from ...verdict.paths import passage_room

        scored = []
        for k, (offsets, _) in enumerate(proposals):
            scenario = self.space.apply(offsets)
            room = (max(ROOM_LEVELS) if _key(offsets) in self.admission.clear   # open at it: no path search
                    else passage_room(scenario, ROOM_LEVELS))
            scored.append((room - self._intrusion(scenario), k))
        return [proposals[k] for _, k in sorted(scored)]

    def _intrusion(self, scenario: Any) -> float:
        """How deep (m) the layout's obstacles cut into the footprint's half width around the
        robot's expected way: the seed's recorded path, or before its episode the seed's route
        driven at top speed; moving obstacles where they are at the moment the robot is there.
        0: the way is clear; more: the robot is pushed that far off its way."""
        import numpy as np
        import shapely

        from ...scenario.geometry import bounding_radius, obstacle_outline
        from ...scenario.motion import Track
        from ...verdict.gaps import footprint_core

        pts, times = self._expected_way()
        _, hw, rho = footprint_core(scenario.robot.footprint)
        half = hw + rho
        nearest = math.inf
        near = self._way[3]   # obstacle -> its distance to the way (the same way: the same answer)
        static = [o for o in scenario.obstacles if getattr(o, "motion", None) is None]
        if static:   # a bounding circle at least ``half`` from the way: that obstacle cannot cut into it
            c = np.array([(o.x, o.y) for o in static])
            gap = np.sqrt(((c[:, None, :] - pts[None, :, :]) ** 2).sum(-1)).min(axis=1)
            clear = {id(o) for o, g in zip(static, gap) if g - bounding_radius(o) >= half + 1e-9}
        for obs in scenario.obstacles:
            if static and id(obs) in clear:
                continue
            try:
                d = near.get(obs)
            except TypeError:   # a field that does not hash: measured each time
                d = None
            if d is None:
                if getattr(obs, "motion", None) is not None:   # the way seen from where it is then
                    track = Track(obs)
                    at = shapely.points(pts - (track.positions(times) - track.positions(np.zeros(1))))
                else:
                    at = self._way[4]
                d = float(shapely.distance(obstacle_outline(obs), at).min())
                if len(near) < WAY_DISTANCES_KEPT:
                    try:
                        near[obs] = d
                    except TypeError:
                        pass
            nearest = min(nearest, d)
        return max(0.0, half - nearest)

    def _expected_way(self) -> tuple[Any, Any]:
        """(points, times) of the robot's expected way: the seed's recorded path over its
        episode's duration once that episode is known, before it the seed's route driven at top
        speed. Made once for each (the intrusion of every proposal is measured against it)."""
        import numpy as np

        seed, episode = self.space.seed, self.seed_episode
        recorded = episode is not None and bool(episode.path)
        if self._way is None or self._way[0] != recorded:
            if recorded:
                pts = np.asarray(episode.path, dtype=float).reshape(-1, 2)
                duration = float(episode.metrics.get("duration") or 0.0) or seed.mission.timeout
            else:
                route = self._route()
                pts = np.array([p[:2] for p in _route_samples(route)], dtype=float)
                duration = route.length / max(seed.robot.limits.max_speed, 1e-6)
            import shapely
            self._way = (recorded, pts, np.linspace(0.0, duration, len(pts)), {}, shapely.points(pts))
        return self._way[1], self._way[2]

    def _hypothesis_batch(self, n: int, attempt: int) -> list[tuple[tuple[float, ...], str]]:
        """Up to ``n`` valid proposals, each from its own draw of Hypothesis's data: a
        ``ConjectureData`` seeded by the search seed, the generation, the attempt and the try gives
        STREAM_BITS booleans through Hypothesis's provider, which seed the proposal's random stream
        (about 0.06 ms a proposal). Until #35 each generation was a whole seeded Hypothesis engine
        run (``given(st.data())``), three quarters of the strategy's own work for the same thing: the
        stream goes through a string-seeded ``random.Random``, so the engine's mutations of
        earlier examples gave no streams nearer each other than fresh draws do. At most
        TRIES_PER_PROPOSAL tries per proposal wanted, as the engine run stopped on too many
        invalid examples (``ask`` then draws again with the next attempt)."""
        from hypothesis.internal.conjecture.data import ConjectureData

        out: list[tuple[tuple[float, ...], str]] = []
        weights = self.weights() if self.told else [1.0 if op == "explore" else 0.0 for op in OPERATORS]
        total = sum(weights)
        for tried in range(TRIES_PER_PROPOSAL * n):
            if len(out) >= n:
                break
            data = ConjectureData(random=random.Random(f"{self.seed_value}:{self.generation}:{attempt}:{tried}"))
            # booleans, not an integer: Hypothesis mixes constants found in the loaded modules
            # into integer (and bytes) draws, which would make the stream depend on what is imported
            stream = sum(1 << i for i in range(STREAM_BITS) if data.draw_boolean())
            rnd = random.Random(f"{self.seed_value}:{self.generation}:{attempt}:{len(out)}:{stream}")
            # not a Hypothesis integer: those favour small values
            op = _weighted_pick(OPERATORS, weights, rnd.random() * total)
            offsets, parent = self.propose(op, rnd)
            if parent is not None and self._repeats(parent, offsets):
                self.report.skipped += 1   # would most likely fail the same way again
                continue
            if not self.admission.admit(offsets):
                continue
            if self.aim is not None:
                self.aims[_key(offsets)] = (self.aim_bandit, self.aim)
            out.append((offsets, op))
        return out

    def propose(self, op: str, rnd: random.Random) -> tuple[tuple[float, ...], Any]:
        """(offsets, parent) of one proposal of operator ``op`` (parent None for exploration)."""
        self.aim = None
        if op == "explore" or not self.cells.elites:
            return uniform(self.space, rnd), None
        if op == "shift":
            parent = self._shift_parent(rnd)
            if parent is not None:
                return self._shift(parent, rnd), parent
        parent = self.cells.pick(rnd)
        if op in PATH_OPERATORS and parent.path:   # Evolve._place, ._insert, ...
            return getattr(self, f"_{op}")(parent, rnd), parent
        if op == "crowd" and self.slots:
            return self._crowd(parent, rnd), parent
        return self._mutate(parent, rnd), parent

    def _repeats(self, parent: Any, offsets: Sequence[float]) -> bool:
        """A child of a failure that changes no parameter by 20 % of its range or more and
        leaves the culprit in place (same quarter of the route, moved < NEAR_COPY) would most
        likely fail the same way: a near-copy, not worth a simulation. (Skipping every aimed
        child that leaves the culprit in place was measured: fewer distinct failures where
        failures are common, as the robot often fails another way before the known culprit.)"""
        if not parent.failed or not parent.culprit or self.space.normalised_distance(parent.offsets, offsets) >= 0.2:
            return False
        before, after = self.space.apply(parent.offsets), self.space.apply(offsets)
        try:
            a, b = before.obstacle(parent.culprit), after.obstacle(parent.culprit)
        except KeyError:
            return False   # the culprit is gone: something else will happen
        route = self._route()
        return (int(route.fraction(a.x, a.y) * 4) == int(route.fraction(b.x, b.y) * 4)
                and math.hypot(a.x - b.x, a.y - b.y) < NEAR_COPY)

    def _route(self) -> Any:
        if self.route is None:
            from ..fitness import Route
            self.route = Route(self.space.seed)
        return self.route

    def _mutate(self, parent: Any, rnd: random.Random) -> tuple[float, ...]:
        space, offsets = self.space, list(parent.offsets)
        n, k = len(space.params), rnd.randrange(4)
        idx = (list(range(n)) if k == 0 else list(rnd.choice(space.groups)) if k == 1
               else sorted({rnd.randrange(n) for _ in range(k)}))
        scale = rnd.choice(MUTATION_SCALES[1:] if parent.failed else MUTATION_SCALES)
        for i in idx:
            p = space.params[i]
            if p.kind == "flag":
                offsets[i] = 1.0 - offsets[i] if rnd.random() < 0.5 else offsets[i]
            else:
                offsets[i] += rnd.gauss(0.0, 1.0) * scale * p.width
        return space.clip(offsets)

    def tell(self, results: Sequence[Any]) -> None:
        self.told += 1
        for cand in results:
            if cand.origin == "seed":
                self.seed_episode = cand
            before = self.cells.elites.get(cand.signature)
            self.cells.add(cand)
            new_failure = cand.failed and cand.signature not in self.failure_signatures
            tested = new_failure or (cand.failed and cand.signature in self.fragile)   # the engine tests it
            if cand.failed:
                self.failure_signatures.add(cand.signature)
            improved = (not cand.failed and math.isfinite(cand.robustness)
                        and (before is None or cand.robustness < before.robustness))
            # credit: new ways of failing, and moves toward failing; not for the first generation,
            # chosen for looking likely to fail, not drawn as its operator draws. A new failure
            # under confirmation earns a third now, the rest when it holds (``confirmed``).
            key = _key(cand.offsets)
            aim = self.aims.pop(key, None)
            credit = (FAILURE_CREDIT if key in self.held_early else FAILURE_CREDIT / 3) if new_failure else 0.0
            if tested and key not in self.held_early:
                self.credited[key] = (cand.origin, aim if new_failure else None, credit)
            self.held_early.discard(key)
            if cand.origin in self.stats and self.told > 1:
                self.stats[cand.origin][0] += 1
                self.stats[cand.origin][1] += credit + (0.2 if improved else 0.0)
            if aim is not None:
                aim[0].tell(aim[1], cand, new_failure)

    def confirmed(self, cand: Any, estimate: Any) -> None:
        """The engine decided whether a failure holds under the seed's randomness (holding.py):
        the operator that found one that holds gets the rest of its credit; one that did not hold
        takes back its target's credit, its way of failing is not taken as found (its cell and
        route quarter stay open to failures that hold) and its cell competes for parenthood as a
        near miss, not as a failure."""
        key, sig = _key(cand.offsets), cand.signature
        origin, aim, given = self.credited.pop(key, (None, None, 0.0))
        if estimate.holds:
            self.fragile.discard(sig)
            self.cells.fragile.discard(sig)
            if origin is None:
                self.held_early.add(key)   # decided before it is told (no test to pass): full credit then
            elif origin in self.stats and self.told > 1:
                self.stats[origin][1] += FAILURE_CREDIT - given
            return
        self.fragile.add(sig)
        self.cells.fragile.add(sig)
        if aim is not None:
            aim[0].credit[aim[1]] -= 1.0

    def _filled(self) -> set[tuple]:
        """The ways of failing the targets count as found: every failing signature but those that
        did not hold."""
        return self.failure_signatures - self.fragile if self.fragile else self.failure_signatures
