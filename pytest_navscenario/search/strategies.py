"""Search strategies as ask/tell objects: ``ask(room)`` proposes a generation of valid candidates
(offset vectors with their origin), ``tell(results)`` receives them simulated, in proposal order.

* ``random``: uniform sampling over the space (the baseline).
* ``hillclimb``: the Surrealist baseline, an adaptive-step coordinate hill-climb over one seed
  obstacle's parameters at a time that minimises the minimum clearance.
* ``evolve`` (default): a quality-diversity search. A MAP-Elites archive keyed by the cause
  signature (fitness.py) keeps the closest-to-failing candidate of each behaviour; parents are
  picked from it with a penalty on cells picked often, so the budget spreads over ways of
  failing instead of one failure's neighbours. Operators: uniform exploration, Gaussian
  mutation, and five that use what the episode showed (PHYS-FUZZ style): move an obstacle onto
  the robot's path at or a moment after its closest approach, insert a new obstacle there,
  squeeze one just beside the path (narrowing the passage to little more than the footprint),
  wall the path off with two inserted boxes (barrier), or retime a moving obstacle so that it
  reaches the robot's path when the robot was there (time-to-impact in time as well as space).
  Two more move toward cells of the signature space that are not filled yet: shift carries a
  failure's inserted box (its trap) along the route to a quarter where inserted boxes have failed
  least, crowd puts a box just beside the footprint at the start or goal pose (the least-failed
  end), where no path-following operator reaches.
  The first generation is uniform layouts, the likeliest to fail first, then the seed; the
  second can aim at the seed's episode. Until a failure is known, each generation is the
  likeliest to fail of HUNT_DRAWS times as many proposals, those simulated first: likeliest by
  what is cheap to know before an episode, the room the narrowest passage leaves the footprint
  less how deep the obstacles cut into the robot's expected way (a uniform draw that fails at
  once where failures are common, a tight one where they are rare).
  Operator shares follow which operator has been finding new failing signatures; where the
  aimed operators put an obstacle (which obstacle, which quarter of the route) is a second
  bandit rewarded for new failing signatures and divided down by re-created ones.
  Hypothesis draws each proposal (operator, parent, random stream) in one seeded Hypothesis run
  per generation.

A generation's size is the strategy's own constant, and so is its ``lag``: how many generations
later it is told a generation's results (engine._search_loop asks for the next generation before
telling the last ``lag`` ones, so workers evaluate while the strategy draws). So what is proposed
never depends on how many candidates are evaluated at once.
"""
from __future__ import annotations

import math
import random
from typing import Any, Sequence

from .space import FLAG_ON, INSERT_PREFIX, SearchSpace, invalid_reason

GENERATION = 8                 # candidates per generation (evolve, random)
MUTATION_SCALES = (0.05, 0.15, 0.3)   # Gaussian step sd as a fraction of the parameter's range
OPERATORS = ("explore", "mutate", "place", "insert", "squeeze", "retime", "barrier", "shift", "crowd")
PATH_OPERATORS = frozenset({"place", "insert", "squeeze", "retime", "barrier"})   # aim at the parent's path
MIN_SHARE = 0.04               # every usable operator keeps at least this share
EXPLORE_SHARE = 0.2            # uniform exploration keeps at least this share: never far below random
PICK_PENALTY = 0.03            # robustness added per earlier pick of an archive cell (novelty)
FAILURE_CREDIT = 3.0           # an operator's credit for a new way of failing (that holds)
NEAR_COPY = 0.5                # m: a failure's child whose culprit moved less (same quarter) is skipped
FAILURE_FLOOR = -0.3           # failure cells compete for parenthood as if this robust
HILLCLIMB_STEP = 0.25          # initial step, fraction of the range
HILLCLIMB_MIN_STEP = 0.02      # a coordinate is done when its step is below this fraction
HILLCLIMB_STALL = 8            # misses in a row on one obstacle: move to the next
MAX_INVALID_FACTOR = 50
STREAM_BITS = 32               # Hypothesis-drawn bits seeding each proposal's random stream
QUARTERS = 4                   # route quarters: the places a target aims at (fitness.PLACE_BINS)
SQUEEZE_BAND = (1.0, 1.3)      # squeeze: obstacle centre at this many (robot half width + obstacle half)
                               # from the path: its face just clears the footprint's recorded pose
