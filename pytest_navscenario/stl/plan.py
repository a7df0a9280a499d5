"""A formula tree -> its evaluation plan: nested closures of whole-array numpy operations.

``plan(root, dt)`` is built once per formula and sampling period (``Formula`` caches it): each
node's closure takes the signals (a dict of float64 arrays of one length) and returns the node's
value at every sample, so evaluating a formula is one call per operator, no dispatch on the tree
and no Python loop over samples. A term may return a float (a constant); a formula always
returns an array. Intervals become sample counts here, where ``dt`` is known.

Robustness of each operator (RTAMT's offline discrete-time semantics; windows.py for time):
``a <= b``, ``a < b``: ``b - a``; ``a >= b``, ``a > b``: ``a - b``; ``a == b``: ``-|a - b|``;
``a !== b``: ``|a - b|``; ``not``: negation; ``and``/``or``: min/max; ``implies``: ``max(-l, r)``;
``iff``: ``-|l - r|``; ``xor``: ``|l - r|``; ``next``/``prev``: the next/previous sample (+inf past
the end, -inf for the strong ``s_next``/``s_prev``); ``rise``: ``min(-prev, now)``; ``fall``:
``min(prev, -now)``.
"""
from __future__ import annotations

import numbers
from typing import Callable

import numpy as np

from . import windows
from .tree import COMPARISONS, Node, number
from .errors import StlEvaluationError

Signals = dict
Step = Callable[[Signals], "np.ndarray | float"]
INF = np.inf
_TOLERANCE = 1e-6          # an interval bound is a whole number of periods within this (in periods)


def samples(seconds: float, dt: float, node: Node, text: str) -> int:
    """``seconds`` as a whole number of sampling periods, or an error naming the interval."""
    k = seconds / dt
    whole = round(k)
    if abs(k - whole) > _TOLERANCE * max(1.0, abs(k)):
        low, high = int(np.floor(k)) * dt, int(np.ceil(k)) * dt
        raise StlEvaluationError(
            f"{text}: the interval bound {number(seconds)} s (column {node.column}) is not a whole "
            f"number of sampling periods of {number(dt)} s",
            f"write {number(round(low, 9))} or {number(round(high, 9))}, or sample at a period that divides it")
    return int(whole)


def plan(root: Node, dt: float, text: str = "") -> Step:
    """The closure that evaluates ``root`` on signals sampled every ``dt`` seconds."""
    return _build(root, dt, text)


def plan_for(formula, dt: float) -> Step:
    """The formula's evaluation plan at period ``dt``, built once and cached on the formula."""
    if isinstance(dt, bool) or not (isinstance(dt, numbers.Real) and dt > 0 and np.isfinite(dt)):
        raise StlEvaluationError(f"the sampling period must be a positive number of seconds, got {dt!r}",
                                 "pass the control tick, e.g. dt=0.1")
    step = formula._plans.get(dt)
    if step is None:
        step = formula._plans[dt] = plan(formula.root, float(dt), formula.text)
    return step


def _build(node: Node, dt: float, text: str) -> Step:
    op = node.op
    kids = [_build(arg, dt, text) for arg in node.args]
    if op == "var":
        name = node.name
        return lambda s: s[name]
    if op == "const":
        value = float(node.value)
        return lambda s: value
    if op in _ARITHMETIC:
        return _ARITHMETIC[op](*kids)
    if op in COMPARISONS:
        return _comparison(op, *kids)
    if op in _LOGIC:
        return _LOGIC[op](*kids)
    window = None if node.interval is None else (samples(node.interval[0], dt, node, text),
                                                 samples(node.interval[1], dt, node, text))
    return _TEMPORAL[op](window, *kids)


#: The key under which the signals dict carries the number of samples (not a signal name).
LENGTH = " n"


def _array(value, s: Signals) -> np.ndarray:
    """A comparison of constants only still has one value per sample."""
    if isinstance(value, np.ndarray):
        return value
    return np.full(s[LENGTH], float(value))


def _comparison(op: str, left: Step, right: Step) -> Step:
    if op in ("<", "<="):
        return lambda s: _array(np.subtract(right(s), left(s)), s)
    if op in (">", ">="):
        return lambda s: _array(np.subtract(left(s), right(s)), s)
    if op == "==":
        return lambda s: _array(-np.abs(np.subtract(left(s), right(s))), s)
    return lambda s: _array(np.abs(np.subtract(left(s), right(s))), s)


