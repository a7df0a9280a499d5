"""Riding the ground vs the planar body: CPU time of one episode on a terrain seed with its body
(wheeled, legged ...) against the same episode flat (terrain removed, the planar body), paired.

    python benchmarks/bench_terrain.py [--repeats 15] [--planner dwa] [--scenarios scenarios/*.yaml]

For each scenario with terrain: A = the flat episode (no terrain, planar body), B = the scenario as
written; A and B alternate (A B A B ...), each timed with time.process_time (CPU time of this
process, meaningful on a shared machine), after a warm-up of each (models compiled and cached, as
in a suite or a search). Two planners: ``--planner`` (the episodes may differ in length: compare
the per-tick figures) and ``fixed`` (drives straight at 0.8 m/s for ``--ticks`` ticks in both: the
same number of ticks, the loop's cost alone). Printed: ticks of each, median ms per episode, median
us per tick, and the median of the per-pair ratios B / A per tick. The issue's target: B / A <= 3
for the wheeled body without a 3D lidar.
"""
from __future__ import annotations

import argparse
import glob
import os
import statistics
import time
from dataclasses import replace

from pytest_navscenario.scenario.loader import load_scenario, loads_scenario
from pytest_navscenario.scenario.bodies import PlanarBody
from pytest_navscenario.sim.episode import simulate
from pytest_navscenario.subjects.loading import make_planner

ROOT = os.path.join(os.path.dirname(__file__), "..")
INLINE = """version: 1
name: ramp-between-levels (inline)
robot: {drive: diff, body: {type: wheeled}, lidar: {mount_height: 0.5}}
mission: {start: {x: 0, y: 0}, goal: {x: 14, y: 0}, timeout: 40}
terrain:
  - {type: ramp, name: ramp, x: 6.0, y: 0, length: 6.0, width: 3.0, rise: 0.5}
  - {type: platform, name: upper, x: 13.0, y: 0, length: 8.0, width: 6.0, height: 0.5}
obstacles:
  - {type: box, name: crate, x: 2.5, y: 1.5, length: 0.8, width: 0.8}
"""


class Fixed:
    """Drives straight at 0.8 m/s: the loop's cost alone."""

    def reset(self, scenario):
        pass

    def act(self, obs):
        return (0.8, 0.0, 0.0)


def flat(scenario):
    """The same episode on a flat floor with today's planar body."""
    return replace(scenario, terrain=(), robot=replace(scenario.robot, body=PlanarBody()))


def pairs(a, b, make, repeats: int, max_ticks: int | None):
    def once(sc):
        planner = make()
        t0 = time.process_time()
        res = simulate(sc, planner, seed=0, max_ticks=max_ticks)
        return time.process_time() - t0, res.ticks

    once(a), once(b)
    ta, tb, ratios = [], [], []
    for _ in range(repeats):
        ca, na = once(a)
        cb, nb = once(b)
        ta.append((ca, na))
        tb.append((cb, nb))
        ratios.append((cb / max(nb, 1)) / (ca / max(na, 1)))
    med = lambda xs: statistics.median(c for c, _ in xs)                    # noqa: E731
    per = lambda xs: statistics.median(c / max(n, 1) for c, n in xs)       # noqa: E731
    return ta[-1][1], tb[-1][1], med(ta), med(tb), per(ta), per(tb), statistics.median(ratios)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--planner", default="dwa")
    ap.add_argument("--ticks", type=int, default=150, help="ticks of the fixed planner's episodes")
    ap.add_argument("--scenarios", nargs="*", default=None)
    args = ap.parse_args()
    paths = args.scenarios if args.scenarios is not None else sorted(glob.glob(os.path.join(ROOT, "scenarios", "*.yaml")))
    seeds = [s for s in (load_scenario(p) for p in paths) if s.terrain] or [loads_scenario(INLINE)]
    print(os.getloadavg())
    print(f"{'scenario':<28} {'body':<8} {'planner':<7} {'ticks A/B':>10} {'A ms':>7} {'B ms':>7} "
          f"{'A us/tick':>9} {'B us/tick':>9} {'B/A per tick':>12}")
    for sc in seeds:
        for name, make, ticks in ((args.planner, lambda: make_planner(args.planner)[0], None),
                                  ("fixed", Fixed, args.ticks)):
            na, nb, ma, mb, pa, pb, ratio = pairs(flat(sc), sc, make, args.repeats, ticks)
            print(f"{sc.name[:28]:<28} {sc.robot.body.kind:<8} {name:<7} {f'{na}/{nb}':>10} {ma * 1e3:>7.1f} "
                  f"{mb * 1e3:>7.1f} {pa * 1e6:>9.0f} {pb * 1e6:>9.0f} {ratio:>12.2f}")


if __name__ == "__main__":
    main()
