"""Per-tick cost of the built-in planners on the five seeds (not a timed test).

For each seed x planner: one real episode records the observations the planner saw; then a
fresh planner (after reset) replays them REPEATS times. Prints the median (and best) cost of one
act() call in microseconds, the ticks of the episode, the median wall time of the whole episode
(run_scenario, MuJoCo included) and the planner's share of it, as a Markdown table.

    python benchmarks/bench_planners.py [--repeats 30]
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from pytest_navscenario.loader import load_scenario
from pytest_navscenario.planner import load_subject
from pytest_navscenario.runner import run_scenario

SEEDS = ["boxes1", "boxes2", "corridor", "cylinders", "L-corridor"]
SUBJECTS = ["dwa", "potential-field"]
ROOT = Path(__file__).resolve().parent.parent


class Recorder:
    def __init__(self, inner):
        self.inner, self.observations = inner, []

    def reset(self, scenario):
        self.inner.reset(scenario)

    def act(self, obs):
        self.observations.append(obs)
        return self.inner.act(obs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=30)
    args = parser.parse_args()
    print("| planner | seed | outcome | ticks | act() median (best) us | episode median ms | planner share |")
    print("|---|---|---|---:|---:|---:|---:|")
    for spec in SUBJECTS:
        factory = load_subject(spec)
        for name in SEEDS:
            scenario = load_scenario(ROOT / "scenarios" / f"{name}.yaml")
            rec = Recorder(factory())
            first = run_scenario(scenario, rec)          # also warms caches (model, rollouts)
            per_tick = []
            for _ in range(args.repeats):
                planner = factory()
                planner.reset(scenario)
                t0 = time.perf_counter()
                for obs in rec.observations:
                    planner.act(obs)
                per_tick.append((time.perf_counter() - t0) / len(rec.observations))
            walls = [run_scenario(scenario, factory).wall_time for _ in range(args.repeats)]
            tick_us = statistics.median(per_tick) * 1e6
            wall_ms = statistics.median(walls) * 1e3
            share = tick_us * len(rec.observations) / 1e3 / wall_ms
            print(f"| {spec} | {name} | {first.outcome.value} | {len(rec.observations)} | "
                  f"{tick_us:.0f} ({min(per_tick) * 1e6:.0f}) | {wall_ms:.1f} | {share:.0%} |")


if __name__ == "__main__":
    main()
