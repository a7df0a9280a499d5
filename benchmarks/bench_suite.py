"""Suite speed: ``pytest`` on 500 generated scenario files, serial vs ``-n 2`` vs xdist's workers.

    env -u PYTHONDONTWRITEBYTECODE python benchmarks/bench_suite.py [--count 500] [--repeats 3]

The scenarios are the five shipped seeds with their obstacles moved by up to +-0.3 m (fixed RNG,
so every run benchmarks the same files), 100 per seed in five family folders, run against the
default built-in planner. Prints per mode the median wall time of the whole ``pytest`` process,
the serial / -n 2 speed-up (``-n 2`` on scenario files only: the plugin's two worker processes;
"xdist": ``-n 2 --dist load``, two pytest-xdist workers), and the plugin overhead per item: pytest's own session time minus
the sum of the episodes' ``run_scenario`` times (``wall_time`` in the results file), divided by
the item count, measured on the serial run (in -n 2 the episodes overlap); "marginal" is the
difference between the full suite and a copy of its first fifth (the same share of each family),
so start-up and imports cancel. Plots of failing items
(a separate feature, ~0.1-1 s each) are off; artifacts too. Also checks that serial and -n 2
produce the same records (wall times aside).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import resource
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

    from pytest_navscenario.core.errors import ScenarioError
    from pytest_navscenario.scenario.loader import load_scenario, loads_scenario
    from pytest_navscenario.scenario.dump import dump_scenario

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


def subset(folder: Path, to: Path, per_family: int) -> Path:
    """The first ``per_family`` files of each family folder, copied: the small suite that the
    marginal per-item cost is measured against (every family in the same share as the full one)."""
    import shutil

    to.mkdir()
    for name in ("pytest.ini", "conftest.py"):
        shutil.copy(folder / name, to / name)
    for family in sorted(p for p in folder.iterdir() if p.is_dir()):
        (to / family.name).mkdir()
        for path in sorted(family.glob("*.yaml"))[:per_family]:
            shutil.copy(path, to / family.name / path.name)
    return to


# Written into the generated suite's rootdir: measures, in a serial run, the CPU time of the session
# (collection + running + reporting) and of the items' call phases (run_scenario + the item's own
# few lines), so the per-item overhead is a CPU-time difference, robust against other load.
PROBE = """
import json, os, time
import pytest

_T = {"calls": 0.0, "n": 0, "setups": 0.0, "feasibility": 0.0}


def pytest_configure(config):
    # Time the feasibility check apart: its shortest path is the metrics' own (cached, reused by
    # the call phase), computed at setup so that an impassable scenario is an error (issue 15).
    try:
        from pytest_navscenario.verdict import feasibility
    except ImportError:
        return
    check = feasibility.infeasible

    def timed(scenario):
        t0 = time.process_time()
        try:
            return check(scenario)
        finally:
            _T["feasibility"] += time.process_time() - t0
    feasibility.infeasible = timed


def pytest_sessionstart(session):
    _T["start"] = time.process_time()


@pytest.hookimpl(tryfirst=True)
def pytest_runtestloop(session):
    _T["loop"] = time.time()      # wall clock: collection is over, the first episode starts now


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item):
    t0 = time.process_time()
    try:
        return (yield)
    finally:
        _T["setups"] += time.process_time() - t0


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    t0 = time.process_time()
    try:
        return (yield)
    finally:
        _T["calls"] += time.process_time() - t0
        _T["n"] += 1
        _T["last"] = time.time()      # wall clock: the last episode's result is in


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config):
    out = os.environ.get("NAVBENCH_PROBE")
    if out and not hasattr(config, "workerinput") and "start" in _T:
        _T["session"] = time.process_time() - _T.pop("start")
        with open(out, "w") as fh:
            json.dump(_T, fh)
