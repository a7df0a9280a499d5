"""Robustness and the verdict: the end of a trace as RTAMT reads it (design notes §7), the
first violation, long traces against a direct reading of the definitions, and errors."""
from __future__ import annotations

import numpy as np
import pytest

from pytest_navscenario.stl import StlEvaluationError, evaluate, parse, robustness

DT = 0.1


def test_a_window_at_the_end_reads_what_is_left_of_the_trace():
    # 10 samples, always over the next second (11 samples): the last samples read what is left
    d = np.full(10, 1.0)
    assert list(robustness("always[0:1](d >= 0.5)", {"d": d}, DT)) == [0.5] * 10
    d[2] = 0.2
    assert list(robustness("always[0:1](d >= 0.5)", {"d": d}, DT)) == [-0.3] * 3 + [0.5] * 7


def test_eventually_with_nothing_left_that_satisfies_it_is_violated_at_the_end():
    d = np.full(10, 1.0)
    d[3] = 0.2
    rho = robustness("eventually[0:0.3](d <= 0.5)", {"d": d}, DT)
    assert np.allclose(rho, [0.3] * 4 + [-0.5] * 6)


def test_a_deadline_past_the_end_of_an_episode_that_ended_early_fails():
    # "reach the dock within 60 s": the episode ended after 10 s without reaching it
    d_dock = np.linspace(5.0, 1.0, 100)
    ev = evaluate("eventually[0:60](d_dock <= 0.3)", {"d_dock": d_dock}, DT)
    assert ev.violated and ev.robustness == pytest.approx(-0.7)
    assert ev.first_violation_index == 99 and ev.first_violation_time == pytest.approx(9.9)
    # reached at the last sample: it holds
    d_dock[-1] = 0.1
    assert not evaluate("eventually[0:60](d_dock <= 0.3)", {"d_dock": d_dock}, DT).violated


def test_windows_entirely_past_the_end_hold_for_always_and_fail_for_eventually():
    x = {"x": [1.0, -1.0, 1.0]}
    assert list(robustness("always[0.5:1](x > 0)", x, DT)) == [np.inf] * 3
    assert list(robustness("eventually[0.5:1](x > 0)", x, DT)) == [-np.inf] * 3
    assert list(robustness("(x > 0) until[0.5:1] (x > 0)", x, DT)) == [-np.inf] * 3
    assert list(robustness("historically[0.5:1](x > 0)", x, DT)) == [np.inf] * 3
    assert list(robustness("once[0.5:1](x > 0)", x, DT)) == [-np.inf] * 3


def test_one_sample_traces_evaluate():
    x = {"x": [2.0]}
    for text, value in [("always(x > 1)", 1.0), ("eventually[0:5](x > 1)", 1.0), ("next(x > 1)", np.inf),
                        ("s_next(x > 1)", -np.inf), ("(x > 3) until (x > 1)", 1.0), ("rise(x > 1)", 1.0)]:
        assert robustness(text, x, DT).tolist() == [value], text


def test_intervals_are_seconds_at_the_callers_sampling_period():
    x = np.ones(40)
    x[20] = -1.0          # 2 s at dt = 0.1, 1 s at dt = 0.05
    assert robustness("eventually[0:1.5](x < 0)", {"x": x}, 0.1)[0] < 0
    assert robustness("eventually[0:1.5](x < 0)", {"x": x}, 0.05)[0] > 0
    assert robustness("eventually[0:1500ms](x < 0)", {"x": x}, 0.05)[0] > 0


def _brute(op, x, y, a, b):
    """The definitions, sample by sample (RTAMT's offline reading)."""
    n = len(x)
    out = np.empty(n)
    for i in range(n):
        hi = n - 1 if b is None else min(i + b, n - 1)
        if op == "always":
            out[i] = min(x[i + a:hi + 1], default=np.inf)
        elif op == "eventually":
            out[i] = max(x[i + a:hi + 1], default=-np.inf)
        else:
            out[i] = max((min(y[m], min(x[i:m], default=np.inf)) for m in range(i + a, hi + 1)),
                         default=-np.inf)
    return out


@pytest.mark.parametrize("a, b", [(0, None), (0, 0), (0, 3), (2, 9), (0, 40), (5, 120), (0, 299), (7, 2000)])
@pytest.mark.parametrize("op", ["always", "eventually", "until"])
def test_long_traces_match_the_definitions(op, a, b):
    rng = np.random.default_rng(a * 1000 + (b or 0))
    x, y = rng.normal(size=300), rng.normal(size=300) - 0.5
    when = "" if b is None else f"[{a}:{b}]"
    text = f"(x > 0) until{when} (y > 0)" if op == "until" else f"{op}{when}(x > 0)"
    if op == "until" and b is None and a:
        pytest.skip("an unbounded until has no begin")
    got = robustness(text, {"x": x, "y": y}, 1.0)
    assert np.array_equal(got, _brute(op, x, y, a, b))


