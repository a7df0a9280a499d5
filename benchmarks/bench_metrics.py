"""Speed of the oracle's figures: compute_metrics per episode and the shortest-path check.

    env -u PYTHONDONTWRITEBYTECODE python benchmarks/bench_metrics.py [--repeats 200] [--json out.json]

Parts (medians over ``--repeats`` calls; wall time and this thread's CPU time, the latter
less disturbed by other processes on a shared machine):

1. compute_metrics on each shipped seed's real 10 s trajectory (dynamic-window planner),
   with the shortest path cached (the usual case: a scenario's repeats and the search's
   reruns) and uncached (a new layout: path planning included);
2. compute_metrics on a synthetic 10 s, 10-obstacle episode (1001 poses following the
   shortest path around ten random boxes), the issue's budget case (~1.5 ms);
3. paths.shortest_path / path_exists on new random 10-obstacle layouts (the search's
   validity check), and a cache hit;
4. shortest_path scaling with the number of boxes;
5. crowded worlds: BARN world 0 (209 cylinders, a real world by others: tests/data), its
   shortest path and evolve's passage_room at ROOM_LEVELS; a weaving layout of ``--weave`` boxes
   (a path that winds through every column), its shortest path and this process's peak memory.
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pytest_navscenario import load_scenario, run_scenario  # noqa: E402
from pytest_navscenario.verdict import paths  # noqa: E402
from pytest_navscenario.verdict.metrics import compute_metrics  # noqa: E402
from pytest_navscenario.sim.trajectory import Trajectory  # noqa: E402
from pytest_navscenario.scenario.model import BoxObstacle, Mission, Pose, Scenario  # noqa: E402


def timed(fn, repeats: int, before=None) -> dict[str, float]:
    """Median wall and CPU milliseconds of ``fn()`` (``before()`` runs untimed each time)."""
    wall, cpu = [], []
    for _ in range(repeats):
        if before:
            before()
        w0, c0 = time.perf_counter(), time.thread_time()
        fn()
        cpu.append(time.thread_time() - c0)
        wall.append(time.perf_counter() - w0)
    return {"wall_ms": statistics.median(wall) * 1e3, "cpu_ms": statistics.median(cpu) * 1e3}


def random_layout(seed: int, k: int = 10) -> Scenario:
    rng = np.random.default_rng(seed)
    obstacles = tuple(BoxObstacle(f"b{i}", rng.uniform(-3, 3), rng.uniform(1.5, 8.5), rng.uniform(0.3, 1.5),
                                  rng.uniform(0.3, 1.5), rng.uniform(0, 180)) for i in range(k))
    return Scenario(mission=Mission(start=Pose(0, 0, 90), goal=Pose(0, 10, 90)), obstacles=obstacles)


def follow(points: np.ndarray, speed: float = 1.0, dt: float = 0.01) -> Trajectory:
    seg = np.hypot(*np.diff(points, axis=0).T)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    t = np.arange(int(cum[-1] / (speed * dt)) + 1) * dt
    x, y = np.interp(t * speed, cum, points[:, 0]), np.interp(t * speed, cum, points[:, 1])
    yaw = np.unwrap(np.arctan2(np.gradient(y), np.gradient(x)))
    vel = np.column_stack([np.full_like(t, speed), np.zeros_like(t), np.gradient(yaw, dt)])
    ticks = t[::10]
    return Trajectory(t=t, pose=np.column_stack([x, y, yaw]), velocity=vel, tick_t=ticks,
                      command=np.zeros((len(ticks), 3)), ranges=np.zeros((len(ticks), 72), np.float32),
                      angles=np.linspace(-np.pi, np.pi, 72, endpoint=False))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=200)
    ap.add_argument("--json", type=Path, help="also write the figures here")
    ap.add_argument("--weave", type=int, default=250, help="part 5: boxes in the weaving layout")
    args = ap.parse_args()
    n = args.repeats
    out: dict[str, object] = {"repeats": n}

    print("1. compute_metrics on the seeds' real trajectories (dwa)")
    seeds = {}
    for path in sorted((ROOT / "scenarios").glob("*.yaml")):
        s = load_scenario(path)
        tr = run_scenario(s, "dwa").trajectory
        cached = timed(lambda: compute_metrics(s, tr), n)
        uncached = timed(lambda: compute_metrics(s, tr), max(n // 4, 5), before=paths.clear_caches)
        seeds[s.name] = {"poses": len(tr.t), "obstacles": len(s.obstacles), "cached": cached, "uncached": uncached}
        print(f"   {s.name:12s} {len(tr.t):5d} poses {len(s.obstacles):2d} obstacles  cached "
              f"{cached['wall_ms']:.2f} ms (cpu {cached['cpu_ms']:.2f})  uncached {uncached['wall_ms']:.2f} ms "
              f"(cpu {uncached['cpu_ms']:.2f})")
    out["seeds"] = seeds

    print("2. compute_metrics, synthetic 10 s episode among 10 boxes")
    s = random_layout(1)
    tr = follow(np.asarray(paths.shortest_path(s).points))
    cached = timed(lambda: compute_metrics(s, tr), n)
    uncached = timed(lambda: compute_metrics(s, tr), max(n // 4, 5), before=paths.clear_caches)
    out["synthetic_10_boxes"] = {"poses": len(tr.t), "cached": cached, "uncached": uncached}
    print(f"   {len(tr.t)} poses: cached {cached['wall_ms']:.2f} ms (cpu {cached['cpu_ms']:.2f}), "
          f"uncached {uncached['wall_ms']:.2f} ms (cpu {uncached['cpu_ms']:.2f})")

    print("3. shortest_path on new 10-box layouts (the search's validity check)")
    layouts = [random_layout(seed) for seed in range(100)]
    wall, cpu = [], []
    for layout in layouts:
        paths.clear_caches()
        w0, c0 = time.perf_counter(), time.thread_time()
        paths.path_exists(layout)
        cpu.append(time.thread_time() - c0)
        wall.append(time.perf_counter() - w0)
    hit = timed(lambda: paths.path_exists(layouts[0]), n)
    out["shortest_path_10_boxes"] = {"wall_ms": statistics.median(wall) * 1e3, "cpu_ms": statistics.median(cpu) * 1e3,
                                     "p90_wall_ms": float(np.percentile(wall, 90) * 1e3), "cache_hit": hit}
    print(f"   uncached median {statistics.median(wall) * 1e3:.2f} ms (cpu {statistics.median(cpu) * 1e3:.2f}), "
          f"p90 {np.percentile(wall, 90) * 1e3:.2f} ms; cache hit {hit['wall_ms'] * 1e3:.1f} us")
    print("4. shortest_path scaling: k boxes on a 30 x 30 m map, corner to corner (median of 3 layouts)")
    scaling = {}
    for k in (10, 20, 50, 100):
        cpu = []
        for seed in range(3):
            rng = np.random.default_rng(1000 * k + seed)
            obstacles = tuple(BoxObstacle(f"b{i}", rng.uniform(-15, 15), rng.uniform(1, 29), rng.uniform(0.3, 1.5),
                                          rng.uniform(0.3, 1.5), rng.uniform(0, 180)) for i in range(k))
            big = Scenario(mission=Mission(start=Pose(-16, 0, 90), goal=Pose(16, 30, 90)), obstacles=obstacles)
            paths.clear_caches()
            c0 = time.thread_time()
            paths.shortest_path(big)
            cpu.append(time.thread_time() - c0)
        scaling[k] = statistics.median(cpu) * 1e3
        print(f"   {k:3d} boxes: {scaling[k]:.1f} ms cpu")
    out["shortest_path_scaling_cpu_ms"] = scaling
    out["crowded"] = crowded(args.weave)
    if args.json:
        args.json.write_text(json.dumps(out, indent=2))


def crowded(weave: int) -> dict[str, float]:
    """Part 5: path searches in crowded worlds (CPU ms, each on a cleared cache)."""
    import math
    import resource

    from pytest_navscenario.ros.world_import import sdf_obstacles
    from pytest_navscenario.scenario.model import Footprint, Robot
    from pytest_navscenario.search.strategies.evolve import ROOM_LEVELS

    print("5. crowded worlds")
    world = sdf_obstacles(ROOT / "tests" / "data" / "barn_world_0.world").obstacles
    barn = Scenario(mission=Mission(start=Pose(-2.25, 3, 90), goal=Pose(-2.25, 13, 90)), obstacles=tuple(world),
                    robot=Robot(footprint=Footprint(length=0.5, width=0.43)))
    out = {"barn_shortest_path_cpu_ms": timed(lambda: paths.shortest_path(barn), 5, before=paths.clear_caches)["cpu_ms"],
           "barn_passage_room_cpu_ms": timed(lambda: paths.passage_room(barn, ROOM_LEVELS), 5,
                                             before=paths.clear_caches)["cpu_ms"]}
    print(f"   BARN world 0 ({len(world)} cylinders): shortest path {out['barn_shortest_path_cpu_ms']:.1f} ms cpu, "
          f"passage_room {out['barn_passage_room_cpu_ms']:.1f} ms cpu")
    side = int(math.ceil(math.sqrt(weave)))
    boxes = tuple(BoxObstacle(f"b{i}", (i % side) * 1.2 + 0.3, (i // side) * 1.2 + (0.3 if (i % side) % 2 else 0.6),
                              0.5, 0.5) for i in range(weave))
    woven = Scenario(mission=Mission(start=Pose(-2, -2, 0), goal=Pose(side * 1.2 + 1, side * 1.2 + 1, 0)),
                     obstacles=boxes)
    paths.clear_caches()
    c0 = time.thread_time()
    sp = paths.shortest_path(woven)
    out["weave_boxes"] = weave
    out["weave_shortest_path_cpu_ms"] = (time.thread_time() - c0) * 1e3
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"   weaving layout of {weave} boxes: shortest path {out['weave_shortest_path_cpu_ms']:.0f} ms cpu "
          f"({'none' if sp is None else f'{sp.length:.2f} m'}); this process's peak memory {out['peak_mb']:.0f} MB")
    return out


if __name__ == "__main__":
    main()
