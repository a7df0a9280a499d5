"""Search strategies as ask/tell objects: ``ask(room)`` proposes a generation of valid candidates
(offset vectors with their origin), ``tell(results)`` receives them simulated, in proposal order.

* ``random``: uniform sampling over the space (the baseline).
* ``hillclimb``: the Surrealist baseline, an adaptive-step coordinate hill-climb over one seed
  obstacle's parameters at a time that minimises the minimum clearance.
* ``evolve`` (default): a quality-diversity search. A MAP-Elites archive keyed by the cause
  signature (fitness.py) keeps the closest-to-failing candidate of each behaviour; parents are
  picked from it with a penalty on cells picked often, so the budget spreads over ways of
  failing instead of one failure's neighbours. Operators: uniform exploration, Gaussian
  mutation, and two that use what the episode showed (PHYS-FUZZ style): move an obstacle onto
  the robot's path at or a moment after its closest approach, or insert a new obstacle there.
  Operator shares follow which operator has been finding new behaviours and failures.
  Hypothesis draws each proposal (operator, parent, random stream) in one seeded Hypothesis run
  per generation.

A generation's size is the strategy's own constant, so what is proposed never depends on how
many candidates are evaluated at once.
"""
from __future__ import annotations

import math
import random
from typing import Any, Sequence

from .space import FLAG_ON, SearchSpace, invalid_reason