"""


def _adopt_orphans() -> None:
    """Make this process the reaper of every descendant (Linux PR_SET_CHILD_SUBREAPER), so the CPU
    time of worker processes that outlive pytest by a moment (a forkserver and the episode workers
    it forked) is counted in RUSAGE_CHILDREN once they are reaped."""
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0)   # PR_SET_CHILD_SUBREAPER
    except (OSError, AttributeError):
        pass


def _reap_all() -> None:
    while True:
        try:
            os.waitpid(-1, 0)
        except ChildProcessError:
            return


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_pytest(target: Path, extra: list[str], results: Path | None,
               probe: Path | None = None, stamps: dict | None = None) -> tuple[float, float, str, float]:
    """(process wall time, pytest's own session time, pytest's last line, CPU time of pytest and
    its xdist workers: less sensitive to other load on the machine than wall time). ``stamps``
    gets the wall clock at the launch and after the exit."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    if probe is not None:
        env["NAVBENCH_PROBE"] = str(probe)
    nav = [] if "no:navscenario" in extra else ["--nav-artifacts=none", "--nav-summary=no", "--nav-plots=none"]
    cmd = [sys.executable, "-m", "pytest", str(target), "-q", "-p", "no:cacheprovider", *nav, *extra]
    if results is not None:
        cmd.append(f"--nav-results={results}")
    cpu0, t0, launch = _children_cpu(), time.perf_counter(), time.time()
    proc = subprocess.run(cmd, cwd=target if target.is_dir() else target.parent, env=env,
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if stamps is not None:
        stamps.update(launch=launch, exit=time.time())
    _reap_all()   # orphaned workers (the plugin's forkserver) are ours to reap: their CPU counts too
    cpu = _children_cpu() - cpu0
    tail = proc.stdout.strip().splitlines()[-1] if proc.stdout.strip() else proc.stderr
    match = re.search(r" in ([0-9.]+)s", tail)
    if proc.returncode not in (0, 1) or not match:
        raise SystemExit(f"pytest failed ({proc.returncode}):\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")
    return wall, float(match.group(1)), tail, cpu


SPIN = "import time\nt = time.perf_counter()\nx = 0\nfor i in range(4_000_000):\n    x += i * i\nprint(time.perf_counter() - t)\n"


def parallel_capacity() -> float:
    """How much faster two CPU-bound processes finish than one after the other, right now (2.0 on
    two idle cores; less when other jobs share the machine): the ceiling of any -n 2 speed-up."""
    one = float(subprocess.run([sys.executable, "-c", SPIN], capture_output=True, text=True).stdout)
    t0 = time.perf_counter()
    procs = [subprocess.Popen([sys.executable, "-c", SPIN], stdout=subprocess.PIPE) for _ in range(2)]
    for proc in procs:
        proc.communicate()
    return 2 * one / (time.perf_counter() - t0)


def _probe_run(folder: Path, extra: list[str]) -> dict:
    probe = folder / "probe.json"
    run_pytest(folder, extra, None, probe)
    return json.loads(probe.read_text())


def floor(count: int, repeats: int) -> int:
    """Per-item CPU outside the call phase when episodes cost (almost) nothing, against pytest's own
    per-item cost on empty Python test functions (same installed plugins), and the same marginally:
    COUNT items against COUNT / 5, so start-up and imports cancel."""
    med = statistics.median
    small = max(1, count // 5)
    with tempfile.TemporaryDirectory(prefix="navfloor-") as tmp:
        rows, marginal = {}, {}
        for label, kind, extra in [("scenario files, 2-tick episodes", "scen", ["--nav-results=r.jsonl"]),
                                   ("empty Python tests", "py", []),
                                   ("empty Python tests, one per file", "py1", []),
                                   ("the same without any plugin but pytest's own", "py1", _BARE)]:
            folders = [_floor_folder(Path(tmp) / f"{kind}-{n}-{len(rows)}", kind, n) for n in (count, small)]
            probes = [[_probe_run(folder, extra) for _ in range(repeats)] for folder in folders]
            outside = [med(p["session"] - p["calls"] for p in runs) for runs in probes]
            rows[label] = outside[0] / probes[0][0]["n"]
            marginal[label] = (outside[0] - outside[1]) / (probes[0][0]["n"] - probes[1][0]["n"])
            print(f"{label}: {1000 * rows[label]:.2f} ms CPU per item outside the call phase (median of "
                  f"{repeats}, {probes[0][0]['n']} items, fixed session costs included); marginal "
                  f"{1000 * marginal[label]:.2f} ms (against {probes[1][0]['n']} items)")
        scen_row = rows["scenario files, 2-tick episodes"]
        print(f"plugin + loader share: {1000 * (scen_row - rows['empty Python tests']):.2f} ms per item "
              f"({1000 * (scen_row - rows['empty Python tests, one per file']):.2f} ms against one test per file; "
              f"marginal {1000 * (marginal['scenario files, 2-tick episodes'] - marginal['empty Python tests, one per file']):.2f} ms)")
    return 0


# pytest with none of the installed plugins (xdist, Hypothesis's, this one, ...): its own cost per item
_BARE = ["-p", "no:navscenario", "-p", "no:hypothesispytest", "-p", "no:xdist", "-p", "no:xdist.looponfail",
         "-p", "no:benchmark", "-p", "no:platformdirs"]


def _floor_folder(folder: Path, kind: str, n: int) -> Path:
    """``n`` items of one kind in their own rootdir: scenario files with 2-tick episodes ("scen"),
    empty test functions 100 to a file ("py") or one to a file ("py1"), as scenario files are."""
    folder.mkdir()
    (folder / "pytest.ini").write_text("[pytest]\n")
    (folder / "conftest.py").write_text(PROBE)
    for i in range(n):
        if kind == "scen":
            (folder / f"s{i:04d}.yaml").write_text(
                "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 0.32, y: 0}, timeout: 0.5}\n"
                f"obstacles: [{{type: box, x: 3, y: {i % 7}, length: 1, width: 1}}]\n")
        elif kind == "py1":
            (folder / f"test_f{i:04d}.py").write_text("def test_it(): pass\n")
    if kind == "py":
        for i in range(0, n, 100):
            (folder / f"test_m{i}.py").write_text("".join(f"def test_{j}(): pass\n" for j in range(min(100, n - i))))
    return folder


def _sequential_parts(probes: list[dict], serial_wall: float, capacities: tuple[float, ...]) -> None:
    """From launch to the run loop and from the last episode's result to the exit, per mode: the
    parts no number of workers shortens, and the speed-up they allow even with no overhead at all
    (an upper bound: under -n 2 the workers may still be starting when the loop begins)."""
    med = statistics.median
    parts = {}
    for label in ("serial", "-n 2"):
        runs = [p for p in probes if p["label"] == label and "loop" in p]
        if not runs:
            return
        parts[label] = (med(p["loop"] - p["launch"] for p in runs), med(p["exit"] - p["last"] for p in runs))
        print(f"{label}: launch to the run loop (collection done, episodes start) {parts[label][0]:.2f} s, the "
              f"last episode's result to the exit {parts[label][1]:.2f} s (median wall)")
    seq_serial, seq_par = sum(parts["serial"]), sum(parts["-n 2"])
    for capacity in sorted(set(min(c, 2.0) for c in capacities) | {2.0}):  # the probe can read > 2
        ceiling = serial_wall / (seq_par + (serial_wall - seq_serial) / capacity)
        print(f"ceiling with no per-item overhead at all, capacity {capacity:.2f}x: {serial_wall:.2f} / "
              f"({seq_par:.2f} + {serial_wall - seq_serial:.2f} / {capacity:.2f}) = {ceiling:.2f}x, "
              f"{100 * ceiling / capacity:.0f} % of the capacity")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=500)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--floor", action="store_true",
                    help="only the overhead floor: COUNT scenario files whose episodes last 2 ticks vs "
                         "COUNT empty Python tests, CPU time outside the call phase per item")
    args = ap.parse_args()
    _adopt_orphans()
    if args.floor:
        return floor(args.count, args.repeats)
    med = statistics.median
    with tempfile.TemporaryDirectory(prefix="navbench-") as tmp:
        folder = Path(tmp) / "suite"
        n = generate(folder, args.count)
        (folder / "pytest.ini").write_text("[pytest]\n")  # its own rootdir: only these files collected
        (folder / "conftest.py").write_text(PROBE)
        probes: list[dict] = []
        capacity = parallel_capacity()
        print(f"{n} scenario files in {len(SEEDS)} families; {args.repeats} runs per mode; "
              f"{os.cpu_count()} CPUs; load average before: {os.getloadavg()[0]:.2f}; "
              f"parallel capacity of two CPU-bound processes now: {capacity:.2f}x")
        walls: dict[str, list[float]] = {"serial": [], "-n 2": [], "xdist": []}
        cpus: dict[str, list[float]] = {"serial": [], "-n 2": [], "xdist": []}
        rest: dict[str, list[tuple[int, float]]] = {"all": [], "small": []}
        records: list[list[dict]] = []
        small_suite = subset(folder, Path(tmp) / "small", max(1, n // len(SEEDS) // 5))
        for r in range(args.repeats):
            for label, target, extra in [("serial", folder, []), ("-n 2", folder, ["-n", "2"]),
                                         ("xdist", folder, ["-n", "2", "--dist", "load"]),
                                         ("small", small_suite, [])]:
                results = Path(tmp) / f"r{r}-{len(records)}.jsonl"
                probe = Path(tmp) / "probe.json" if label in ("serial", "small", "-n 2") else None
                stamps: dict = {}
                wall, session, tail, cpu = run_pytest(target, extra, results, probe, stamps)
                if probe is not None:
                    probes.append(dict(json.loads(probe.read_text()), label=label, **stamps))
                recs = [json.loads(line) for line in results.read_text().splitlines()]
                episodes = sum(rec["wall_time"] for rec in recs)
                print(f"  run {r + 1} {label:10s}: {wall:6.2f} s wall, {cpu:6.2f} s CPU, session {session:6.2f} s, "
                      f"episodes {episodes:6.2f} s  [{tail}]")
                if label in walls:
                    walls[label].append(wall)
                    cpus[label].append(cpu)
                    records.append([{k: v for k, v in rec.items() if k != "wall_time"} for rec in recs])
                if label in ("serial", "small"):
                    rest["all" if label == "serial" else "small"].append((len(recs), session - episodes))
        collect = [run_pytest(folder, ["--collect-only"], None)[1] for _ in range(args.repeats)]
        same = all(recs == records[0] for recs in records)
        print(f"records identical across all serial, -n 2 and xdist runs: {same}")
        for label in ("-n 2", "xdist"):
            print(f"median wall: serial {med(walls['serial']):.2f} s, {label} {med(walls[label]):.2f} s, "
                  f"speed-up {med(walls['serial']) / med(walls[label]):.2f}x")
        (n_all, _), (n_one, _) = rest["all"][0], rest["small"][0]
        extra_all = med(x for _, x in rest["all"])
        extra_one = med(x for _, x in rest["small"])
        capacities = (capacity, parallel_capacity())
        print(f"parallel capacity after: {capacities[1]:.2f}x (2.00 = two idle cores)")
        for label in ("-n 2", "xdist"):
            print(f"median CPU time: serial {med(cpus['serial']):.2f} s, {label} {med(cpus[label]):.2f} s "
                  f"(+{100 * (med(cpus[label]) / med(cpus['serial']) - 1):.0f} %; 95 % of the capacity allows "
                  f"~+5 %)")
        print(f"load average after: {os.getloadavg()[0]:.2f} (wall times inflate with load)")
        print(f"session time not spent in run_scenario: {extra_all:.2f} s for {n_all} items, "
              f"{extra_one:.2f} s for {n_one} items")
        print(f"  = {1000 * extra_all / n_all:.2f} ms per item on average (fixed costs included); "
              f"marginal per-item overhead {1000 * (extra_all - extra_one) / (n_all - n_one):.2f} ms "
              f"(difference between the two suite sizes: start-up and imports cancel)")
        full = [p for p in probes if p["label"] == "serial"]
        small = [p for p in probes if p["label"] == "small"]
        outside = {k: med(p["session"] - p["calls"] for p in ps) for k, ps in (("full", full), ("small", small))}
        print(f"CPU time outside the items' call phases (collection, reports, report.nav, results), serial: "
              f"{outside['full']:.2f} s for {full[0]['n']} items = {1000 * outside['full'] / full[0]['n']:.2f} ms "
              f"per item; marginal {1000 * (outside['full'] - outside['small']) / (full[0]['n'] - small[0]['n']):.2f}"
              f" ms per item (vs {small[0]['n']} items; call phases {med(p['calls'] for p in full):.2f} s CPU)")
        per = {k: {q: med(p[q] for p in ps) for q in ("setups", "feasibility")}
               for k, ps in (("full", full), ("small", small))}
        span = full[0]["n"] - small[0]["n"]
        feas = 1000 * (per["full"]["feasibility"] - per["small"]["feasibility"]) / span
        print(f"  of which setup phases {1000 * (per['full']['setups'] - per['small']['setups']) / span:.2f} ms "
              f"per item (marginal), and in them the feasibility check {feas:.2f} ms: the shortest path the "
              f"metrics need, computed at setup since issue 15 and reused by the call phase; without it "
              f"{1000 * (outside['full'] - outside['small']) / span - feas:.2f} ms per item")
        print(f"collection alone (--collect-only, {n} files): {med(collect):.2f} s session, "
              f"{1000 * med(collect) / n:.2f} ms per file")
        _sequential_parts(probes, med(walls["serial"]), capacities)
    return 0


if __name__ == "__main__":
    sys.exit(main())
