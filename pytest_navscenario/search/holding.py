"""Failures that hold: how often a failing layout fails under the scenario's own randomness.

A layout that failed once may have failed on one unlucky draw of the lidar's noise (a knife-edge:
a gap exactly one footprint wide, a timing that works once). Its *failure probability* is how
often it fails over fresh noise seeds (the lidar's noise, dropout and spurious returns, the
localisation drift and the seed's opt-in perturbations, scenario.model.randomness). The search
confirms each failure before it counts: the layout is run again under new noise seeds (run k uses
the base seed ``core.seeds.repeat_seed(nav_seed, k)``, as ``--nav-repeat`` does, so
``pytest <frozen file> --nav-seed N --nav-repeat k+1`` replays them), and Wald's sequential test
(core.rates.Sprt) decides between "fails with probability at least the threshold" (``p1``, default
0.9, ``--navsearch-hold``) and "at most ``p0``", the probability whose odds are ODDS_RATIO times
smaller (0.5 for 0.9), with error rates of 10 % each. It stops as soon as the evidence is
decisive: a layout that fails every time is confirmed after 4 runs, one that passes twice in a
row is rejected after 2. The run that found the layout is not counted (it was picked because it
failed). A run counts as failing when its outcome is any failure (the frozen file, a regression
test, fails then), not only the found one.

A scenario without randomness needs no confirmation: one run decides (``exact``), as does a
threshold of 0 (confirmation off).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..core.rates import Sprt, clopper_pearson

DEFAULT_HOLD = 0.9
ODDS_RATIO = 9.0          # p0's odds are the threshold's divided by this
ALPHA = BETA = 0.1        # the test's error rates
MAX_RUNS = 20             # a test still undecided after this many runs decides by its sign
MAX_REJECTIONS = 3        # a way of failing rejected this often is not confirmed again
CONFIDENCE = 0.95         # of the reported interval (Clopper-Pearson)


def hold_test(threshold: float) -> Sprt | None:
    """The sequential test for ``threshold`` (None: 0, confirmation off). ValueError outside [0, 1)."""
    if not 0.0 <= threshold < 1.0 or math.isnan(threshold):
        raise ValueError(f"the hold threshold is a failure probability from 0 (off) to below 1, got {threshold}")
    if threshold == 0.0:
        return None
    odds = threshold / (1.0 - threshold) / ODDS_RATIO
    return Sprt(p0=odds / (1.0 + odds), p1=threshold, alpha=ALPHA, beta=BETA, max_runs=MAX_RUNS)


@dataclass
class Estimate:
    """What the confirmation runs of one layout showed. ``decision``: "pending" (runs to come),
    "held", "rejected", "unconfirmed" (the budget ran out first), "exact" (the scenario has no
    randomness: the one run decides) or "off" (confirmation off)."""
    decision: str = "pending"
    outcomes: list[bool] = field(default_factory=list)   # per confirmation run: did it fail
    threshold: float = DEFAULT_HOLD

    @property
    def runs(self) -> int:
        return len(self.outcomes)

    @property
    def failed(self) -> int:
        return sum(self.outcomes)

    @property
    def probability(self) -> float | None:
        """The estimated failure probability (1 for an exact one; None when nothing was run)."""
        if self.decision == "exact":
            return 1.0
        return self.failed / self.runs if self.runs else None

    @property
    def interval(self) -> tuple[float, float] | None:
        """The 95 % Clopper-Pearson interval of the probability (None when nothing was run)."""
        if self.decision == "exact":
            return 1.0, 1.0
        return clopper_pearson(self.failed, self.runs, CONFIDENCE) if self.runs else None

    @property
    def holds(self) -> bool:
        return self.decision in ("held", "exact", "off")

    def describe(self) -> str:
        """"fails in 4/4 runs (95 % 0.40-1.00)", "fails every run (no randomness)", ..."""
        if self.decision == "exact":
            return "fails every run (the scenario has no randomness)"
        if self.decision == "off":
            return "not confirmed (--navsearch-hold 0)"
        if not self.runs:
            return "not confirmed yet"
        lo, hi = self.interval or (0.0, 1.0)
        return f"fails in {self.failed}/{self.runs} runs (95 % {lo:.2f}-{hi:.2f})"

    def provenance(self, nav_seed: int) -> dict[str, Any]:
        """The estimate as a frozen file's provenance keys."""
        out: dict[str, Any] = {"confirmation": self.decision}
        if self.decision != "off":
            out["hold_threshold"] = self.threshold
        p, iv = self.probability, self.interval
        if p is not None and iv is not None:
            out["failure_probability"] = round(p, 6)
            out["failure_probability_interval"] = [round(iv[0], 6), round(iv[1], 6)]
        if self.runs:
            out["confirmation_runs"] = self.runs
            out["confirmation_failures"] = self.failed
            out["confirmation_replay"] = f"--nav-seed {nav_seed} --nav-repeat {self.runs + 1}"
        return out

    def to_data(self) -> dict[str, Any]:
        return {"decision": self.decision, "outcomes": list(self.outcomes), "threshold": self.threshold}

    @classmethod
    def from_data(cls, data: dict[str, Any] | None) -> "Estimate":
        if not data:
            return cls(decision="off", threshold=0.0)
        return cls(data["decision"], [bool(v) for v in data["outcomes"]], data["threshold"])


def decide(test: Sprt, estimate: Estimate) -> None:
    """Update ``estimate.decision`` from its outcomes (pending until the test decides)."""
    verdict, _ = test.decide(estimate.outcomes)
    estimate.decision = {"accept": "held", "reject": "rejected"}.get(verdict, "pending")
