"""The 3D lidar's scan: CPU time of one 16 x 360 scan (CloudLidar.scan: ray casts, noise, points) in
worlds of growing difficulty, and the episode with and without a 3D lidar.

    python benchmarks/bench_lidar3d.py [--repeats 51]

Worlds (the sensor 0.5 m above the base, level, at the world's middle):
  ``flat``       a floor plane and 10 boxes (a warehouse aisle);
  ``primitives`` the same with a ramp, three steps and a platform built from boxes (terrain's way);
  ``rough``      the floor and a rough patch 10 x 8 m (amplitude 0.1 m, bumps every 0.8 m: 81 x 101
                 samples) under the sensor;
  ``field 256``  the floor and a 256 x 256-cell heightfield 20 x 20 m (0.3 m of relief) under it.
Times are time.process_time medians over ``--repeats`` scans after a warm-up scan (the grids
prepared); ``episode`` runs dwa on a flat corridor scenario with and without ``lidar3d`` (its
``timings["lidar3d"]`` per tick shown too).
"""
from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "sim"))

from pytest_navscenario.scenario.loader import loads_scenario       # noqa: E402
from pytest_navscenario.scenario.terrain import Lidar3D, Rough     # noqa: E402
from pytest_navscenario.sim.lidar3d import CloudLidar               # noqa: E402

from sensor_worlds import build, scenario                            # noqa: E402  (tests/sim)

BOXES = [(x, side * 2.0, 0.5, 0.5, 0.4, 0.5) for x in range(-4, 6, 2) for side in (-1, 1)]
TERRAIN = [(3.0, -4.0, 0.1, 0.3, 1.0, 0.1), (3.6, -4.0, 0.2, 0.3, 1.0, 0.2), (4.2, -4.0, 0.3, 0.3, 1.0, 0.3),
           (-3.0, 5.0, 0.6, 2.0, 1.5, 0.6)]


def time_scans(lidar: CloudLidar, repeats: int) -> float:
    pos, rot = np.zeros(3), np.eye(3)
    lidar.scan(0, pos, rot)
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        lidar.scan(0, pos, rot)
        times.append(time.process_time() - t0)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=51)
    args = ap.parse_args()
    spec = Lidar3D(rings=16, beams=360, mount_z=0.5)
    cases = []
    scn = scenario(lidar3d=spec)
    cases.append(("flat", scn, dict(boxes=BOXES)))
    cases.append(("primitives", scn, dict(boxes=BOXES + TERRAIN, ramp=(1.0, 3.0, 0.5, 1.5))))
    rough = Rough("yard", 0.0, 0.0, length=10.0, width=8.0, amplitude=0.1, wavelength=0.8, seed=1)
    cases.append(("rough", scenario(lidar3d=spec, terrain=[rough]), {}))
    field = Rough("field", 0.0, 0.0, length=20.0, width=20.0, amplitude=0.3, wavelength=20.0 / 256 * 8, seed=1)
    cases.append(("field 256", scenario(lidar3d=spec, terrain=[field]), {}))
    print(f"{'world':<12} {'scan ms':>8} {'points':>7}")
    for name, scn, geometry in cases:
        world, data = build(scn, **geometry)
        lidar = CloudLidar(scn, world, data, 1, seed=0)
        median = time_scans(lidar, args.repeats)
        points = len(lidar.scan(0, np.zeros(3), np.eye(3)))
        print(f"{name:<12} {median * 1e3:>8.2f} {points:>7}")
    episode(args.repeats)


def episode(repeats: int) -> None:
    from pytest_navscenario.sim.episode import simulate
    from pytest_navscenario.subjects.loading import make_planner

    s = loads_scenario("""
version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 12, y: 0}, timeout: 30}
obstacles:
  - {type: box, x: 6, y: 1.2, length: 10, width: 0.2}
  - {type: box, x: 6, y: -1.2, length: 10, width: 0.2}
  - {type: box, x: 4, y: 0.5, length: 0.4, width: 0.4}
""")
    with3d = replace(s, robot=replace(s.robot, lidar3d=Lidar3D()))
    for label, scn in (("episode, 2D lidar", s), ("episode, + 3D lidar", with3d)):
        runs = max(3, repeats // 10)
        times, per_tick = [], []
        simulate(scn, make_planner("dwa")[0], seed=0)
        for _ in range(runs):
            t0 = time.process_time()
            result = simulate(scn, make_planner("dwa")[0], seed=0)
            times.append(time.process_time() - t0)
            if "lidar3d" in result.timings:
                per_tick.append(result.timings["lidar3d"] / max(result.ticks, 1))
        extra = f", 3D lidar {statistics.median(per_tick) * 1e3:.2f} ms a tick" if per_tick else ""
        print(f"{label:<22} {statistics.median(times) * 1e3:8.1f} ms ({result.ticks} ticks, {result.end}{extra})")


if __name__ == "__main__":
    main()
