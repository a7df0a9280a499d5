"""Hypothesis strategies of random formulas (as text) and traces, for the agreement with RTAMT.

The formulas use every operator both evaluators have, bounded and unbounded, with intervals up
to past the end of short traces (the end-of-trace semantics), written either fully parenthesised
or with parentheses left out at random (so that the precedence is compared too). A trace is drawn
as its length, its kind and a seed (numpy makes the values): drawing each value through
Hypothesis costs ten times the evaluation, and the formula is what needs shrinking.
"""
from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from pytest_navscenario.stl.tree import number

SIGNALS = ("a", "b", "c")
PERIODS = (1.0, 0.1, 0.25, 0.05)
UNARY = ("not", "always", "eventually", "historically", "once", "G", "F", "H", "O",
         "next", "prev", "s_next", "s_prev", "rise", "fall")
TIMED = ("always", "eventually", "historically", "once", "G", "F", "H", "O")
BINARY = ("and", "or", "implies", "iff", "xor", "until", "since", "U", "S")

constants = st.integers(-8, 8).map(lambda k: number(k / 4))
variables = st.sampled_from(SIGNALS)


@st.composite
def predicates(draw):
    x, y = draw(variables), draw(variables)
    term = draw(st.sampled_from([x, f"{x} + {y}", f"{x} - {y}", f"{x} * {draw(constants)}",
                                 f"abs({x} - {y})", f"{x} / 2"]))
    op = draw(st.sampled_from(["<", "<=", ">", ">=", "==", "!=="]))
    return f"{term} {op} {draw(st.one_of(constants, variables))}"


def interval(draw, dt: float) -> str:
    """``""`` (unbounded, one time in three) or ``[a:b]`` in seconds, whole periods."""
    if draw(st.integers(0, 2)) == 0:
        return ""
    a = draw(st.integers(0, 6))
    b = a + draw(st.integers(0, 9))
    return f"[{number(round(a * dt, 9))}:{number(round(b * dt, 9))}]"


@st.composite
def formulas(draw, dt: float, bare: bool, depth: int = 3):
    """A formula text of up to ``depth`` nested operators; ``bare``: parentheses left out where
    a drawn boolean says so (both evaluators must then group it alike)."""
    if depth == 0 or draw(st.integers(0, 4)) == 0:
        return draw(predicates())

    def operand():
        text = draw(formulas(dt, bare, depth - 1))
        return text if bare and draw(st.booleans()) else f"({text})"

    if draw(st.booleans()):
        op = draw(st.sampled_from(UNARY))
        if op in ("rise", "fall"):
            return f"{op}({draw(formulas(dt, bare, depth - 1))})"
        when = interval(draw, dt) if op in TIMED else ""
        return f"{op}{when} {operand()}"
    op = draw(st.sampled_from(BINARY))
    when = interval(draw, dt) if op in ("until", "since", "U", "S") else ""
    return f"{operand()} {op}{when} {operand()}"


@st.composite
def traces(draw, n: int) -> dict:
    """Signals a, b, c of ``n`` samples: quarter steps (many ties) or any reals in [-5, 5]."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    if draw(st.booleans()):
        return {name: list(rng.integers(-8, 9, n) / 4) for name in SIGNALS}
    return {name: list(rng.uniform(-5, 5, n)) for name in SIGNALS}


@st.composite
def cases(draw, bare: bool = False):
    """(formula text, signals, dt): a trace of 2-24 samples (RTAMT fails on one sample)."""
    dt = draw(st.sampled_from(PERIODS))
    text = draw(formulas(dt, bare))
    n = draw(st.integers(2, 24))
    return text, draw(traces(n)), dt
