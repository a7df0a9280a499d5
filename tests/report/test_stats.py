"""Statistics against published / reference values."""
import math

import pytest

from pytest_navscenario.report.stats import mcnemar_exact, rate_with_interval, wilson_interval

# Wilson score intervals (no continuity correction): Newcombe (1998), Stat. Med. 17:857, table I.
NEWCOMBE = [
    (81, 263, 0.2553, 0.3662),
    (15, 148, 0.0624, 0.1605),
    (0, 20, 0.0000, 0.1611),
    (1, 29, 0.0061, 0.1718),
]


@pytest.mark.parametrize("k, n, low, high", NEWCOMBE)
def test_wilson_matches_newcombe_table(k, n, low, high):
    lo, hi = wilson_interval(k, n)
    assert lo == pytest.approx(low, abs=5e-5)
    assert hi == pytest.approx(high, abs=5e-5)


def test_wilson_edges_and_symmetry():
    assert wilson_interval(0, 0) == (0.0, 1.0)
    lo, hi = wilson_interval(20, 20)
    assert hi == 1.0 and lo == pytest.approx(1 - 0.16112515805281935, abs=1e-12)
    with pytest.raises(ValueError, match="successes"):
        wilson_interval(5, 3)


# Exact McNemar = two-sided exact binomial test on the discordant pairs, p = 1/2.
# (1, 7) -> 0.070 is the worked example of Fagerland, Lydersen & Laake (2013), BMC Med Res
# Methodol 13:91; the other values are exact fractions or agree with scipy.stats.binomtest.
MCNEMAR = [
    (0, 0, 1.0),
    (3, 3, 1.0),
    (0, 1, 1.0),
    (0, 5, 0.0625),                 # 2 / 2**5
    (1, 7, 0.0703125),              # 2 * 9 / 2**8
    (1, 9, 0.021484375),            # 2 * 11 / 2**10
    (2, 12, 0.012939453125),
    (10, 25, 0.016673847800120715),
    (40, 60, 0.05688793364098089),
    (150, 120, 0.07738939898021849),
    (500, 560, 0.06990955946026937),
]


@pytest.mark.parametrize("b, c, p", MCNEMAR)
def test_mcnemar_exact_reference_table(b, c, p):
    assert mcnemar_exact(b, c) == pytest.approx(p, rel=1e-12)
    assert mcnemar_exact(c, b) == mcnemar_exact(b, c)


def test_mcnemar_huge_counts_do_not_underflow():
    p = mcnemar_exact(5000, 5400)
    assert 0 < p < 0.01
    assert mcnemar_exact(5000, 5000) == 1.0
    with pytest.raises(ValueError, match="non-negative"):
        mcnemar_exact(-1, 2)


def test_rate_with_interval():
    rate, lo, hi = rate_with_interval(15, 148)
    assert rate == pytest.approx(15 / 148) and lo < rate < hi
    assert math.isnan(rate_with_interval(0, 0)[0])
