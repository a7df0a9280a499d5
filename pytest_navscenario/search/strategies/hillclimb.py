"""``hillclimb``: the Surrealist baseline, an adaptive-step coordinate hill-climb over one seed
obstacle's parameters at a time that minimises the minimum clearance."""
from __future__ import annotations

import math
import random
from typing import Any, Sequence

from ..space import SearchSpace
from .admission import Admission, uniform
from .protocol import BaseStrategy, Proposal

HILLCLIMB_STEP = 0.25          # initial step, fraction of the range
HILLCLIMB_MIN_STEP = 0.02      # a coordinate is done when its step is below this fraction
HILLCLIMB_STALL = 8            # misses in a row on one obstacle: move to the next


class HillClimb(BaseStrategy):
    """Coordinate hill-climb on one obstacle at a time, minimising min clearance: each step
    tries +step and -step on one coordinate; an improvement moves there and multiplies that
    coordinate's step by 1.5, a miss halves it; the climb moves to the next obstacle when every
    step of this one is below HILLCLIMB_MIN_STEP of its range or HILLCLIMB_STALL tries in a row
    missed. A failure found restarts the climb from the seed on the next obstacle."""

    lag = 0   # each step needs the result of the last one

    def __init__(self, space: SearchSpace, report: Any, budget: int, seed_value: int):
        self.space, self.admission = space, Admission(space, report, budget)
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

    def ask(self, room: int) -> list[Proposal]:
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

    def _probe(self) -> list[Proposal]:
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

