"""What the strategies share: the validity and repeat filter every proposal passes (``Admission``,
which counts what it discards in the report and gives up when almost nothing is valid) and a
uniform draw over the space."""
from __future__ import annotations

import random
from typing import Any, Sequence

from ...verdict.open_way import open_way
from ..space import SearchSpace, invalid_reason
from .protocol import GaveUp

MAX_INVALID_FACTOR = 50        # give up after budget * this many invalid or repeated candidates in a row


class Admission:
    """Validity check and repeat filter shared by the strategies (counts what it discards)."""

    def __init__(self, space: SearchSpace, report: Any, budget: int, margin: float = 0.0):
        self.space, self.report, self.budget = space, report, budget
        self.seen: set[tuple[float, ...]] = set()
        self.invalid_run = 0
        self.margin = margin                  # the footprint's growth open_way is asked about
        self.clear: dict[tuple, float] = {}   # admitted with an open way at ``margin``: key -> its length
        self._last: float | None = None

    def admit(self, offsets: Sequence[float]) -> bool:
        key = tuple(round(v, 6) for v in offsets)
        if key in self.seen:
            self.report.skipped += 1
            return self._miss()
        self._last = None
        reason = invalid_reason(self.space.apply(offsets), self._way)
        if reason is not None:
            k = reason.split(":")[0]
            self.report.discarded[k] = self.report.discarded.get(k, 0) + 1
            self.report.discard_log.append((self.report.sims_used, k))
            return self._miss()
        self.invalid_run = 0
        self.seen.add(key)
        if self._last is not None:
            self.clear[key] = self._last
        return True

    def _way(self, scenario: Any) -> float | None:
        """``open_way`` at ``margin`` (the path checks' answer without a path search, or None)."""
        self._last = open_way(scenario, self.margin)
        return self._last

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

