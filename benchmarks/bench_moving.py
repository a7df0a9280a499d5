"""Moving obstacles' cost: the same scenario with 10 obstacles static and with all 10 moving.

    python benchmarks/bench_moving.py [--repeats 15] [--planner dwa]

Ten people-sized cylinders stand (static) or walk back and forth across a 12 m run (moving, away
from the robot's line so both episodes drive the same path for the same number of ticks). Each
pair of episodes runs in turn (static, moving, static, ...) after a warm-up, timed in CPU time of
this process (time.process_time: meaningful on a shared machine); the figures are the medians of
each and the median of the per-pair ratios moving / static. Besides the given planner, a
``replay`` planner that answers a fixed command shows the loop's own overhead (the worst case:
nothing else costs anything). The issue's bound: moving at most 1.3x static.
"""
from __future__ import annotations

import argparse
import statistics
import time

from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.sim.episode import simulate
from pytest_navscenario.subjects.loading import make_planner

HEAD = """\
version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 12, y: 0}, timeout: 30}
obstacles:
"""


def scenario(moving: bool):
    lines = []
    for k in range(10):
        x, y = 1.0 + 1.1 * k, (3.0 if k % 2 else -3.0)
        if moving:
            lines.append(f"  - {{type: person, name: p{k}, motion: {{path: [[{x}, {y}], [{x}, {y * 1.6}]], "
                         f"mode: back-and-forth, start: {0.1 * k}}}}}")
        else:
            lines.append(f"  - {{type: cylinder, name: p{k}, x: {x}, y: {y}, radius: 0.25, height: 1.7}}")
    return loads_scenario(HEAD + "\n".join(lines) + "\n")


class Fixed:
    """Drives straight at 0.8 m/s: the loop's cost alone."""

    def reset(self, scenario):
        pass

    def act(self, obs):
        return (0.8, 0.0, 0.0)


def run_pairs(static, moving, make, repeats: int) -> tuple[float, float, float, int]:
    def once(sc):
        planner = make()
        t0 = time.process_time()
        res = simulate(sc, planner, seed=0)
        return time.process_time() - t0, res

    once(static), once(moving)   # warm-up: models compiled and cached
    a, b, ratios = [], [], []
    for _ in range(repeats):
        ta, ra = once(static)
        tb, rb = once(moving)
        assert ra.ticks == rb.ticks, (ra.ticks, rb.ticks)   # the same episode length, or no comparison
        a.append(ta)
        b.append(tb)
        ratios.append(tb / ta)
    return statistics.median(a), statistics.median(b), statistics.median(ratios), ra.ticks


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--planner", default="dwa")
    args = ap.parse_args()
    static, moving = scenario(False), scenario(True)
    print(f"{'planner':<10} {'ticks':>6} {'static ms':>10} {'moving ms':>10} {'ratio':>7}")
    for name, make in ((args.planner, lambda: make_planner(args.planner)[0]), ("replay", Fixed)):
        sa, sb, ratio, ticks = run_pairs(static, moving, make, args.repeats)
        print(f"{name:<10} {ticks:>6} {sa * 1e3:>10.1f} {sb * 1e3:>10.1f} {ratio:>7.3f}")


if __name__ == "__main__":
    main()
