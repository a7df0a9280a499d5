"""CPU cost of one trajectory plot (figure + PNG), with its labels placed (not a timed test).

Runs a few shipped seeds once (a timeout that circles, a safety stop, a moving person, an
irregular workshop), then draws each one REPEATS times and prints the median CPU seconds per
plot (time.process_time: other jobs on a shared machine inflate it less than wall time). Run it
in two checkouts to compare versions; the episodes are simulated by the checkout that runs it.

    env -u PYTHONDONTWRITEBYTECODE python benchmarks/bench_plots.py [--repeats 5]
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.report.plots import png_bytes, trajectory_figure
from pytest_navscenario.scenario.loader import load_scenario

ROOT = Path(__file__).resolve().parent.parent
CASES = [("glass-door", "potential-field"), ("boxes2", "potential-field"), ("person-crossing", "dwa"),
         ("workshop-irregular", "dwa")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    results = [run_scenario(load_scenario(ROOT / "scenarios" / f"{seed}.yaml"), subject) for seed, subject in CASES]
    png_bytes(trajectory_figure(results[0]))     # matplotlib's own first-use cost, not counted
    print("| episode | outcome | CPU s per plot (median of %d) |" % args.repeats)
    print("|---|---|---|")
    every = []
    for (seed, subject), result in zip(CASES, results):
        times = []
        for _ in range(args.repeats):
            t0 = time.process_time()
            png_bytes(trajectory_figure(result))
            times.append(time.process_time() - t0)
        every += times
        print(f"| {seed}, {subject} | {result.outcome.value} | {statistics.median(times):.3f} |")
    print(f"| all | | {statistics.median(every):.3f} |")


if __name__ == "__main__":
    main()
