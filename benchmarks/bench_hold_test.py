"""How the search's confirmation test (search/holding.py) behaves at each threshold (issue 29):
no simulation, only the sequential test itself, run on Bernoulli draws.

    python benchmarks/bench_hold_test.py                       # thresholds 0.8, 0.9, 0.95, 0.99
    python benchmarks/bench_hold_test.py --holds 0.9 --trials 100000

For each threshold: the test's hypotheses (p1 = the threshold, p0 = the probability whose odds are
9 times smaller), the runs it takes to confirm a layout that fails every time and to reject one
that passes every time, and for layouts that fail with probability p: how often it accepts them
and how many runs it takes on average (its operating characteristic and average sample number).
With the share of accepted layouts by p, the share of frozen failures that fail in at least 4 of
5 fresh runs follows for any mix of layouts the search meets.
"""
from __future__ import annotations

import argparse
import random
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

PS = (0.1, 0.3, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 1.0)


def four_of_five(p: float) -> float:
    """P(at least 4 failures in 5 runs) for a layout that fails with probability p."""
    return p ** 5 + 5 * p ** 4 * (1 - p)


def main() -> None:
    from pytest_navscenario.search.holding import hold_test

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--holds", default="0.8,0.9,0.95,0.99")
    ap.add_argument("--trials", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    rnd = random.Random(a.seed)
    for hold in (float(h) for h in a.holds.split(",")):
        test = hold_test(hold)
        always = test.decide([True] * test.max_runs)[1]
        never = test.decide([False] * test.max_runs)[1]
        print(f"hold {hold:g}: p1 {test.p1:g} against p0 {test.p0:.3f} (alpha {test.alpha}, beta {test.beta}, at most "
              f"{test.max_runs} runs); a layout that always fails is confirmed after {always} runs, one that "
              f"never fails rejected after {never}")
        print(f"  {'p':>5} {'accepted':>9} {'mean runs':>9} {'4 of 5 fresh':>12}")
        for p in PS:
            accepted, runs = 0, []
            for _ in range(a.trials):
                outcomes: list[bool] = []
                while True:
                    outcomes.append(rnd.random() < p)
                    verdict, n = test.decide(outcomes)
                    if verdict != "continue":
                        break
                accepted += verdict == "accept"
                runs.append(n)
            print(f"  {p:>5.2f} {accepted / a.trials:>9.3f} {statistics.mean(runs):>9.2f} {four_of_five(p):>12.3f}")


if __name__ == "__main__":
    main()
