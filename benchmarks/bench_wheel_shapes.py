"""What wheels as spheres or capsules would give: the terrain seeds ridden by the wheeled body with its
wheels as cylinders (as built), spheres or capsules of the same radius, against the same episodes
flat and planar; per-tick CPU ratios as bench_terrain.py, and the trajectories side by side.

    python benchmarks/bench_wheel_shapes.py [--repeats 7] [--planner dwa] [--picture out.png]

Each shape runs in a process of its own (the compiled worlds are cached per process): the wheel
geoms of ``sim/bodies/wheeled.py`` are changed in the MjSpec after the body is built (a sphere of
the wheel's radius; a capsule of that radius whose straight part is the wheel's width, along the
axle), nothing else. A and B alternate (flat planar, then the seed as written), each timed with
time.process_time after a warm-up; printed: the median per-tick ratio B / A, the riding tick's
MuJoCo stepping alone (this thread's CPU time inside mj_step, mj_step1 and mj_step2, us a tick, in
rounds of their own in this process, the shapes alternating, the least of ``--repeats``), the episode's end and its terrain event or collision, and how far the
trajectory is from the cylinders' (largest distance between the paths at equal times). The picture:
one panel per seed, the paths of the three shapes over the terrain's outline.
"""
from __future__ import annotations

import argparse
import glob
import json
import math
import os
import statistics
import subprocess
import sys
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SHAPES = ("cylinder", "sphere", "capsule")


_SHAPE = ["cylinder"]        # the shape the patched build gives the wheels


def _patch(shape: str) -> None:
    """Make the wheeled body's wheels ``shape`` (in the spec, after the body builds them)."""
    import mujoco

    from pytest_navscenario.sim.bodies import wheeled

    _SHAPE[0] = shape
    if getattr(wheeled.WheeledModel.build, "shaped", False):
        return
    build = wheeled.WheeledModel.build

    def shaped(self, spec):
        build(self, spec)
        width = float(self.spec_body.wheel_width)
        for geom in spec.geoms:
            if geom.name.startswith("wheel") and _SHAPE[0] != "cylinder":
                r = float(geom.size[0])
                if _SHAPE[0] == "sphere":
                    geom.type = mujoco.mjtGeom.mjGEOM_SPHERE
                    geom.size = [r, 0.0, 0.0]
                else:
                    geom.type = mujoco.mjtGeom.mjGEOM_CAPSULE
                    geom.size = [r, width / 2.0, 0.0]

    shaped.shaped = True
    wheeled.WheeledModel.build = shaped


def run_shape(shape: str, repeats: int, planner: str, paths: list[str]) -> dict:
    """The seeds' figures and riding trajectories with the wheels as ``shape``."""
    _patch(shape)
    sys.path.insert(0, os.path.join(ROOT, "benchmarks"))
    from bench_terrain import flat

    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.sim.episode import simulate
    from pytest_navscenario.subjects.loading import make_planner

    out = {}
    for path in paths:
        sc = load_scenario(path)
        if not sc.terrain:
            continue
        a, b = flat(sc), sc

        def once(s):
            t0 = time.process_time()
            res = simulate(s, make_planner(planner)[0], seed=0)
            return time.process_time() - t0, res

        once(a), once(b)
        ratios = []
        for _ in range(repeats):
            ca, ra = once(a)
            cb, rb = once(b)
            ratios.append((cb / max(rb.ticks, 1)) / (ca / max(ra.ticks, 1)))
        traj = rb.trajectory
        out[os.path.basename(path)] = dict(
            ratio=statistics.median(ratios),
            ticks=rb.ticks, end=rb.end, message=str(rb.terrain_event or rb.collision or "")[:140],
            t=traj.t.tolist(), x=traj.pose[:, 0].tolist(), y=traj.pose[:, 1].tolist(),
            z=[float(v) for v in (traj.z if traj.z is not None else [])])
    return out