def _divide(left: Step, right: Step) -> Step:
    def step(s):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.divide(left(s), right(s))
    return step


def _sqrt(arg: Step) -> Step:
    def step(s):
        with np.errstate(invalid="ignore"):
            return np.sqrt(arg(s))
    return step


_ARITHMETIC = {
    "neg": lambda a: (lambda s: np.negative(a(s))),
    "+": lambda a, b: (lambda s: np.add(a(s), b(s))),
    "-": lambda a, b: (lambda s: np.subtract(a(s), b(s))),
    "*": lambda a, b: (lambda s: np.multiply(a(s), b(s))),
    "/": _divide,
    "abs": lambda a: (lambda s: np.abs(a(s))),
    "sqrt": _sqrt,
    "exp": lambda a: (lambda s: np.exp(a(s))),
    "pow": lambda a, b: (lambda s: np.power(a(s), b(s))),
}

def _difference(left: Step, right: Step, sign: float) -> Step:
    """``sign * |l - r|`` (iff: -1, xor: +1); NaN where both are the same infinity, as in RTAMT."""
    def step(s):
        with np.errstate(invalid="ignore"):
            return sign * np.abs(np.subtract(left(s), right(s)))
    return step


_LOGIC = {
    "not": lambda a: (lambda s: np.negative(a(s))),
    "and": lambda a, b: (lambda s: np.minimum(a(s), b(s))),
    "or": lambda a, b: (lambda s: np.maximum(a(s), b(s))),
    "implies": lambda a, b: (lambda s: np.maximum(np.negative(a(s)), b(s))),
    "iff": lambda a, b: _difference(a, b, -1.0),
    "xor": lambda a, b: _difference(a, b, 1.0),
}


def _shift(x: np.ndarray, by: int, fill: float) -> np.ndarray:
    """``x`` moved ``by`` samples earlier (by > 0: next) or later (by < 0: previous)."""
    out = np.empty_like(x)
    if by > 0:
        out[:-by] = x[by:]
        out[-by:] = fill
    else:
        out[-by:] = x[:by]
        out[:-by] = fill
    return out


def _always(w, a):
    if w is None:
        return lambda s: windows.suffix(a(s), np.minimum)
    return lambda s: windows.window(a(s), w[0], w[1], np.minimum, INF)


def _eventually(w, a):
    if w is None:
        return lambda s: windows.suffix(a(s), np.maximum)
    return lambda s: windows.window(a(s), w[0], w[1], np.maximum, -INF)


def _historically(w, a):
    if w is None:
        return lambda s: np.minimum.accumulate(a(s))
    return lambda s: windows.past_window(a(s), w[0], w[1], np.minimum, INF)


def _once(w, a):
    if w is None:
        return lambda s: np.maximum.accumulate(a(s))
    return lambda s: windows.past_window(a(s), w[0], w[1], np.maximum, -INF)


def _until(w, a, b):
    lo, hi = (0, None) if w is None else w
    return lambda s: windows.until(a(s), b(s), lo, hi)


def _since(w, a, b):
    lo, hi = (0, None) if w is None else w
    return lambda s: windows.since(a(s), b(s), lo, hi)


def _rise(w, a):
    def step(s):
        x = a(s)
        return np.minimum(np.negative(_shift(x, -1, -INF)), x)
    return step


def _fall(w, a):
    def step(s):
        x = a(s)
        return np.minimum(_shift(x, -1, INF), np.negative(x))
    return step


_TEMPORAL = {
    "always": _always, "eventually": _eventually, "historically": _historically, "once": _once,
    "until": _until, "since": _since, "rise": _rise, "fall": _fall,
    "next": lambda w, a: (lambda s: _shift(a(s), 1, INF)),
    "s_next": lambda w, a: (lambda s: _shift(a(s), 1, -INF)),
    "prev": lambda w, a: (lambda s: _shift(a(s), -1, INF)),
    "s_prev": lambda w, a: (lambda s: _shift(a(s), -1, -INF)),
}
