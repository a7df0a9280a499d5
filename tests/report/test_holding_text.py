"""Issue 32 item 6: "the search measured 1.00 (1.00-1.00) over 1 run(s)" read as a 95 % interval
where one run of a scenario without randomness decided the failure."""
from __future__ import annotations

from pytest_navscenario.report.flaky import format_holding, holding_rows

KEY = ("scenarios/regressions/p/p-1.yaml", "p-1")
EXACT = {"confirmation": "exact", "hold_threshold": 0.9, "failure_probability": 1.0,
         "failure_probability_interval": [1.0, 1.0], "confirmation_runs": 1, "confirmation_failures": 1}
HELD = {"confirmation": "held", "hold_threshold": 0.9, "failure_probability": 1.0,
        "failure_probability_interval": [0.4, 1.0], "confirmation_runs": 4, "confirmation_failures": 4}


def records(n: int) -> list[dict]:
    return [{"path": KEY[0], "scenario": KEY[1], "outcome": "safety-stop", "repeat": i} for i in range(n)]


def test_a_failure_without_randomness_is_not_given_an_interval():
    text = format_holding(holding_rows(records(2), {KEY: EXACT}))
    assert ("the search found it fails every run (the scenario has no randomness: one run decides): holds"
            in text), text
    assert "(1.00-1.00)" not in text and "run(s)" not in text


def test_a_measured_rate_names_its_interval():
    text = format_holding(holding_rows(records(2), {KEY: HELD}))
    assert "the search measured a failure rate of 1.00 over 4 runs (95 % 0.40-1.00): holds" in text, text
