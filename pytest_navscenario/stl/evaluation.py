"""``robustness`` and ``evaluate``: a formula against signals sampled every ``dt`` seconds.

The robustness at sample i says how far the formula is from flipping at time ``i * dt``, in the
units of the signals it compares (metres for a distance, m/s for a speed): positive where it holds,
negative where it is violated. The verdict is the robustness at sample 0. The semantics are
RTAMT's offline discrete-time evaluator's, end of trace included (see ``windows.py``); the tests
check agreement with RTAMT itself on random formulas and traces.

"First violated at": the sample where the violation shows, found from the top of the formula down
(``witness``): for ``always φ`` the earliest sample of its window where φ is negative, looking
into φ (``always (always[0:5] x > 0)`` gives the sample where ``x`` first drops, not five before);
for ``eventually φ`` the end of its window (the deadline that passed); for ``and`` the earliest
violated part; for ``or`` (every part violated) the latest; ``not`` and ``implies`` by their
duals (``not eventually φ`` is ``always not φ``); any other operator at the sample itself.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from .tree import COMPARISONS, Node
from .errors import StlEvaluationError
from .formula import Formula, parse
from .plan import LENGTH, plan, plan_for, samples


@dataclass(frozen=True)
class Evaluation:
    """A formula's verdict on one trace. ``robustness`` is ``rho[0]``; ``violated`` is
    ``robustness < 0``; the first violation (``None`` when it holds) in seconds from the first
    sample and as a sample index; ``rho`` the robustness at every sample."""

    robustness: float
    violated: bool
    first_violation_time: float | None
    first_violation_index: int | None
    rho: np.ndarray


def robustness(formula: Formula | str, signals: Mapping[str, object], dt: float) -> np.ndarray:
    """The robustness of ``formula`` at every sample (float64, one per sample).

    ``signals`` maps each name the formula reads to a 1-D sequence, all of one length, sampled
    every ``dt`` seconds (intervals in the formula are seconds; each bound must be a whole number
    of periods). Raises ``StlEvaluationError`` for a missing signal, mismatched lengths, an empty
    trace or an interval that is not a whole number of periods.
    """
    formula = parse(formula) if isinstance(formula, str) else formula
    step = plan_for(formula, dt)
    return np.asarray(step(_arrays(formula, signals)), dtype=np.float64)


def evaluate(formula: Formula | str, signals: Mapping[str, object], dt: float) -> Evaluation:
    """The verdict of ``formula`` on the signals: ``robustness`` plus where it was first violated."""
    formula = parse(formula) if isinstance(formula, str) else formula
    arrays = _arrays(formula, signals)
    rho = np.asarray(plan_for(formula, dt)(arrays), dtype=np.float64)
    value = float(rho[0])
    if np.isnan(value):
        raise StlEvaluationError(f"{formula.text}: the robustness at time 0 is undefined (NaN)",
                                 "it comes from 0/0, sqrt of a negative number, or iff/xor of two "
                                 "windows past the end of the trace: guard the arithmetic or the windows")
    if not value < 0:
        return Evaluation(value, False, None, None, rho)
    index = _Witness(formula, arrays, dt).find(formula.root, 0, False)
    return Evaluation(value, True, round(index * dt, 9), index, rho)


def _arrays(formula: Formula, signals: Mapping[str, object]) -> dict:
    out: dict = {}
    n = None
    for name in sorted(formula.signals):
        if name not in signals:
            have = ", ".join(sorted(signals)) or "none"
            raise StlEvaluationError(f"{formula.text}: no signal {name!r} (signals given: {have})",
                                     f"declare {name!r} or correct its name in the formula")
        x = np.asarray(signals[name], dtype=np.float64)
        if x.ndim != 1:
            raise StlEvaluationError(f"signal {name!r} has shape {x.shape}; one value per sample is needed",
                                     "pass a 1-D array")
        if n is not None and x.shape[0] != n:
            raise StlEvaluationError(f"signal {name!r} has {x.shape[0]} samples, the others {n}",
                                     "sample every signal at the same ticks")
        if np.isnan(x).any():
            first = int(np.flatnonzero(np.isnan(x))[0])
            raise StlEvaluationError(f"signal {name!r} is NaN at sample {first} (of {x.shape[0]})",
                                     "a signal must have a value at every sample; fix the function "
                                     "that computes it")
        n = x.shape[0]
        out[name] = x
    if n is None:       # a formula of constants only: any signal gives the length
        lengths = {len(v) for v in signals.values()}
        n = lengths.pop() if len(lengths) == 1 else None
        if n is None:
            raise StlEvaluationError(f"{formula.text}: reads no signal, and the signals given do not say "
                                     "how many samples there are", "pass at least one signal")
    if n == 0:
        raise StlEvaluationError(f"{formula.text}: the signals have no samples", "evaluate a non-empty trace")
    out[LENGTH] = n
    return out


class _Witness:
    """Where a violated formula first shows its violation (module docstring)."""

    def __init__(self, formula: Formula, arrays: dict, dt: float):
        self.arrays = arrays
        self.n = arrays[LENGTH]
        self.dt = dt
        self.text = formula.text
        self.cache: dict[int, np.ndarray] = {}

    def rho(self, node: Node) -> np.ndarray:
        got = self.cache.get(id(node))
        if got is None:
            got = self.cache[id(node)] = np.asarray(plan(node, self.dt, self.text)(self.arrays), dtype=float)
        return got

    def window(self, node: Node, i: int) -> tuple[int, int]:
        if node.interval is None:
            return i, self.n - 1
        a = samples(node.interval[0], self.dt, node, self.text)
        b = samples(node.interval[1], self.dt, node, self.text)
        return min(i + a, self.n - 1), min(i + b, self.n - 1)

    def find(self, node: Node, i: int, negated: bool) -> int:
        """The sample where ``node`` (or ``not node`` if ``negated``), violated at ``i``, shows it."""
        op = node.op
        if op == "not":
            return self.find(node.args[0], i, not negated)
        if op in COMPARISONS:
            return i
        if (op == "always" and not negated) or (op == "eventually" and negated):
            lo, hi = self.window(node, i)
            body = self.rho(node.args[0])[lo:hi + 1]
            bad = np.flatnonzero(body > 0 if negated else body < 0)
            return self.find(node.args[0], lo + int(bad[0]), negated) if bad.size else i
        if op in ("always", "eventually"):
            return self.window(node, i)[1]
        if op in ("and", "or", "implies"):
            return self._logic(node, i, negated)
        if op == "until" and not negated:
            lo, hi = self.window(node, i)
            broken = np.flatnonzero(self.rho(node.args[0])[i:hi + 1] < 0)
            return min(i + int(broken[0]), hi) if broken.size else hi
        return i

    def _logic(self, node: Node, i: int, negated: bool) -> int:
        left, right = node.args
        left_negated = negated if node.op != "implies" else not negated
        # violated parts: and -> any violated part; or/implies -> all parts violated
        conjunction = (node.op == "and") != negated
        parts = [(left, left_negated), (right, negated)]
        times = [self.find(part, i, neg) for part, neg in parts if self._violated(part, i, neg)]
        if not times:
            return i
        return min(times) if conjunction else max(times)

    def _violated(self, node: Node, i: int, negated: bool) -> bool:
        value = self.rho(node)[i]
        return bool(value > 0) if negated else bool(value < 0)
