"""A 50-corner polygon obstacle's cost per tick, against a box in the same place.

    python benchmarks/bench_polygon.py [--repeats 15]

The robot drives a fixed command (0.8 m/s along +x, safety layer on) past an obstacle 0.9 m beside
its line: a 1.6 x 1.6 m box, or a 50-corner star of the same extent (non-convex: 26 convex parts in
MuJoCo), so both episodes have the same ticks and the obstacle is within the safety layer's reach
for part of the drive. Pairs run in turn after a warm-up (model compiled and cached), CPU time of
this process; medians per tick and the median ratio of the pairs. Then the verdict's cost (oracle
and metrics: clearance and shortest path, cached paths cleared) per episode, and the model's
compile time once.
"""
from __future__ import annotations

import argparse
import math
import statistics
import time

from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.sim.episode import simulate
from pytest_navscenario.sim.world import clear_model_cache, compiled_world
from pytest_navscenario.verdict import metrics, paths

HEAD = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 10, y: 0}, timeout: 15}\nobstacles:\n"


def scenario(kind: str):
    if kind == "box":
        return loads_scenario(HEAD + "  - {type: box, name: o, x: 5, y: 1.95, length: 1.6, width: 1.6}\n")
    star = [[round((0.8 - 0.35 * (i % 2)) * math.cos(2 * math.pi * i / 50), 4),
             round((0.8 - 0.35 * (i % 2)) * math.sin(2 * math.pi * i / 50), 4)] for i in range(50)]
    return loads_scenario(HEAD + f"  - {{type: polygon, name: o, x: 5, y: 1.95, points: {star}}}\n")


class Fixed:
    def reset(self, scenario):
        pass

    def act(self, obs):
        return (0.8, 0.0, 0.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    box, star = scenario("box"), scenario("polygon")
    for sc in (box, star):
        clear_model_cache()
        t0 = time.process_time()
        compiled_world(sc)
        print(f"compile {sc.obstacles[0].kind}: {1e3 * (time.process_time() - t0):.1f} ms")

    def once(sc):
        t0 = time.process_time()
        res = simulate(sc, Fixed(), seed=0)
        t1 = time.process_time()
        paths.clear_caches()
        metrics.compute_metrics(sc, res.trajectory)
        return t1 - t0, time.process_time() - t1, res

    once(box), once(star)
    sim_a, sim_b, ver_a, ver_b, ratios, safety = [], [], [], [], [], []
    for _ in range(args.repeats):
        ta, va, ra = once(box)
        tb, vb, rb = once(star)
        assert ra.ticks == rb.ticks and ra.end == rb.end == "goal", (ra.end, rb.end)
        sim_a.append(ta / ra.ticks)
        sim_b.append(tb / rb.ticks)
        ver_a.append(va)
        ver_b.append(vb)
        ratios.append(tb / ta)
        safety.append((ra.timings["safety"] / ra.ticks, rb.timings["safety"] / rb.ticks))
    med = statistics.median
    print(f"ticks {ra.ticks}; per tick: box {1e6 * med(sim_a):.0f} us, 50-corner polygon "
          f"{1e6 * med(sim_b):.0f} us, ratio {med(ratios):.3f}")
    print(f"  of which the safety layer: box {1e6 * med(s[0] for s in safety):.1f} us, polygon "
          f"{1e6 * med(s[1] for s in safety):.1f} us")
    print(f"verdict per episode (uncached paths): box {1e3 * med(ver_a):.1f} ms, polygon {1e3 * med(ver_b):.1f} ms")


if __name__ == "__main__":
    main()
