"""Rates from repeated runs, dependency-free: confidence intervals for a binomial proportion
(Wilson, Clopper-Pearson) and Wald's sequential probability ratio test, which decides between
two failure probabilities with as few runs as the evidence allows.

Used for how often a failure fails under the scenario's own randomness (search/holding.py) and
for rates of scenario families (report/stats.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

Z95 = 1.959963984540054  # two-sided 95 % normal quantile


def _check(successes: int, n: int) -> None:
    if n < 0 or not 0 <= successes <= n:
        raise ValueError(f"need 0 <= successes <= n, got successes={successes}, n={n}")


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval for a binomial proportion; (0, 1) when n == 0.

    Preferred over the normal (Wald) interval because it stays inside [0, 1] and is honest
    for the small counts and extreme rates a scenario family typically has.
    """
    _check(successes, n)
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    z2 = z * z
    denom = 1.0 + z2 / n
    centre = (p + z2 / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


def _binom_cdf(k: int, n: int, p: float) -> float:
    """P(X <= k) for X ~ Binomial(n, p), summed in log space (n up to thousands)."""
    if k < 0:
        return 0.0
    if k >= n:
        return 1.0
    if p <= 0.0:
        return 1.0
    if p >= 1.0:
        return 0.0
    lp, lq = math.log(p), math.log1p(-p)
    total = 0.0
    for i in range(k + 1):
        total += math.exp(math.lgamma(n + 1) - math.lgamma(i + 1) - math.lgamma(n - i + 1) + i * lp + (n - i) * lq)
    return min(1.0, total)


def _solve(f, target: float) -> float:
    """p in [0, 1] with f(p) = target for f decreasing in p (bisection to 1e-12)."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = (lo + hi) / 2
        if f(mid) > target:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def clopper_pearson(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """The exact (Clopper-Pearson) interval for a binomial proportion; (0, 1) when n == 0.

    It never covers less than ``confidence``, which matters at the few runs a confirmation uses
    (4 failures in 4 runs: 0.40 to 1 at 95 %, where Wilson's interval says 0.51 to 1)."""
    _check(successes, n)
    if n == 0:
        return 0.0, 1.0
    tail = (1.0 - confidence) / 2
    # lower: P(X >= k) = tail, i.e. P(X <= k - 1) = 1 - tail; upper: P(X <= k) = tail (both decrease in p)
    lower = 0.0 if successes == 0 else _solve(lambda p: _binom_cdf(successes - 1, n, p), 1.0 - tail)
    upper = 1.0 if successes == n else _solve(lambda p: _binom_cdf(successes, n, p), tail)
    return lower, upper


@dataclass(frozen=True)
class Sprt:
    """Wald's sequential probability ratio test of a Bernoulli probability: ``p1`` (accept: the
    probability is at least this) against ``p0`` (reject: at most this), with error rates
    ``alpha`` (accepting when it is ``p0``) and ``beta`` (rejecting when it is ``p1``). Each
    success adds log(p1 / p0) to the log-likelihood ratio, each miss log((1 - p1) / (1 - p0));
    the test accepts once the ratio reaches log((1 - beta) / alpha), rejects once it falls to
    log(beta / (1 - alpha)), and after ``max_runs`` decides by its sign (Wald's truncation)."""
    p0: float
    p1: float
    alpha: float = 0.1
    beta: float = 0.1
    max_runs: int = 20

    def __post_init__(self) -> None:
        if not 0.0 < self.p0 < self.p1 < 1.0:
            raise ValueError(f"need 0 < p0 < p1 < 1, got p0={self.p0}, p1={self.p1}")
        if not (0.0 < self.alpha < 0.5 and 0.0 < self.beta < 0.5):
            raise ValueError(f"error rates must be in (0, 0.5), got alpha={self.alpha}, beta={self.beta}")
        if self.max_runs < 1:
            raise ValueError(f"max_runs must be >= 1, got {self.max_runs}")

    @property
    def up(self) -> float:
        return math.log(self.p1 / self.p0)

    @property
    def down(self) -> float:
        return math.log((1.0 - self.p1) / (1.0 - self.p0))

    @property
    def accept_at(self) -> float:
        return math.log((1.0 - self.beta) / self.alpha)

    @property
    def reject_at(self) -> float:
        return math.log(self.beta / (1.0 - self.alpha))

    def llr(self, outcomes: "list[bool] | tuple[bool, ...]") -> float:
        """The log-likelihood ratio after ``outcomes``."""
        return sum(self.up if hit else self.down for hit in outcomes)

    def decide(self, outcomes: "list[bool] | tuple[bool, ...]") -> tuple[str, int]:
        """("accept" | "reject" | "continue", the runs the decision took) after ``outcomes`` (True:
        a success, here a failure of the planner), read in order up to the first crossing."""
        llr = 0.0
        for n, hit in enumerate(outcomes, start=1):
            llr += self.up if hit else self.down
            if llr >= self.accept_at - 1e-12:
                return "accept", n
            if llr <= self.reject_at + 1e-12:
                return "reject", n
            if n >= self.max_runs:
                return ("accept" if llr > 0 else "reject"), n
        return "continue", len(outcomes)

    def runs_to_decide(self, outcomes: "list[bool] | tuple[bool, ...]") -> int:
        """The fewest further runs that could end the test after ``outcomes`` (all successes or
        all misses from here): how many to ask for next."""
        llr = self.llr(outcomes)
        to_accept = math.ceil((self.accept_at - 1e-12 - llr) / self.up)
        to_reject = math.ceil((self.reject_at + 1e-12 - llr) / self.down)
        return max(1, min(to_accept, to_reject, self.max_runs - len(outcomes)))