RETIME_STARTS = 21             # retime: start offsets tried across their range (and RETIME_SPEEDS speeds)
RETIME_SPEEDS = 5
RETIME_LAG = (-1.0, 0.5)       # s: the obstacle is aimed at where the robot was this much later
CROWD_GAP = 0.4                # m: crowd leaves at most this much between a box and the start/goal footprint
SHIFT_RADIUS = 2.0             # m: shift carries the inserted boxes this near the culprit along with it
HUNT_DRAWS = 8                 # no failure known yet: proposals drawn per one simulated (the likeliest kept)
ROOM_LEVELS = (0.05, 0.1, 0.15, 0.2, 0.3, 0.45, 0.6)   # m: footprint growth tried by paths.passage_room


class GaveUp(Exception):
    """Too many invalid candidates in a row: the bounds leave almost nothing valid."""


class _Admission:
    """Validity check and repeat filter shared by the strategies (counts what it discards)."""

    def __init__(self, space: SearchSpace, report: Any, budget: int):
        self.space, self.report, self.budget = space, report, budget
        self.seen: set[tuple[float, ...]] = set()
        self.invalid_run = 0

    def admit(self, offsets: Sequence[float]) -> bool:
        key = tuple(round(v, 6) for v in offsets)
        if key in self.seen:
            self.report.skipped += 1
            return self._miss()
        reason = invalid_reason(self.space.apply(offsets))
        if reason is not None:
            k = reason.split(":")[0]
            self.report.discarded[k] = self.report.discarded.get(k, 0) + 1
            self.report.discard_log.append((self.report.sims_used, k))
            return self._miss()
        self.invalid_run = 0
        self.seen.add(key)
        return True

    def _miss(self) -> bool:
        self.invalid_run += 1
        if self.invalid_run > MAX_INVALID_FACTOR * max(self.budget, 1):
            self.report.stop_reason = (f"gave up after {self.invalid_run} invalid or repeated candidates in a "
                                       "row: the search bounds are too wide for this seed, or every nearby "
                                       "layout fails already")
            raise GaveUp()
        return False


def uniform(space: SearchSpace, rnd: random.Random) -> tuple[float, ...]:
    return tuple(rnd.uniform(p.lo, p.hi) for p in space.params)


# -- random -----------------------------------------------------------------------------------
class RandomStrategy:
    """Uniform sampling; one Random stream, so results never depend on the evaluation."""

    lag = 1   # learns nothing from results: any lag is free

    def __init__(self, space: SearchSpace, report: Any, budget: int, seed_value: int):
        self.space, self.admission = space, _Admission(space, report, budget)
        self.rnd = random.Random(seed_value)

    def ask(self, room: int) -> list[tuple[tuple[float, ...], str]]:
        out = []
        while len(out) < min(room, GENERATION):
            offsets = uniform(self.space, self.rnd)
            if self.admission.admit(offsets):
                out.append((offsets, "random"))
        return out

    def tell(self, results: Sequence[Any]) -> None:
        pass


