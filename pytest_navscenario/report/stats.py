"""Small, dependency-free statistics for rates: Wilson score intervals (and paired tests)."""
from __future__ import annotations

import math

from ..core.rates import Z95, wilson_interval  # noqa: F401  (moved to core: the search uses it too)


def mcnemar_exact(b: int, c: int) -> float:
    """Exact two-sided McNemar p-value for paired pass/fail data.

    ``b`` and ``c`` are the discordant pair counts (e.g. A passed & B failed, A failed & B passed);
    concordant pairs carry no information about a difference. Under "no difference" b is
    Binomial(b + c, 1/2); the p-value is twice the smaller tail, capped at 1 (1.0 when b + c == 0).
    Computed with exact integers, so it is right for any count (no normal approximation).
    """
    if b < 0 or c < 0 or int(b) != b or int(c) != c:
        raise ValueError(f"discordant counts must be non-negative integers, got b={b}, c={c}")
    b, c = int(b), int(c)
    n = b + c
    if n == 0:
        return 1.0
    k = min(b, c)
    term = tail = 1  # C(n, 0); C(n, i+1) = C(n, i) * (n - i) / (i + 1), exact in integers
    for i in range(k):
        term = term * (n - i) // (i + 1)
        tail += term
    # int / int is correctly rounded in Python even for huge integers
    return min(1.0, (2 * tail) / (1 << n))


def rate_with_interval(successes: int, n: int) -> tuple[float, float, float]:
    """(rate, low, high) with the 95 % Wilson interval; rate is NaN when n == 0."""
    low, high = wilson_interval(successes, n)
    return (successes / n if n else float("nan")), low, high
