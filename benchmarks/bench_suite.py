"""Suite speed: ``pytest`` on 500 generated scenario files, serial vs ``-n 2`` (pytest-xdist).

    env -u PYTHONDONTWRITEBYTECODE python benchmarks/bench_suite.py [--count 500] [--repeats 3]

The scenarios are the five shipped seeds with their obstacles moved by up to +-0.3 m (fixed RNG,
so every run benchmarks the same files), 100 per seed in five family folders, run against the
default built-in planner. Prints per mode the median wall time of the whole ``pytest`` process,
the serial / -n 2 speed-up, and the plugin overhead per item: pytest's own session time minus
the sum of the episodes' ``run_scenario`` times (``wall_time`` in the results file), divided by
the item count, measured on the serial run (in -n 2 the episodes overlap). Plots of failing items
(a separate feature, ~0.1-1 s each) are off; artifacts too. Also checks that serial and -n 2
produce the same records (wall times aside).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SEEDS = ["boxes1", "boxes2", "corridor", "cylinders", "L-corridor"]


def generate(folder: Path, count: int, rng_seed: int = 1) -> int:
    import numpy as np

    from pytest_navscenario.errors import ScenarioError
    from pytest_navscenario.loader import dump_scenario, load_scenario, loads_scenario

    rng = np.random.default_rng(rng_seed)
    written = 0
    per_seed = -(-count // len(SEEDS))
    for seed_name in SEEDS:
        seed = load_scenario(ROOT / "scenarios" / f"{seed_name}.yaml")
        family = folder / seed_name
        family.mkdir(parents=True, exist_ok=True)
        i = 0
        while i < per_seed and written < count:
            obstacles = tuple(dataclasses.replace(o, x=o.x + float(rng.uniform(-0.3, 0.3)),
                                                  y=o.y + float(rng.uniform(-0.3, 0.3)))
                              for o in seed.obstacles)
            name = f"{seed_name}-{i:03d}"
            text = dump_scenario(dataclasses.replace(seed, obstacles=obstacles, name=name, family=seed_name))
            try:
                loads_scenario(text, source=name)  # e.g. an obstacle moved onto the start pose
            except ScenarioError:
                continue
            (family / f"{name}.yaml").write_text(text)
            i += 1
            written += 1
    return written


def run_pytest(folder: Path, extra: list[str], results: Path) -> tuple[float, float, str]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    cmd = [sys.executable, "-m", "pytest", str(folder), "-q", "-p", "no:cacheprovider",
           f"--nav-results={results}", "--nav-artifacts=none", "--nav-summary=no", "--nav-plots=none",
           *extra]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=folder, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    tail = proc.stdout.strip().splitlines()[-1] if proc.stdout.strip() else proc.stderr
    match = re.search(r" in ([0-9.]+)s", tail)
    if proc.returncode not in (0, 1) or not match:
        raise SystemExit(f"pytest failed ({proc.returncode}):\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")
    return wall, float(match.group(1)), tail


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=500)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="navbench-") as tmp:
        folder = Path(tmp) / "suite"
        n = generate(folder, args.count)
        # a project root of its own, so that only the generated files are collected
        (folder / "pytest.ini").write_text("[pytest]\n")
        print(f"{n} scenario files in {len(SEEDS)} families; {args.repeats} runs per mode; "
              f"{os.cpu_count()} CPUs")
        figures: dict[str, dict[str, list[float]]] = {}
        outcomes: dict[str, list[dict]] = {}
        for label, extra in [("serial", []), ("-n 2", ["-n", "2"])]:
            walls, sessions, overheads = [], [], []
            for r in range(args.repeats):
                results = Path(tmp) / f"r-{label.strip('- ').replace(' ', '')}-{r}.jsonl"
                wall, session, tail = run_pytest(folder, extra, results)
                records = [json.loads(line) for line in results.read_text().splitlines()]
                outcomes[f"{label}-{r}"] = [{k: v for k, v in rec.items() if k != "wall_time"} for rec in records]
                episodes = [rec["wall_time"] for rec in records]
                walls.append(wall)
                sessions.append(session)
                overheads.append((session - sum(episodes)) / len(episodes))
                print(f"  {label:6s} run {r + 1}: {wall:6.2f} s wall, pytest session {session:6.2f} s, "
                      f"sum of episodes {sum(episodes):6.2f} s  [{tail}]")
            figures[label] = {"wall": walls, "session": sessions, "overhead": overheads}
        runs = list(outcomes.values())
        mismatched = sum(1 for recs in runs[1:] for a, b in zip(runs[0], recs) if a != b)
        print(f"records identical across all runs and modes: {all(recs == runs[0] for recs in runs)} "
              f"({mismatched} differing records)")
        med = {k: statistics.median(v["wall"]) for k, v in figures.items()}
        print(f"median wall: serial {med['serial']:.2f} s, -n 2 {med['-n 2']:.2f} s, "
              f"speed-up {med['serial'] / med['-n 2']:.2f}x")
        print(f"plugin overhead per item (serial, session minus episodes): "
              f"{1000 * statistics.median(figures['serial']['overhead']):.2f} ms median")
    return 0


if __name__ == "__main__":
    sys.exit(main())