# -- hill-climb (Surrealist) ------------------------------------------------------------------
class HillClimb:
    """Coordinate hill-climb on one obstacle at a time, minimising min clearance: each step
    tries +step and -step on one coordinate; an improvement moves there and multiplies that
    coordinate's step by 1.5, a miss halves it; the climb moves to the next obstacle when every
    step of this one is below HILLCLIMB_MIN_STEP of its range or HILLCLIMB_STALL tries in a row
    missed. A failure found restarts the climb from the seed on the next obstacle."""

    lag = 0   # each step needs the result of the last one

    def __init__(self, space: SearchSpace, report: Any, budget: int, seed_value: int):
        self.space, self.admission = space, _Admission(space, report, budget)
        obstacle_groups = [tuple(i for i in g if space.params[i].kind == "offset")
                           for g in space.groups if space.params[g[0]].part.startswith(("obstacle:", "terrain:"))]
        self.groups = [g for g in obstacle_groups if g] or [g for g in space.groups]
        self.rnd = random.Random(seed_value)
        self.group = self.rnd.randrange(len(self.groups)) if seed_value else 0
        self.current: tuple[float, ...] = space.zero()
        self.current_value = self.seed_value_clearance = math.inf
        self.coord = 0
        self.misses = 0
        self.steps = self._fresh_steps()
        self.started = False
        self.climbs: list[list[float]] = [[]]   # clearance after each accepted move, per climb

    def _fresh_steps(self) -> dict[int, float]:
        return {i: HILLCLIMB_STEP * self.space.params[i].width for i in self.groups[self.group]}

    def _next_group(self, restart: bool) -> None:
        self.group = (self.group + 1) % len(self.groups)
        self.steps, self.coord, self.misses = self._fresh_steps(), 0, 0
        if restart:
            self.current, self.current_value = self.space.zero(), self.seed_value_clearance
            self.climbs.append([])

    def ask(self, room: int) -> list[tuple[tuple[float, ...], str]]:
        if not self.started:
            self.started = True
            if self.admission.admit(self.current):
                return [(self.current, "seed")]
        for _ in range(10 * len(self.space.params) + 10):
            out = self._probe()
            if out:
                return out[:room]
        while True:   # boxed in on every coordinate: a random restart (GaveUp ends a hopeless space)
            offsets = uniform(self.space, self.rnd)
            if self.admission.admit(offsets):
                self.current, self.current_value = offsets, math.inf
                self.climbs.append([])
                return [(offsets, "climb")]

    def _probe(self) -> list[tuple[tuple[float, ...], str]]:
        group = self.groups[self.group]
        if all(self.steps[i] < HILLCLIMB_MIN_STEP * self.space.params[i].width for i in group) \
                or self.misses >= HILLCLIMB_STALL:
            self._next_group(restart=False)
            group = self.groups[self.group]
        i = group[self.coord % len(group)]
        out = []
        for sign in (1.0, -1.0):
            trial = list(self.current)
            trial[i] += sign * self.steps[i]
            trial = self.space.clip(trial)
            if trial != self.current and self.admission.admit(trial):
                out.append((trial, "climb"))
        if not out:   # both directions out of bounds or invalid: count as a miss
            self.steps[i] /= 2
            self.misses += 1
            self.coord += 1
        return out

    def tell(self, results: Sequence[Any]) -> None:
        scored = [c for c in results if math.isfinite(c.clearance)]
        if not scored:
            return
        if results[0].origin == "seed":
            self.current_value = self.seed_value_clearance = scored[0].clearance
            return
        best = min(scored, key=lambda c: c.clearance)
        i = self.groups[self.group][self.coord % len(self.groups[self.group])]
        if best.failed:
            self._next_group(restart=True)
        elif best.clearance < self.current_value:
            self.current, self.current_value = best.offsets, best.clearance
            self.climbs[-1].append(best.clearance)
            self.steps[i] = min(self.steps[i] * 1.5, self.space.params[i].width)
            self.misses = 0
        else:
            self.steps[i] /= 2
            self.misses += 1
            self.coord += 1


# -- evolve (quality diversity) ----------------------------------------------------------------
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