def physics_cpu(paths: list[str], repeats: int, planner: str) -> dict:
    """MuJoCo's stepping alone in each seed's riding episode with each wheel shape: this thread's
    CPU time inside mj_step, mj_step1 and mj_step2, us per tick, the least of ``repeats`` rounds
    (the shapes alternate within a round, each world compiled afresh: the compile is outside the
    steps)."""
    import mujoco

    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.sim import world as planar
    from pytest_navscenario.sim.episode import simulate
    from pytest_navscenario.subjects.loading import make_planner

    names = ("mj_step", "mj_step1", "mj_step2")
    plain = {n: getattr(mujoco, n) for n in names}
    spent = [0]

    def timed(f):
        def call(*args):
            t0 = time.thread_time_ns()
            f(*args)
            spent[0] += time.thread_time_ns() - t0
        return call

    out: dict = {}
    try:
        for n in names:
            setattr(mujoco, n, timed(plain[n]))
        for path in paths:
            sc = load_scenario(path)
            if not sc.terrain:
                continue
            best = out.setdefault(os.path.basename(path), {})
            for _ in range(repeats):
                for shape in SHAPES:
                    _patch(shape)
                    planar._CACHE.clear()
                    spent[0] = 0
                    res = simulate(sc, make_planner(planner)[0], seed=0)
                    us = spent[0] / 1e3 / max(res.ticks, 1)
                    best[shape] = min(best.get(shape, math.inf), us)
    finally:
        for n in names:
            setattr(mujoco, n, plain[n])
        _patch("cylinder")
    return out


def picture(results: dict, path: str) -> None:
    """One panel per seed: the three shapes' paths (x, y) and their heights over time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    seeds = list(results["cylinder"])
    fig, axes = plt.subplots(2, len(seeds), figsize=(4.2 * len(seeds), 6.4), squeeze=False)
    colours = dict(cylinder="black", sphere="tab:red", capsule="tab:blue")
    styles = dict(cylinder="-", sphere="--", capsule=":")
    for k, seed in enumerate(seeds):
        top, bottom = axes[0][k], axes[1][k]
        for shape in SHAPES:
            r = results[shape][seed]
            label = f"{shape}: {r['end']} ({r['ticks']} ticks)"
            top.plot(r["x"], r["y"], styles[shape], color=colours[shape], lw=1.4, label=label)
            if r["z"]:
                bottom.plot(r["t"], r["z"], styles[shape], color=colours[shape], lw=1.2)
        top.set_title(seed.replace(".yaml", ""))
        top.set_aspect("equal", adjustable="datalim")
        top.legend(fontsize=7, loc="best")
        top.set_xlabel("x (m)")
        top.set_ylabel("y (m)")
        bottom.set_xlabel("t (s)")
        bottom.set_ylabel("base height z (m)")
    fig.suptitle("wheeled body, dwa: wheels as cylinders (as built), spheres, capsules")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def _gap(a: dict, b: dict) -> float:
    n = min(len(a["x"]), len(b["x"]))
    return max((math.hypot(a["x"][i] - b["x"][i], a["y"][i] - b["y"][i]) for i in range(n)), default=0.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--planner", default="dwa")
    ap.add_argument("--picture", default=None, help="write the trajectories' picture here (PNG)")
    ap.add_argument("--shape", default=None, help=argparse.SUPPRESS)      # the child process
    ap.add_argument("--scenarios", nargs="*", default=None)
    args = ap.parse_args()
    paths = args.scenarios or sorted(glob.glob(os.path.join(ROOT, "scenarios", "*.yaml")))
    if args.shape:
        print(json.dumps(run_shape(args.shape, args.repeats, args.planner, paths)))
        return
    print(os.getloadavg())
    results = {}
    for shape in SHAPES:
        cmd = [sys.executable, __file__, "--shape", shape, "--repeats", str(args.repeats),
               "--planner", args.planner, "--scenarios", *paths]
        results[shape] = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
    steps = physics_cpu(paths, args.repeats, args.planner)
    print(f"{'seed':<20} {'shape':<9} {'B/A per tick':>12} {'MuJoCo us/tick':>15} {'end':<10} {'ticks':>5} "
          f"{'max gap to cylinder m':>21}  message")
    for seed in results["cylinder"]:
        for shape in SHAPES:
            r = results[shape][seed]
            print(f"{seed[:20]:<20} {shape:<9} {r['ratio']:>12.2f} {steps[seed][shape]:>15.0f} {r['end']:<10} "
                  f"{r['ticks']:>5} {_gap(r, results['cylinder'][seed]):>21.3f}  {r['message']}")
    print(os.getloadavg())
    if args.picture:
        picture(results, args.picture)


if __name__ == "__main__":
    main()