GENERATION = 8                 # candidates per generation (evolve, random)
MUTATION_SCALES = (0.05, 0.15, 0.3)   # Gaussian step sd as a fraction of the parameter's range
OPERATORS = ("explore", "mutate", "place", "insert")
MIN_SHARE = 0.15               # every usable operator keeps at least this share
PICK_PENALTY = 0.03            # robustness added per earlier pick of an archive cell (novelty)
NEAR_COPY = 0.5                # m: a failure's child whose culprit moved less (same quarter) is skipped
FAILURE_FLOOR = -0.3           # failure cells compete for parenthood as if this robust
HILLCLIMB_STEP = 0.25          # initial step, fraction of the range
HILLCLIMB_MIN_STEP = 0.02      # a coordinate is done when its step is below this fraction
HILLCLIMB_STALL = 8            # misses in a row on one obstacle: move to the next
MAX_INVALID_FACTOR = 50
STREAM_BITS = 32               # Hypothesis-drawn bits seeding each proposal's random stream


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

    def __init__(self, space: SearchSpace, report: Any, budget: int, seed_value: int):
        self.space, self.admission = space, _Admission(space, report, budget)
        obstacle_groups = [tuple(i for i in g if space.params[i].kind == "offset")
                           for g in space.groups if space.params[g[0]].part.startswith("obstacle:")]
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
    """MAP-Elites archive: the elite (lowest robustness) of each cause signature."""

    def __init__(self):
        self.elites: dict[tuple, Any] = {}
        self.picks: dict[tuple, int] = {}

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
                   key=lambda k: max(self.elites[k].robustness, FAILURE_FLOOR) + PICK_PENALTY * self.picks.get(k, 0))
        self.picks[best] = self.picks.get(best, 0) + 1
        return self.elites[best]


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
        self.failure_signatures: set[tuple] = set()
        self.route: Any = None

    def weights(self) -> list[float]:
        usable = {"explore": True, "mutate": bool(self.cells.elites),
                  "place": bool(self.cells.elites and self.movable), "insert": bool(self.cells.elites and self.slots)}
        rates = {op: (self.stats[op][1] + 1.0) / (self.stats[op][0] + 2.0) for op in OPERATORS if usable[op]}
        total = sum(rates.values())
        return [max(MIN_SHARE, rates[op] / total) if op in rates else 0.0 for op in OPERATORS]

    def ask(self, room: int) -> list[tuple[tuple[float, ...], str]]:
        self.generation += 1
        out: list[tuple[tuple[float, ...], str]] = []
        if self.generation == 1 and self.admission.admit(self.space.zero()):
            out.append((self.space.zero(), "seed"))
        want = min(room, GENERATION)
        attempt = 0
        while len(out) < want:   # ends: the admission gives up (GaveUp) after too many misses
            out.extend(self._hypothesis_batch(want - len(out), attempt))
            attempt += 1
        return out[:want]

    def _hypothesis_batch(self, n: int, attempt: int) -> list[tuple[tuple[float, ...], str]]:
        """Up to ``n`` valid proposals drawn in one seeded Hypothesis run."""
        from hypothesis import HealthCheck, Phase, Verbosity, given, reject, settings
        from hypothesis import seed as hseed
        from hypothesis import strategies as st

        out: list[tuple[tuple[float, ...], str]] = []
        weights = self.weights()
        total = sum(weights)

        def body(data):
            # 32 booleans, not an integer: Hypothesis mixes constants found in the loaded
            # modules into integer draws, which would make the stream depend on what is imported
            bits = data.draw(st.lists(st.booleans(), min_size=STREAM_BITS, max_size=STREAM_BITS), label="stream")
            stream = sum(1 << i for i, b in enumerate(bits) if b)
            rnd = random.Random(f"{self.seed_value}:{self.generation}:{attempt}:{len(out)}:{stream}")
            ticket = rnd.random() * total   # not a Hypothesis integer: those favour small values
            op = OPERATORS[-1]
            for name, w in zip(OPERATORS, weights):
                if ticket < w:
                    op = name
                    break
                ticket -= w
            offsets, parent = self.propose(op, rnd)
            if parent is not None and self._repeats(parent, offsets):
                self.report.skipped += 1   # would most likely fail the same way again
                reject()
            if len(out) >= n or not self.admission.admit(offsets):
                reject()
            out.append((offsets, op))

        run = settings(max_examples=n, database=None, deadline=None, phases=[Phase.generate],
                       suppress_health_check=list(HealthCheck), verbosity=Verbosity.quiet,
                       derandomize=False, report_multiple_bugs=False, print_blob=False)(
            hseed(self.seed_value * 1_000_003 + self.generation * 101 + attempt)(given(st.data())(body)))
        run()
        return out

    def propose(self, op: str, rnd: random.Random) -> tuple[tuple[float, ...], Any]:
        """(offsets, parent) of one proposal of operator ``op`` (parent None for exploration)."""
        if op == "explore" or not self.cells.elites:
            return uniform(self.space, rnd), None
        parent = self.cells.pick(rnd)
        if op == "place" and parent.path:
            return self._place(parent, rnd), parent
        if op == "insert" and parent.path:
            return self._insert(parent, rnd), parent
        return self._mutate(parent, rnd), parent

    def _repeats(self, parent: Any, offsets: Sequence[float]) -> bool:
        """A child of a failure that changes no parameter by 20 % of its range or more and
        leaves the culprit in place (same quarter of the route, moved < NEAR_COPY) would most
        likely fail the same way: a near-copy, not worth a simulation."""
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

    def _target(self, parent: Any, rnd: random.Random, half: float, culprit: str) -> tuple[float, float]:
        """A point beside the parent's path where an obstacle would be met, offset sideways by up
        to 1.3 times the robot's half width plus ``half``: at or a moment after the closest
        approach (time-to-impact placement), else anywhere along the path. Quarters of the route
        where ``culprit`` already caused a known failure are avoided while others are left (a
        new place, a new way of failing)."""
        path, route = parent.path, self._route()
        n = len(path)
        known = {sig[2] for sig in self.failure_signatures if sig[1] == culprit}
        quarter = [min(3, int(route.fraction(x, y) * 4)) for x, y in path]
        inner = range(max(1, n // 10), max(2, n - 1))
        allowed = [j for j in inner if j < n and quarter[j] not in known] or [j for j in inner if j < n] or [0]
        j = rnd.choice(allowed)
        if parent.closest and rnd.random() < 0.6 and all(math.isfinite(v) for v in parent.closest[1:]):
            _, cx, cy = parent.closest
            j0 = min(range(n), key=lambda k: (path[k][0] - cx) ** 2 + (path[k][1] - cy) ** 2)
            jc = min(n - 1, j0 + rnd.randrange(0, max(2, n // 8)))
            j = jc if quarter[jc] not in known else j
        a, b = path[max(0, j - 1)], path[min(n - 1, j + 1)]
        dx, dy = b[0] - a[0], b[1] - a[1]
        norm = math.hypot(dx, dy) or 1.0
        fp = self.space.seed.robot.footprint
        robot_half = fp.radius if fp.shape == "circle" else fp.width / 2
        lateral = rnd.uniform(-1.3, 1.3) * (robot_half + half)
        return path[j][0] - dy / norm * lateral, path[j][1] + dx / norm * lateral

    def _place(self, parent: Any, rnd: random.Random) -> tuple[float, ...]:
        space, offsets = self.space, list(parent.offsets)
        culprit = [g for g in self.movable if space.params[g[0]].part == f"obstacle:{parent.culprit}"]
        group = culprit[0] if culprit and rnd.random() < 0.5 else rnd.choice(self.movable)
        obs = space.seed.obstacle(space.params[group[0]].part.split(":", 1)[1])
        half = getattr(obs, "radius", None) or min(getattr(obs, "length", 0.5), getattr(obs, "width", 0.5)) / 2
        tx, ty = self._target(parent, rnd, half, obs.name)
        for i in group:
            attr = space.params[i].attr
            if attr == "dx":
                offsets[i] = tx - obs.x
            elif attr == "dy":
                offsets[i] = ty - obs.y
            elif attr == "removed":
                offsets[i] = 0.0
        return space.clip(offsets)

    def _insert(self, parent: Any, rnd: random.Random) -> tuple[float, ...]:
        space, offsets = self.space, list(parent.offsets)
        free = [g for g in self.slots if offsets[g[0]] < FLAG_ON]
        group = rnd.choice(free or self.slots)
        x0, y0, x1, y1 = space.region
        lo = space.limits.insert_size[0]
        values = {"on": 1.0, "size": rnd.uniform(0.0, space.limits.insert_size[1] - lo),
                  "yaw": rnd.uniform(-90.0, 90.0)}
        tx, ty = self._target(parent, rnd, (lo + values["size"]) / 2, "inserted")
        values["x"], values["y"] = tx - (x0 + x1) / 2, ty - (y0 + y1) / 2
        for i in group:
            offsets[i] = values.get(space.params[i].attr, offsets[i])
        return space.clip(offsets)

    def tell(self, results: Sequence[Any]) -> None:
        for cand in results:
            before = self.cells.elites.get(cand.signature)
            self.cells.add(cand)
            new_failure = cand.failed and cand.signature not in self.failure_signatures
            if cand.failed:
                self.failure_signatures.add(cand.signature)
            improved = (not cand.failed and math.isfinite(cand.robustness)
                        and (before is None or cand.robustness < before.robustness))
            if cand.origin in self.stats:   # credit: new ways of failing, and moves toward failing
                self.stats[cand.origin][0] += 1
                self.stats[cand.origin][1] += (3.0 if new_failure else 0.0) + (0.5 if improved else 0.0)


def _has(space: SearchSpace, group: Sequence[int], attr: str) -> bool:
    return any(space.params[i].attr == attr for i in group)


def make_strategy(name: str, space: SearchSpace, report: Any, budget: int, seed_value: int) -> Any:
    cls = {"evolve": Evolve, "random": RandomStrategy, "hillclimb": HillClimb}[name]
    return cls(space, report, budget, seed_value)


__all__ = ["Evolve", "HillClimb", "RandomStrategy", "make_strategy", "GaveUp"]