class Evolve:
    """See the module docstring. Proposals come from one seeded Hypothesis run per generation."""

    def __init__(self, space: SearchSpace, report: Any, budget: int, seed_value: int):
        self.space, self.report, self.seed_value = space, report, seed_value
        self.admission = _Admission(space, report, budget)
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
        self.aim: tuple[str, int] | None = None         # the arm of the proposal being drawn
        self.aim_bandit: _Targets | None = None          # and the bandit it belongs to
        self.told = 0                                   # generations told so far
        self.shifted: dict[tuple, int] = {}             # signature -> times its failure was shifted
        self.seed_episode: Any = None                   # the seed's own episode (generation 1)
        self._way: tuple | None = None                  # (from the episode?, points, times): _expected_way

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
                  "shift": bool(self._shiftable()), "crowd": bool(self.cells.elites and self.slots)}
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
        grow and still find a way (``paths.passage_room``) less how deep the layout's obstacles
        cut into the robot's expected way (``_intrusion``); ties keep the drawing order."""
        from ..verdict.paths import passage_room

        scored = []
        for k, (offsets, _) in enumerate(proposals):
            scenario = self.space.apply(offsets)
            scored.append((passage_room(scenario, ROOM_LEVELS) - self._intrusion(scenario), k))
        return [proposals[k] for _, k in sorted(scored)]

    def _intrusion(self, scenario: Any) -> float:
        """How deep (m) the layout's obstacles cut into the footprint's half width around the
        robot's expected way: the seed's recorded path, or before its episode the seed's route
        driven at top speed; moving obstacles where they are at the moment the robot is there.
        0: the way is clear; more: the robot is pushed that far off its way."""
        import numpy as np
        import shapely

        from ..scenario.geometry import obstacle_polygon
        from ..scenario.motion import Track
        from ..verdict.paths import footprint_core

        pts, times = self._expected_way()
        _, hw, rho = footprint_core(scenario.robot.footprint)
        half = hw + rho
        nearest = math.inf
        for obs in scenario.obstacles:
            at = pts
            if getattr(obs, "motion", None) is not None:   # the way seen from where it is then
                track = Track(obs)
                at = pts - (track.positions(times) - track.positions(np.zeros(1)))
            nearest = min(nearest, float(shapely.distance(obstacle_polygon(obs), shapely.points(at)).min()))
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
            self._way = (recorded, pts, np.linspace(0.0, duration, len(pts)))
        return self._way[1], self._way[2]

    def _hypothesis_batch(self, n: int, attempt: int) -> list[tuple[tuple[float, ...], str]]:
        """Up to ``n`` valid proposals drawn in one seeded Hypothesis run."""
        from hypothesis import HealthCheck, Phase, Verbosity, given, reject, settings
        from hypothesis import seed as hseed
        from hypothesis import strategies as st

        out: list[tuple[tuple[float, ...], str]] = []
        weights = self.weights() if self.told else [1.0 if op == "explore" else 0.0 for op in OPERATORS]
        total = sum(weights)

        def body(data):
            # 32 booleans, not an integer: Hypothesis mixes constants found in the loaded
            # modules into integer draws, which would make the stream depend on what is imported
            bits = data.draw(st.lists(st.booleans(), min_size=STREAM_BITS, max_size=STREAM_BITS), label="stream")
            stream = sum(1 << i for i, b in enumerate(bits) if b)
            rnd = random.Random(f"{self.seed_value}:{self.generation}:{attempt}:{len(out)}:{stream}")
            # not a Hypothesis integer: those favour small values
            op = _weighted_pick(OPERATORS, weights, rnd.random() * total)
            offsets, parent = self.propose(op, rnd)
            if parent is not None and self._repeats(parent, offsets):
                self.report.skipped += 1   # would most likely fail the same way again
                reject()
            if len(out) >= n or not self.admission.admit(offsets):
                reject()
            if self.aim is not None:
                self.aims[_key(offsets)] = (self.aim_bandit, self.aim)
            out.append((offsets, op))

        run = settings(max_examples=n, database=None, deadline=None, phases=[Phase.generate],
                       suppress_health_check=list(HealthCheck), verbosity=Verbosity.quiet,
                       derandomize=False, report_multiple_bugs=False, print_blob=False)(
            hseed(self.seed_value * 1_000_003 + self.generation * 101 + attempt)(given(st.data())(body)))
        run()
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
            from .fitness import Route
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
        route = self._route()
        path = [p for p in parent.path[1:]] or [p[:2] for p in _route_samples(route)]
        if quarter is not None:
            inq = [p for p in path if _quarter(route.fraction(*p)) == quarter]
            path = inq or [p[:2] for p in _route_samples(route) if _quarter(p[2]) == quarter] or path
        fp = self.space.seed.robot.footprint
        contact = (fp.radius if fp.shape == "circle" else fp.width / 2) + half
        if within is not None:   # path points from which the band beside the path is in the box
            path = [p for k, p in enumerate(path) if _beside_within(path, k, 1.15 * contact, within)] or path
        (px, py), (ux, uy) = self._anchor(parent, path, rnd)
        lateral = rnd.uniform(*SQUEEZE_BAND) * rnd.choice((-1.0, 1.0)) if squeeze else rnd.uniform(-1.3, 1.3)
        lateral *= contact
        return px - uy * lateral, py + ux * lateral, px, py

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
            from ..scenario.motion import Track

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
        from ..scenario.motion import Track

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
    from ..scenario.geometry import footprint_polygon, rectangle

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
    from ..scenario.geometry import obstacle_polygon
    x0, y0, x1, y1 = obstacle_polygon(obs).bounds
    return min(x1 - x0, y1 - y0) / 2


def _has(space: SearchSpace, group: Sequence[int], attr: str) -> bool:
    return any(space.params[i].attr == attr for i in group)


def make_strategy(name: str, space: SearchSpace, report: Any, budget: int, seed_value: int) -> Any:
    cls = {"evolve": Evolve, "random": RandomStrategy, "hillclimb": HillClimb}[name]
    return cls(space, report, budget, seed_value)


__all__ = ["Evolve", "HillClimb", "RandomStrategy", "make_strategy", "GaveUp"]
