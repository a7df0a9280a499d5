"""How closely two runs of the same episodes agree: the warp batch engine (single precision, its
own solver order) against the CPU engine, which cannot be compared bit for bit.

``compare(a, b)`` measures one pair of EpisodeResults: the same outcome, the largest distance
between the robot's positions at the same physics steps, the largest heading difference, and how
far apart the episodes ended. ``Tolerance`` is what "agree" means; ``AGREE`` is the tolerance the
tests and ``benchmarks/bench_gpu_batch.py`` hold the warp engine to (docs/architecture.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np


@dataclass(frozen=True)
class Tolerance:
    """Two episodes agree when they end with the same outcome, within ``end`` seconds of each
    other, their positions within ``position`` metres and headings within ``yaw`` radians at every
    physics step both ran."""
    position: float = 0.01
    yaw: float = 0.01
    end: float = 0.1


AGREE = Tolerance()


@dataclass(frozen=True)
class Agreement:
    """One episode run twice: each run's outcome and end time, and the largest differences."""
    name: str
    outcome_a: str
    outcome_b: str
    end_a: float
    end_b: float
    position: float       # m: the largest distance between the positions at the same step
    yaw: float            # rad: the largest heading difference at the same step

    def within(self, tol: Tolerance = AGREE) -> bool:
        return (self.outcome_a == self.outcome_b and abs(self.end_a - self.end_b) <= tol.end
                and self.position <= tol.position and self.yaw <= tol.yaw)

    def describe(self) -> str:
        same = "same outcome" if self.outcome_a == self.outcome_b else f"{self.outcome_a} vs {self.outcome_b}"
        return (f"{self.name}: {same}, ends {self.end_a:.2f} s / {self.end_b:.2f} s, positions within "
                f"{self.position:.2e} m, headings within {self.yaw:.2e} rad")


def compare(a: Any, b: Any, name: str = "") -> Agreement:
    """The Agreement of two EpisodeResults (or SimResults) of one episode."""
    ta, tb = a.trajectory, b.trajectory
    n = min(len(ta.pose), len(tb.pose))
    if n:
        d = ta.pose[:n] - tb.pose[:n]
        position = float(np.hypot(d[:, 0], d[:, 1]).max())
        yaw = float(np.abs((d[:, 2] + math.pi) % (2 * math.pi) - math.pi).max())
    else:
        position = yaw = 0.0
    end_a = float(ta.t[-1]) if len(ta.t) else 0.0
    end_b = float(tb.t[-1]) if len(tb.t) else 0.0
    if not name:
        name = getattr(getattr(a, "scenario", None), "name", "") or ""
    return Agreement(name, _outcome(a), _outcome(b), end_a, end_b, position, yaw)


def _outcome(result: Any) -> str:
    outcome = getattr(result, "outcome", None)
    return str(getattr(outcome, "value", outcome)) if outcome is not None else str(getattr(result, "end", ""))


def summary(rows: Sequence[Agreement], tol: Tolerance = AGREE) -> str:
    """One line: how many episodes agree within ``tol``, the largest differences among them."""
    if not rows:
        return "no episodes compared"
    ok = [r for r in rows if r.within(tol)]
    same = sum(r.outcome_a == r.outcome_b for r in rows)
    worst_pos = max(r.position for r in rows)
    worst_yaw = max(r.yaw for r in rows)
    return (f"{len(ok)} of {len(rows)} episodes agree within {tol.position} m, {tol.yaw} rad and "
            f"{tol.end} s ({same} of {len(rows)} with the same outcome); largest differences: "
            f"{worst_pos:.2e} m, {worst_yaw:.2e} rad")
