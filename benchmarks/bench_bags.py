"""ROS bag speed: importing the real TurtleBot3 bag into a seed, and writing an episode's bag in
each format compared with simulating that episode.

    python benchmarks/bench_bags.py [--repeats 7]
    python benchmarks/bench_bags.py --against OTHER_CHECKOUT [--pairs 9]

``from-bag``: scenario_from_bag on tests/data/fuse_turtlebot3.bag (1.3 MB ROS 1 bag, 91 s, 2741
odometry + 457 scans of 360 beams), budget 5 s. ``write``: write_episode_bag of the DWA episode
on each shipped seed scenario, per format, against run_scenario of the same episode (the ratio
is why ``--nav-bag`` is off by default). Medians over ``--repeats`` runs after one warm-up (rosbags
compiles its serialisers once per process). Times are CPU time of this process
(time.process_time), which stays meaningful on a machine shared with other jobs; wall-clock
medians are printed beside them.

``--against OTHER_CHECKOUT``: the whole command ``navscenario from-bag`` on the TurtleBot3 bag (what
a user waits for: Python's start-up, the imports, the bag's reading and the seed), this checkout
(A) and the other (B) alternately, A B A B, each in a fresh process; the CPU time of each (user +
system, from the operating system's accounting of the finished child), the ratio A/B pair by pair
and the median of the ratios. The issue-24 target: at most 1.5x the time before it.
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


def _child_cpu(cmd: list[str], env: dict[str, str]) -> float:
    """User + system CPU seconds of one finished child process running ``cmd``."""
    import resource
    import subprocess

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    # run in the checkout: `python -c` puts the working folder first on the path
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   cwd=env["PYTHONPATH"])
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def paired(other: Path, pairs: int) -> None:
    """This checkout against ``other``, A B A B, on the whole from-bag command (see the docstring)."""
    import os
    import sys

    out = Path(tempfile.mkdtemp(prefix="bench_bags_pair."))
    envs = []
    for root in (ROOT, other.resolve()):
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env["PYTHONPATH"] = str(root)
        envs.append(env)
    cmd = [sys.executable, "-c", "import sys; from pytest_navscenario.cli import main; sys.exit(main(sys.argv[1:]))",
           "from-bag", str(TB3), "-o", str(out / "tb3.yaml"), "--force", "--no-plot"]
    try:
        for env in envs:          # a warm-up each: bytecode written, the bag in the page cache
            _child_cpu(cmd, env)
        a, b = [], []
        for _ in range(pairs):
            a.append(_child_cpu(cmd, envs[0]))
            b.append(_child_cpu(cmd, envs[1]))
    finally:
        shutil.rmtree(out, ignore_errors=True)
    ratios = [x / y for x, y in zip(a, b)]
    print(f"from-bag {TB3.name}, whole command, CPU s: A (this checkout) median {statistics.median(a):.3f} "
          f"[{min(a):.3f}..{max(a):.3f}], B ({other}) median {statistics.median(b):.3f} [{min(b):.3f}..{max(b):.3f}]; "
          f"A/B per pair {', '.join(f'{r:.2f}' for r in ratios)}; median {statistics.median(ratios):.2f}x "
          f"({pairs} pairs)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--against", type=Path, default=None, metavar="OTHER_CHECKOUT",
                    help="time the whole from-bag command here and in that checkout, alternately")
    ap.add_argument("--pairs", type=int, default=9)
    args = ap.parse_args()
    if args.against is not None:
        paired(args.against, args.pairs)
        return

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
