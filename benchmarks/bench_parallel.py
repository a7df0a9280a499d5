"""One search on every core, and on Ray: serial vs ``-n 2`` vs ``--nav-ray``, against the capacity
of the machine at the same moment.

    env -u PYTHONDONTWRITEBYTECODE python benchmarks/bench_parallel.py search [--budget 200]
        [--subject dwa] [--seed-name boxes1] [--repeats 3] [--ray] [--shrink-budget 25%]
        [--exec-budget 16] [--exec-tick 0.05] [--exec-repeats 1]
    env -u PYTHONDONTWRITEBYTECODE python benchmarks/bench_parallel.py busy [--budget 200] [--workers 2]
    env -u PYTHONDONTWRITEBYTECODE python benchmarks/bench_parallel.py overhead [--jobs 200]

``search``: the same search (seed scenario, budget, search seed 0) run serially, with ``-n 2``
(each generation on two local worker processes) and, with ``--ray``, with ``--nav-ray=auto -n 2``
(a local Ray instance with two CPUs; its start-up counts). For each mode: median wall time of the
whole pytest process (CPU time cannot be summed: the workers are not its children), and the
speed-up over serial next to the parallel capacity measured right before each round (two
CPU-bound processes against one after the other: 2.0 on two idle cores). Then the same for an
``exec:`` planner that answers every tick after ``--exec-tick`` s (a real stack's latency; budget
``--exec-budget``, shrinking off; ``--exec-budget 0`` skips it). Also checks that the frozen files
and the search log (wall times aside) are the same in every mode, and ends with one table row
per planner: the share of the capacity is issue 14's figure (target: 90 %).

``busy``: CPU-side evidence that does not depend on the machine's load: one search with
shrinking, in this process, its candidates and shrinks on local worker processes, each job timed
in its worker. Prints this process's CPU time (drawing candidates, bookkeeping), the workers' CPU
time, and how much of the time each worker had a job (the rest it waited for work: the
generation barrier, the drawing, the start and the end); also the per-generation figures.

``overhead``: the cost a worker adds per episode: the same batch of short episodes run in this
process, on two local worker processes and as Ray tasks (1 CPU, then 2), with the per-task
overhead of each (wall time minus the episodes' own time, per episode) and the payload of one
result as it travels back (pickled bytes, compact and with its trajectory).
"""
from __future__ import annotations

import argparse
import json
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_suite import parallel_capacity  # noqa: E402