@pytest.mark.parametrize("text, signals, index", [
    # always: the first sample of its body's violation
    ("always ((d < 1.5) implies (v <= 0.3))", {"d": [3, 2, 1.2, 1.0, 0.7], "v": [0.5, 0.5, 0.35, 0.2, 0.1]}, 2),
    # looking into the body: where x drops, not 5 samples before
    ("always (always[0:0.5] (x > 0))", {"x": [1, 1, 1, 1, 1, 1, 1, 1, -1, 1]}, 8),
    # eventually: the end of its window (the deadline that passed)
    ("eventually[0:0.3] (x > 0)", {"x": [-1] * 10}, 3),
    ("eventually (x > 0)", {"x": [-1] * 10}, 9),
    # and: the earliest violated part; or: the latest
    ("always (x > 0) and always (y > 0)", {"x": [1, 1, 1, -1, 1], "y": [1, -1, 1, 1, 1]}, 1),
    ("always (x > 0) or always (y > 0)", {"x": [1, 1, 1, -1, 1], "y": [1, -1, 1, 1, 1]}, 3),
    # not eventually = always not
    ("not eventually (x > 2)", {"x": [1, 1, 3, 1]}, 2),
    # until: where its left side broke before the right side held
    ("(x > 0) until[0:1] (y > 0)", {"x": [1, 1, 1, -1, 1], "y": [-1] * 5}, 3),
])
def test_the_first_violation_is_where_the_violation_shows(text, signals, index):
    ev = evaluate(text, signals, DT)
    assert ev.violated and ev.robustness < 0 and ev.robustness == ev.rho[0]
    assert ev.first_violation_index == index
    assert ev.first_violation_time == pytest.approx(index * DT)


def test_a_formula_that_holds_has_no_first_violation():
    ev = evaluate(parse("always (x > 0)"), {"x": [1.0, 2.0]}, DT)
    assert not ev.violated and ev.robustness == 1.0
    assert ev.first_violation_time is None and ev.first_violation_index is None


@pytest.mark.parametrize("text, signals, dt, message, fix", [
    ("always (x > 0)", {"y": [1.0]}, DT, "no signal 'x' (signals given: y)", "declare 'x'"),
    ("always (x > y)", {"x": [1.0, 2.0], "y": [1.0]}, DT, "has 1 samples, the others 2", "same ticks"),
    ("always (x > 0)", {"x": []}, DT, "no samples", None),
    ("always (x > 0)", {"x": [[1.0]]}, DT, "shape (1, 1)", "1-D"),
    ("always[0:0.25] (x > 0)", {"x": [1.0]}, DT, "0.25 s (column 1) is not a whole number of sampling "
                                                 "periods of 0.1 s", "write 0.2 or 0.3"),
    ("always (x > 0)", {"x": [1.0]}, 0.0, "positive number of seconds", "dt="),
    ("always (x > 0)", {"x": [1.0, float("nan")]}, DT, "signal 'x' is NaN at sample 1 (of 2)", "value at every sample"),
])
def test_evaluation_errors_say_what_and_how_to_fix_it(text, signals, dt, message, fix):
    with pytest.raises(StlEvaluationError) as info:
        robustness(text, signals, dt)
    assert message in info.value.message
    if fix:
        assert fix in info.value.hint


def test_robustness_is_float64_whatever_the_inputs():
    rho = robustness("always (x > 0)", {"x": [1, 2, 3]}, 1)
    assert rho.dtype == np.float64 and rho.tolist() == [1.0, 2.0, 3.0]
    assert robustness("1 < 2", {"x": [0, 0]}, 1).tolist() == [1.0, 1.0]


def test_a_formula_checks_its_intervals_against_a_period_before_any_trace():
    f = parse("always[0:0.25] (x > 0) and eventually[0:1] (x > 1)")
    f.check_period(0.05)
    with pytest.raises(StlEvaluationError, match="0.25 s .column 1. is not a whole number"):
        f.check_period(0.1)


def test_an_undefined_verdict_is_an_error_not_a_pass():
    # 0/0 is NaN; NaN < 0 is false, so it would read as kept
    with pytest.raises(StlEvaluationError, match="undefined .NaN.") as info:
        evaluate("x / x > 0", {"x": [0.0, 1.0]}, DT)
    assert "0/0" in info.value.hint
    assert np.isnan(robustness("x / x > 0", {"x": [0.0, 1.0]}, DT)[0])
