"""``random``: uniform sampling over the search space, the baseline every strategy is measured against."""
from __future__ import annotations

import random
from typing import Any

from ..space import SearchSpace
from .admission import Admission, uniform
from .protocol import GENERATION, BaseStrategy, Proposal


class RandomStrategy(BaseStrategy):
    """Uniform sampling; one Random stream, so results never depend on the evaluation."""

    lag = 1   # learns nothing from results: any lag is free

    def __init__(self, space: SearchSpace, report: Any, budget: int, seed_value: int):
        self.space, self.admission = space, Admission(space, report, budget)
        self.rnd = random.Random(seed_value)

    def ask(self, room: int) -> list[Proposal]:
        out = []
        while len(out) < min(room, GENERATION):
            offsets = uniform(self.space, self.rnd)
            if self.admission.admit(offsets):
                out.append((offsets, "random"))
        return out

