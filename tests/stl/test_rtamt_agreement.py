"""Robustness agrees with RTAMT's offline discrete-time evaluator (the reference implementation)
on random formulas and traces: every operator, bounded and unbounded, windows past the end of
short traces, with and without parentheses. Derandomized: the same examples on every run.

The default run checks 2 x 150 pairs; the heavy run (CI) 2 x 600 = 1200.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from pytest_navscenario.stl import parse, robustness

from rtamt_reference import rtamt_module, rtamt_robustness
from stl_strategies import cases


def _settings(examples: int):
    return settings(max_examples=examples, derandomize=True, deadline=None, database=None,
                    suppress_health_check=list(HealthCheck))


def _agrees(case) -> None:
    text, signals, dt = case
    ours = robustness(parse(text), signals, dt)
    reference = np.asarray(rtamt_robustness(text, signals, dt))
    assert ours.dtype == np.float64 and ours.shape == reference.shape
    np.testing.assert_allclose(ours, reference, rtol=1e-12, atol=1e-12,
                               err_msg=f"{text} (read as {parse(text).text}), dt={dt}, {signals}")


@pytest.fixture(autouse=True)
def _needs_rtamt():
    rtamt_module()


@_settings(150)
@given(cases(bare=False))
def test_parenthesised_formulas_agree_with_rtamt(case):
    _agrees(case)


@_settings(150)
@given(cases(bare=True))
def test_formulas_with_parentheses_left_out_agree_with_rtamt(case):
    _agrees(case)


@pytest.mark.heavy
@_settings(600)
@given(cases(bare=False))
def test_600_more_parenthesised_formulas_agree_with_rtamt(case):
    _agrees(case)


@pytest.mark.heavy
@_settings(600)
@given(cases(bare=True))
def test_600_more_formulas_with_parentheses_left_out_agree_with_rtamt(case):
    _agrees(case)