SLOW_EXEC = r'''#!/usr/bin/env python3
"""An external planner that takes TICK seconds per tick (a real stack's latency): drives straight
at the goal, slowing near obstacles the lidar sees."""
import json, math, sys, time
TICK = float(sys.argv[1])
for line in sys.stdin:
    msg = json.loads(line)
    if msg["type"] == "reset":
        print(json.dumps({"type": "ready", "name": "slow-exec"}), flush=True)
    elif msg["type"] == "observation":
        time.sleep(TICK)
        x, y, yaw = msg["pose"]
        gx, gy = msg["waypoints"][0] if msg["waypoints"] else msg["goal"][:2]
        dx, dy = gx - x, gy - y
        d = math.hypot(dx, dy) or 1.0
        near = min(msg["ranges"]) if msg["ranges"] else 10.0
        v = min(1.0, d, max(0.2, near - 0.5))
        c, s = math.cos(yaw), math.sin(yaw)
        print(json.dumps({"type": "command", "vx": v * (c * dx + s * dy) / d,
                          "vy": v * (-s * dx + c * dy) / d, "wz": 0.0}), flush=True)
    elif msg["type"] == "shutdown":
        break
'''


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_search(folder: Path, subject: str, budget: int, seed_name: str, extra: list[str], out: str,
               shrink: str | int | None = None) -> tuple[float, float, str]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--nav-subject={subject}",
           "--navsearch", seed_name, "--budget", str(budget), "--navsearch-out", out, *extra]
    if shrink is not None:
        cmd.append(f"--navsearch-shrink-budget={shrink}")
    cpu0, t0 = _children_cpu(), time.perf_counter()
    proc = subprocess.run(cmd, cwd=folder, env=env, capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t0, _children_cpu() - cpu0
    if proc.returncode != 0:
        raise SystemExit(f"pytest failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-2000:]}")
    summary = next((line for line in proc.stdout.splitlines() if " vs " in line and " sims" in line), "")
    return wall, cpu, summary


def files_of(folder: Path) -> dict[str, object]:
    """Frozen files (provenance time masked) and the log (wall times dropped), for comparison."""
    out: dict[str, object] = {}
    for path in sorted(folder.rglob("*")):
        if not path.is_file():
            continue
        text = path.read_text()
        if path.name.endswith(".jsonl"):
            rows = [json.loads(line) for line in text.splitlines()]
            for row in rows:
                row.pop("wall_time", None)
            out[path.relative_to(folder).as_posix()] = rows
        else:
            out[path.relative_to(folder).as_posix()] = re.sub(r"'?\d{4}-\d\d-\d\dT[0-9:.+]+'?", "<t>", text)
    return out


def compare(folder: Path, subject: str, budget: int, shrink: str | int | None, repeats: int, ray: bool,
            seed_name: str) -> dict[str, object]:
    """Serial vs -n 2 (vs Ray) for one search, ``repeats`` rounds, capacity measured before each."""
    med = statistics.median
    modes = [("serial", []), ("-n 2", ["-n", "2"])]
    if ray:
        modes.append(("ray -n 2", ["--nav-ray=auto", "-n", "2"]))
    print(f"search {seed_name}, budget {budget}, shrink budget {'default' if shrink is None else shrink}, "
          f"subject {subject}; {os.cpu_count()} CPUs; load average {os.getloadavg()[0]:.2f}")
    walls: dict[str, list[float]] = {m: [] for m, _ in modes}
    caps, loads = [], [os.getloadavg()[0]]
    results: dict[str, object] = {}
    summary = ""
    for r in range(repeats):
        caps.append(parallel_capacity())
        for label, extra in modes:
            out = f"out-{abs(hash(subject)) % 10000}-{label.replace(' ', '')}-{r}"
            wall, _, summary = run_search(folder, subject, budget, seed_name, extra, out, shrink)
            walls[label].append(wall)
            results[f"{label}/{r}"] = files_of(folder / out)
            print(f"  run {r + 1} {label:9s}: {wall:7.2f} s wall  [{summary.strip()[:150]}]")
        loads.append(os.getloadavg()[0])
    first = next(iter(results.values()))
    identical = all(v == first for v in results.values())
    cap = med(caps)
    print(f"frozen files and logs identical in every mode and run: {identical}")
    print(f"parallel capacity (median of {len(caps)}, measured before each round): {cap:.2f}x "
          f"({', '.join(f'{c:.2f}' for c in caps)}); load average {min(loads):.1f}-{max(loads):.1f}")
    row: dict[str, object] = {"subject": subject, "budget": budget, "capacity": cap, "identical": identical,
                              "load": (min(loads), max(loads)), "serial": med(walls["serial"]),
                              "summary": summary.strip()}
    for label, _ in modes[1:]:
        speedup = med(walls["serial"]) / med(walls[label])
        row[label] = (med(walls[label]), speedup, speedup / cap)
        print(f"{label}: median {med(walls[label]):.2f} s vs serial {med(walls['serial']):.2f} s: "
              f"{speedup:.2f}x = {100 * speedup / cap:.0f} % of the capacity")
    return row


def search(args: argparse.Namespace) -> int:
    rows = []
    with tempfile.TemporaryDirectory(prefix="navpar-") as tmp:
        folder = Path(tmp)
        shutil.copytree(ROOT / "scenarios", folder / "scenarios", ignore=shutil.ignore_patterns("regressions"))
        (folder / "pytest.ini").write_text("[pytest]\nnav_scenario_paths = scenarios\n")
        rows.append(compare(folder, args.subject, args.budget, args.shrink_budget, args.repeats, args.ray,
                            args.seed_name))
        if args.exec_budget > 0:
            program = folder / "slow_exec.py"
            program.write_text(SLOW_EXEC)
            program.chmod(0o755)
            subject = f"exec:{sys.executable} {program} {args.exec_tick}"
            rows.append(compare(folder, subject, args.exec_budget, 0, args.exec_repeats, False, args.seed_name))
    print("\n| search | capacity (load) | serial | `-n 2` | speed-up | share of the capacity | identical |")
    print("|---|---:|---:|---:|---:|---:|---|")
    for row in rows:
        wall, speedup, share = row["-n 2"]   # type: ignore[misc]
        name = row["subject"] if not str(row["subject"]).startswith("exec:") else f"exec: {args.exec_tick * 1000:.0f} ms per tick"
        lo, hi = row["load"]   # type: ignore[misc]
        print(f"| {name}, budget {row['budget']} | {row['capacity']:.2f}x ({lo:.1f}-{hi:.1f}) | {row['serial']:.2f} s "
              f"| {wall:.2f} s | {speedup:.2f}x | **{100 * share:.0f} %** | {row['identical']} |")
        if "ray -n 2" in row:
            rwall, rspeed, rshare = row["ray -n 2"]   # type: ignore[misc]
            print(f"|   `--nav-ray=auto -n 2` | | | {rwall:.2f} s | {rspeed:.2f}x | {100 * rshare:.0f} % | |")
    return 0


# -- busy: CPU-side evidence ----------------------------------------------------------------------
class Timed:
    """A job wrapper that times its job in the worker (start, end, CPU, worker id)."""

    spans: list[tuple[float, float, float, int, str]] = []   # filled on this side, by restore

    def __init__(self, job: object):
        self.job = job

    def run(self) -> tuple:
        t0, c0 = time.monotonic(), time.process_time()
        out = self.job.run()   # type: ignore[attr-defined]
        return t0, time.monotonic(), time.process_time() - c0, os.getpid(), out

    def restore(self, outcome: tuple) -> object:
        Timed.spans.append((*outcome[:4], type(self.job).__name__))
        return self.job.restore(outcome[4])   # type: ignore[attr-defined]


class TimedExecutor:
    def __init__(self, executor: object):
        self.executor = executor
        self.workers = executor.workers   # type: ignore[attr-defined]

    def submit(self, jobs: list) -> list:
        return self.executor.submit([Timed(j) for j in jobs])   # type: ignore[attr-defined]


def busy(args: argparse.Namespace) -> int:
    from pytest_navscenario.dispatch.jobs import SubjectFactory
    from pytest_navscenario.dispatch.local import ProcessExecutor
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search import strategies
    from pytest_navscenario.search.engine import run_search as search_once
    from pytest_navscenario.search.parallel import executor_evaluator

    seed = load_scenario(ROOT / "scenarios" / f"{args.seed_name}.yaml")
    pool = ProcessExecutor(args.workers)
    pool.map([EpisodeWarmup() for _ in range(args.workers)])   # workers up before the clock starts
    drawing = [0.0, 0]
    ask = strategies.Evolve.ask

    def timed_ask(self, room):   # this process's CPU spent drawing each generation
        c0 = time.process_time()
        try:
            return ask(self, room)
        finally:
            drawing[0] += time.process_time() - c0
            drawing[1] += 1
    strategies.Evolve.ask = timed_ask
    load0 = os.getloadavg()[0]
    c0, t0 = time.process_time(), time.monotonic()
    report = search_once(seed, SubjectFactory(args.subject, os.getcwd()), budget=args.budget, seed_value=0,
                         shrink_budget=args.shrink_budget, evaluator=executor_evaluator(TimedExecutor(pool)))
    wall, cpu = time.monotonic() - t0, time.process_time() - c0
    pool.close()
    strategies.Evolve.ask = ask
    spans = Timed.spans
    work = sum(c for _, _, c, _, _ in spans)
    had_job = sum(e - s for s, e, _, _, _ in spans)
    first = min(s for s, *_ in spans) - t0
    last = max(e for _, e, *_ in spans) - t0
    print(f"search {args.seed_name} vs {args.subject}, budget {args.budget}, shrink budget {args.shrink_budget}, "
          f"{args.workers} workers; load average {load0:.2f} -> {os.getloadavg()[0]:.2f}")
    print(f"  {report.sims_used} search + {report.shrink_sims} shrink simulations, {len(report.failures)} "
          f"distinct failures found at sims {[f.found.sim for f in report.failures]}")
    print(f"  wall {wall:.2f} s; this process {cpu:.2f} s CPU, of which drawing {drawing[0]:.2f} s "
          f"({1000 * drawing[0] / max(drawing[1], 1):.1f} ms per generation); workers {work:.2f} s CPU")
    print(f"  workers had a job {100 * had_job / (args.workers * wall):.1f} % of the time "
          f"(first job after {first:.2f} s, last one done {wall - last:.2f} s before the end)")
    per = [(s - t0, e - t0, k) for s, e, _, _, k in spans if k == "ShrinkJob"]
    print(f"  shrink jobs (start, end s): {[(round(a, 1), round(b, 1)) for a, b, _ in per]}")
    print(f"  ideal on {args.workers} idle cores: {(cpu + work) / args.workers:.2f} s; on this machine now "
          f"{(cpu + work) / wall:.2f} cores were busy with this search")
    return 0


class EpisodeWarmup:
    def run(self) -> None:
        return None

    def restore(self, outcome: None) -> None:
        return None


def overhead(args: argparse.Namespace) -> int:
    import pickle

    from pytest_navscenario.dispatch.jobs import EpisodeJob
    from pytest_navscenario.sim.trajectory import Trajectory
    from pytest_navscenario.dispatch.local import ProcessExecutor, SerialExecutor
    from pytest_navscenario.scenario.loader import load_scenario

    scenario = load_scenario(ROOT / "scenarios" / "boxes1.yaml")
    import dataclasses
    short = scenario if args.full else dataclasses.replace(
        scenario, mission=dataclasses.replace(scenario.mission, timeout=2.0))
    jobs = [EpisodeJob(short, "dwa", seed=i, keep_trajectory="none") for i in range(args.jobs)]
    full = SerialExecutor().map([EpisodeJob(scenario, "dwa", keep_trajectory="all")])[0]
    compact = dataclasses.replace(full, scenario=None, trajectory=Trajectory.empty())
    print(f"payload of one result: {len(pickle.dumps(compact))} bytes compact, "
          f"{len(pickle.dumps(dataclasses.replace(full, scenario=None)))} with its trajectory "
          f"({len(full.trajectory.t)} physics rows, a full boxes1 episode), scenario {len(pickle.dumps(scenario))} "
          f"bytes out; the batch below: {args.jobs} boxes1 episodes" + ("" if args.full else " cut to 2 s of simulated time"))

    def timed(executor, label: str) -> None:
        executor.map(jobs[:4])                     # start-up and warm caches
        t0 = time.perf_counter()
        results = executor.map(jobs)
        wall = time.perf_counter() - t0
        episodes = sum(r.wall_time for r in results)
        per = wall / len(jobs) * executor.workers
        print(f"{label:28s}: {len(jobs)} episodes in {wall:6.2f} s, {1000 * wall / len(jobs):6.2f} ms each; "
              f"episode {1000 * episodes / len(jobs):6.2f} ms, overhead per task "
              f"{1000 * (per - episodes / len(jobs)):6.2f} ms (x {executor.workers} workers)")
        executor.close()

    print(f"load average {os.getloadavg()[0]:.2f}, parallel capacity now {parallel_capacity():.2f}x")
    timed(SerialExecutor(), "this process")
    timed(ProcessExecutor(1), "1 local worker process")
    timed(ProcessExecutor(2), "2 local worker processes")
    if args.ray:
        from pytest_navscenario.dispatch.on_ray import RayExecutor
        for cpus in (1, 2):
            t0 = time.perf_counter()
            ex = RayExecutor("auto", num_cpus=cpus)
            print(f"Ray local instance with {cpus} CPU(s) started in {time.perf_counter() - t0:.1f} s")
            timed(ex, f"Ray, {cpus} CPU(s)")
        if args.cluster:
            from ray.cluster_utils import Cluster
            t0 = time.perf_counter()
            cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
            cluster.add_node(num_cpus=1)
            cluster.wait_for_nodes()
            import ray
            ray.init(address=cluster.address, log_to_driver=False)
            print(f"two-node cluster (1 CPU each) started in {time.perf_counter() - t0:.1f} s")
            ex = RayExecutor(cluster.address)
            timed(ex, "Ray, two nodes x 1 CPU")
            ray.shutdown()
            cluster.shutdown()
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what", required=True)
    s = sub.add_parser("search")
    s.add_argument("--budget", type=int, default=200)
    s.add_argument("--subject", default="dwa")
    s.add_argument("--seed-name", default="boxes1")
    s.add_argument("--repeats", type=int, default=3)
    s.add_argument("--ray", action="store_true")
    s.add_argument("--shrink-budget", default=None, help="default: the plugin's (a share such as 25%%, or N per failure)")
    s.add_argument("--exec-budget", type=int, default=16, help="budget of the exec: planner's search (0: skip)")
    s.add_argument("--exec-tick", type=float, default=0.05, help="s the exec: planner takes per tick")
    s.add_argument("--exec-repeats", type=int, default=1)
    b = sub.add_parser("busy")
    b.add_argument("--budget", type=int, default=200)
    b.add_argument("--shrink-budget", default="25%", help="a share (25%%, the default) or N per failure")
    b.add_argument("--subject", default="dwa")
    b.add_argument("--seed-name", default="boxes1")
    b.add_argument("--workers", type=int, default=2)
    o = sub.add_parser("overhead")
    o.add_argument("--jobs", type=int, default=200)
    o.add_argument("--ray", action="store_true")
    o.add_argument("--full", action="store_true", help="whole boxes1 episodes (~0.1 s) instead of 2 s cuts")
    o.add_argument("--cluster", action="store_true", help="also a two-node Ray cluster on this machine")
    args = ap.parse_args()
    return {"search": search, "busy": busy, "overhead": overhead}[args.what](args)


if __name__ == "__main__":
    sys.exit(main())
