"""A test-only stand-in for ``pytest_navscenario.stl`` (branch ``stl``) until that package lands:
the agreed API (parse, Formula, StlSyntaxError, robustness, evaluate, Evaluation) over RTAMT, the
reference implementation. Installed by this folder's conftest only when the real package is
missing; never shipped."""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

_KEYWORDS = {"always", "eventually", "until", "and", "or", "not", "implies", "true", "false",
             "historically", "once", "since", "next", "prev", "iff", "xor", "abs", "G", "F", "U"}
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class StlSyntaxError(ValueError):
    def __init__(self, message: str, column: int = 1, hint: str = ""):
        super().__init__(message)
        self.message, self.column, self.hint = message, column, hint


@dataclass(frozen=True)
class Formula:
    text: str
    signals: frozenset


@dataclass(frozen=True)
class Evaluation:
    robustness: float
    violated: bool
    first_violation_time: float | None
    first_violation_index: int | None
    rho: np.ndarray


def _spec(text: str, names, dt: float):
    import rtamt
    spec = rtamt.StlDiscreteTimeSpecification()
    for name in sorted(names):
        spec.declare_var(name, "float")
    spec.set_sampling_period(int(round(dt * 1000)), "ms", 0.1)
    spec.spec = text
    spec.parse()
    return spec


def parse(text: str) -> Formula:
    if not isinstance(text, str) or not text.strip():
        raise StlSyntaxError("the formula is empty", 1, "write e.g. always (clearance >= 0.3)")
    if text.count("(") != text.count(")"):
        column = len(text) if text.count("(") > text.count(")") else text.rfind(")") + 1
        raise StlSyntaxError("unbalanced parentheses", column, "close every '(' with a ')'")
    stripped = re.sub(r"\[[^\]]*\]", "", text)
    names = frozenset(m.group(0) for m in _IDENT.finditer(stripped) if m.group(0) not in _KEYWORDS)
    try:
        _spec(text, names, 0.1)
    except Exception as exc:       # RTAMT's parse errors
        raise StlSyntaxError(f"not a formula: {exc}", 1, "write STL such as always (d >= 0.8)") from None
    return Formula(" ".join(text.split()), names)


def robustness(formula: Formula, signals, dt: float) -> np.ndarray:
    spec = _spec(formula.text, formula.signals, dt)
    n = len(next(iter(signals.values())))
    data = {"time": [round(i * dt, 9) for i in range(n)]}
    data.update({k: [float(v) for v in signals[k]] for k in formula.signals})
    return np.array([v for _, v in spec.evaluate(data)], dtype=float)


def evaluate(formula: Formula, signals, dt: float) -> Evaluation:
    rho = robustness(formula, signals, dt)
    value = float(rho[0])
    first = None
    if value < 0:
        body = formula.text
        m = re.match(r"\s*always\s*(\[[^\]]*\])?\s*(.*)$", body)
        inner = rho
        if m and not m.group(1):
            inner = robustness(Formula(m.group(2), formula.signals), signals, dt)
        negative = np.flatnonzero(inner < 0)
        first = int(negative[0]) if len(negative) else 0
    return Evaluation(value, value < 0, None if first is None else first * dt, first, rho)
