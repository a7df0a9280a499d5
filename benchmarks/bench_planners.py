"""Per-tick cost of the built-in planners on the five seeds (not a timed test).

For each seed x planner: one real episode records the observations the planner saw; then a
fresh planner (after reset) replays them REPEATS times. Prints the median (and best) cost of one
act() call in microseconds, the ticks of the episode, the median time of the whole episode
(run_scenario, MuJoCo and metrics included) and the planner's share of it, as a Markdown table.
Times are CPU time of this thread (time.thread_time) so that other jobs on a shared machine
inflate them less; --wall uses time.perf_counter instead.

    env -u PYTHONDONTWRITEBYTECODE python benchmarks/bench_planners.py [--repeats 30] [--wall]
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.subjects.loading import load_subject
from pytest_navscenario.harness.runner import run_scenario

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
    parser.add_argument("--wall", action="store_true", help="wall-clock instead of CPU time")
    args = parser.parse_args()
    clock = time.perf_counter if args.wall else time.thread_time
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
                t0 = clock()
                for obs in rec.observations:
                    planner.act(obs)
                per_tick.append((clock() - t0) / len(rec.observations))
            walls = []
            for _ in range(args.repeats):
                t0 = clock()
                run_scenario(scenario, factory)
                walls.append(clock() - t0)
            tick_us = statistics.median(per_tick) * 1e6
            wall_ms = statistics.median(walls) * 1e3
            share = tick_us * len(rec.observations) / 1e3 / wall_ms
            print(f"| {spec} | {name} | {first.outcome.value} | {len(rec.observations)} | "
                  f"{tick_us:.0f} ({min(per_tick) * 1e6:.0f}) | {wall_ms:.1f} | {share:.0%} |")


if __name__ == "__main__":
    main()
