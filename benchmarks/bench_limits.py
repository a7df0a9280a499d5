"""The cost of the verdict at each documented terrain limit (issue 38, part 1): each case runs in a
fresh process (its own caches, its own peak memory), loads its scenario from a file and computes
what a pytest item computes beyond the episode: the terrain barriers, the shortest path and the
feasibility check (which asks the barriers again with a more capable body). Printed: the median
wall time of ``--repeat`` runs and the largest peak RSS.

    python benchmarks/bench_limits.py [--repeat 3] [--only NAME]

Cases (the limit each one reaches):
  huge-platform   one platform of 999999 x 999999 m (|value| <= 1e6)
  platforms-5000  5000 platforms of 0.5 m in a weaving field (5000 terrain elements)
  barriers-400    100 platforms in a weaving field: 400 barriers, the most the path search plans among
  rough-50        50 rough patches of 1023 x 1023 samples (gentle: every grid is searched)
  heightfields-64 64 heightfields of 1024 x 1024 (MAX_GRID_SAMPLES, all grids together)
  npy-header      the 14-byte malformed .npy header (refused: loader error)
"""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEAD = ("version: 1\nmission: {{start: {{x: {sx}, y: {sy}}}, goal: {{x: {gx}, y: {gy}}}, timeout: 5000}}\n"
        "robot: {{drive: diff, body: {{type: legged, max_step: 0.2, max_slope: 30, max_gap: 0.3}}}}\nterrain:\n")


def weaving(n: int) -> str:
    side = int(math.ceil(math.sqrt(n)))
    pos = [((i % side) * 1.2 + 0.3, (i // side) * 1.2 + (0.3 if (i % side) % 2 else 0.6)) for i in range(n)]
    return HEAD.format(sx=-2, sy=-2, gx=side * 1.2 + 1, gy=side * 1.2 + 1) + "\n".join(
        f"  - {{type: platform, x: {x:.2f}, y: {y:.2f}, length: 0.5, width: 0.5, height: 0.3}}" for x, y in pos)


def write_case(name: str, folder: Path) -> Path:
    path = folder / f"{name}.yaml"
    if name == "huge-platform":
        text = HEAD.format(sx=0, sy=0, gx=5, gy=0) + \
            "  - {type: platform, x: 0, y: 0, length: 999999, width: 999999, height: 0.5}"
    elif name == "platforms-5000":
        text = weaving(5000)
    elif name == "barriers-400":
        text = weaving(100)
    elif name == "rough-50":
        text = HEAD.format(sx=-5, sy=-30, gx=1000, gy=-30) + "\n".join(
            f"  - {{type: rough, x: {20 * i}, y: 0, length: 19, width: 19, amplitude: 0.01, "
            f"wavelength: {19 * 8 / 1022:.6f}, seed: {i}}}" for i in range(50))
    elif name == "heightfields-64":
        import numpy as np
        rng = np.random.default_rng(0)
        for i in range(64):
            np.save(folder / f"h{i}.npy", rng.random((1024, 1024)) * 0.01)
        text = HEAD.format(sx=-5, sy=-30, gx=1300, gy=-30) + "\n".join(
            f"  - {{type: heightfield, x: {20 * i}, y: 0, file: h{i}.npy, length: 19, width: 19, max_height: 0.01}}"
            for i in range(64))
    elif name == "npy-header":
        (folder / "bad.npy").write_bytes(b"\x93NUMPY\x01\x00\x06\x00{'a':\n")
        text = HEAD.format(sx=0, sy=0, gx=5, gy=0) + \
            "  - {type: heightfield, x: 3, y: 5, file: bad.npy, length: 2, width: 2, max_height: 0.1}"
    else:
        raise SystemExit(f"unknown case {name}")
    path.write_text(text + "\n")
    return path


def child(path: str) -> None:
    """Load, barriers, shortest path, feasibility; print one JSON line."""
    import warnings
    warnings.simplefilter("ignore")
    from pytest_navscenario import ScenarioError, load_scenario
    from pytest_navscenario.verdict.feasibility import impassable_reason
    from pytest_navscenario.verdict.paths import shortest_path
    from pytest_navscenario.scenario.ground.traversable import barriers

    t0 = time.perf_counter()
    try:
        s = load_scenario(path)
    except ScenarioError as exc:
        out = {"refused": str(exc).splitlines()[0][:100]}
    else:
        t1 = time.perf_counter()
        n = len(barriers(s))
        t2 = time.perf_counter()
        sp = shortest_path(s)
        reason = impassable_reason(s)
        out = {"load": t1 - t0, "barriers": t2 - t1, "n_barriers": n, "path+feasibility": time.perf_counter() - t2,
               "path": None if sp is None else round(sp.length, 2), "impassable": reason is not None}
    out["total"] = time.perf_counter() - t0
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps(out))


CASES = ["huge-platform", "platforms-5000", "barriers-400", "rough-50", "heightfields-64", "npy-header"]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--only", default=None)
    p.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.child:
        return child(args.child)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    print(f"load: {os.getloadavg()[0]:.1f} (1 min), {os.cpu_count()} cores")
    print(f"{'case':16s} {'median s':>9s} {'runs':>24s} {'peak MB':>8s}  details")
    with tempfile.TemporaryDirectory() as tmp:
        for name in [args.only] if args.only else CASES:
            path = write_case(name, Path(tmp))
            runs = []
            for _ in range(args.repeat):
                done = subprocess.run([sys.executable, __file__, "--child", str(path)], env=env, capture_output=True,
                                      text=True, timeout=900)
                runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
            totals = [r["total"] for r in runs]
            detail = {k: (round(v, 2) if isinstance(v, float) else v) for k, v in runs[-1].items()
                      if k not in ("total", "peak_mb")}
            print(f"{name:16s} {statistics.median(totals):9.2f} {' '.join(f'{t:.2f}' for t in totals):>24s} "
                  f"{max(r['peak_mb'] for r in runs):8.0f}  {detail}", flush=True)


if __name__ == "__main__":
    main()
