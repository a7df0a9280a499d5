"""ROS bag speed: importing the real TurtleBot3 bag into a seed, and writing an episode's bag in
each format compared with simulating that episode.

    python benchmarks/bench_bags.py [--repeats 7]

``from-bag``: scenario_from_bag on tests/data/fuse_turtlebot3.bag (1.3 MB ROS 1 bag, 91 s, 2741
odometry + 457 scans of 360 beams), budget 5 s. ``write``: write_episode_bag of the DWA episode
on each shipped seed scenario, per format, against run_scenario of the same episode (the ratio
is why ``--nav-bag`` is off by default). Medians over ``--repeats`` runs after one warm-up (rosbags
compiles its serialisers once per process). Times are CPU time of this process
(time.process_time), which stays meaningful on a machine shared with other jobs; wall-clock
medians are printed beside them.
"""
from __future__ import annotations

import argparse
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from pytest_navscenario.ros.bag_import import scenario_from_bag
from pytest_navscenario.ros.bag_writer import FORMATS, default_bag_path, write_episode_bag
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.harness.runner import run_scenario

ROOT = Path(__file__).resolve().parent.parent
TB3 = ROOT / "tests" / "data" / "fuse_turtlebot3.bag"


def timed(fn, repeats: int) -> tuple[float, float]:
    """(median CPU s, median wall s) of ``fn()`` over ``repeats`` runs, after a warm-up run."""
    fn()
    cpu, wall = [], []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        fn()
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    return statistics.median(cpu), statistics.median(wall)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()

    cpu, wall = timed(lambda: scenario_from_bag(TB3), args.repeats)
    seed = scenario_from_bag(TB3)
    print(f"from-bag {TB3.name} ({TB3.stat().st_size / 1e6:.1f} MB): {cpu:.2f} s CPU "
          f"({wall:.2f} s wall), median of {args.repeats}; {next(n for n in seed.notes if ' returns -> ' in n)}")

    tmp = Path(tempfile.mkdtemp(prefix="bench_bags."))
    try:
        print(f"\n{'scenario':<12} {'episode s':>9} {'run_scenario':>12} "
              + " ".join(f"{f + ' write':>13} {'ratio':>6}" for f in FORMATS))
        for path in sorted((ROOT / "scenarios").glob("*.yaml")):
            scenario = load_scenario(path)
            result = run_scenario(scenario, "dwa")
            sim_cpu, _ = timed(lambda: run_scenario(scenario, "dwa"), args.repeats)
            cells = []
            for fmt in FORMATS:
                target = default_bag_path(tmp, f"{path.stem}-{fmt}", fmt)
                w_cpu, _ = timed(lambda: write_episode_bag(result, target, fmt=fmt), args.repeats)
                cells.append(f"{w_cpu * 1e3:>10.0f} ms {w_cpu / sim_cpu:>5.1f}x")
            print(f"{path.stem:<12} {result.metrics.duration:>9.1f} {sim_cpu * 1e3:>9.0f} ms " + " ".join(cells))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
