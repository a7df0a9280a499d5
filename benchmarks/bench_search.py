"""Benchmark of the failure search (issue 4). Run from the repository root:

    python benchmarks/bench_search.py                 # everything (about 20 min on 2 cores)
    python benchmarks/bench_search.py --part speed    # budget 1000, one seed, DWA, one core
    python benchmarks/bench_search.py --part power    # 5 seeds x 2 planners x 5 search seeds, evolve vs random
    python benchmarks/bench_search.py --part suite    # suite generated against potential-field, re-run with DWA

Figures: medians and totals, printed as a table and saved as JSON (--out).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SEEDS = ("boxes1", "boxes2", "corridor", "cylinders", "L-corridor")
PLANNERS = ("dwa", "potential-field")


def _load(name):
    from pytest_navscenario.scenario.loader import load_scenario
    return load_scenario(ROOT / "scenarios" / f"{name}.yaml")


def one_search(args):
    seed_name, planner, strategy, seed_value, budget = args
    from pytest_navscenario.subjects.loading import load_subject
    from pytest_navscenario.search.engine import run_search

    t0, c0 = time.perf_counter(), time.process_time()
    r = run_search(_load(seed_name), load_subject(planner), budget=budget, seed_value=seed_value,
                   strategy=strategy, shrink_budget=0)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    search = [c for c in r.candidates if c.phase == "search"]
    return {"seed": seed_name, "planner": planner, "strategy": strategy, "search_seed": seed_value,
            "budget": budget, "sims": r.sims_used, "discarded": r.discarded_total,
            "distinct_failures": len(r.failures), "failing_sims": sum(c.failed for c in search),
            "best_clearance": r.best_clearance, "wall": wall, "cpu": cpu,
            "sim_wall": sum(c.wall_time for c in search),
            "suite": [list(c.offsets) for c in search], "suite_outcomes": [c.outcome for c in search]}


def rerun(args):
    seed_name, planner, offsets_list = args
    from pytest_navscenario.subjects.loading import load_subject
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.search.space import SearchSpace

    space = SearchSpace(_load(seed_name))
    factory = load_subject(planner)
    return [run_scenario(space.apply(o), factory()).outcome.value for o in offsets_list]


def part_speed(budget: int) -> dict:
    r = one_search(("boxes1", "dwa", "evolve", 0, budget))
    over = (r["wall"] - r["sim_wall"]) / budget * 1000
    print(f"speed: budget {budget} on boxes1 vs dwa (evolve, one process): {r['wall']:.1f} s wall, "
          f"{r['cpu']:.1f} s CPU, {r['cpu'] / budget * 1000:.1f} ms CPU per simulation, search overhead "
          f"(wall outside episodes) {over:.1f} ms per simulation, {r['distinct_failures']} distinct failures")
    return {"budget": budget, "wall": r["wall"], "cpu": r["cpu"], "overhead_ms": over,
            "distinct_failures": r["distinct_failures"]}


def part_power(budget: int, search_seeds: int, jobs: int, reuse_random: str | None = None) -> list[dict]:
    reused = []
    if reuse_random:  # random sampling does not depend on the evolve strategy: reuse a saved run
        reused = [r for r in json.loads(Path(reuse_random).read_text())["power"]
                  if r["strategy"] == "random" and r["budget"] == budget and r["search_seed"] < search_seeds]
    strategies = ("evolve",) if reused else ("evolve", "random")
    tasks = [(s, p, strat, k, budget) for s in SEEDS for p in PLANNERS for strat in strategies
             for k in range(search_seeds)]
    with ProcessPoolExecutor(jobs) as pool:
        rows = list(pool.map(one_search, tasks)) + reused
    print(f"\npower: budget {budget}, {search_seeds} search seeds; distinct failures (total over search "
          f"seeds) and lowest clearance (m)")
    print(f"{'seed':<11} {'planner':<16} {'evolve':>7} {'random':>7} {'ev.clr':>7} {'rnd.clr':>7}")
    tot = {"evolve": 0, "random": 0}
    for s in SEEDS:
        for p in PLANNERS:
            cell = {}
            for strat in ("evolve", "random"):
                sel = [r for r in rows if r["seed"] == s and r["planner"] == p and r["strategy"] == strat]
                cell[strat] = (sum(r["distinct_failures"] for r in sel),
                               min(r["best_clearance"] for r in sel))
                tot[strat] += cell[strat][0]
            print(f"{s:<11} {p:<16} {cell['evolve'][0]:>7} {cell['random'][0]:>7} "
                  f"{cell['evolve'][1]:>7.3f} {cell['random'][1]:>7.3f}")
    ratio = tot["evolve"] / tot["random"] if tot["random"] else math.inf
    print(f"{'total':<28} {tot['evolve']:>7} {tot['random']:>7}   evolve/random = {ratio:.2f}")
    for p in PLANNERS:
        for strat in ("evolve", "random"):
            walls = [r["wall"] for r in rows if r["planner"] == p and r["strategy"] == strat] or [math.nan]
            print(f"  median wall per search, {p} {strat}: {statistics.median(walls):.1f} s")
    return rows


def part_suite(rows: list[dict], jobs: int) -> dict:
    """The suite generated against potential-field (every simulated candidate of its evolve
    searches) re-run with DWA: success rates of both on the same suite."""
    gen = [r for r in rows if r["planner"] == "potential-field" and r["strategy"] == "evolve"]
    pf_out = [o for r in gen for o in r["suite_outcomes"]]
    tasks = [(r["seed"], "dwa", r["suite"]) for r in gen]
    with ProcessPoolExecutor(jobs) as pool:
        dwa_out = [o for outs in pool.map(rerun, tasks) for o in outs]
    n = len(pf_out)
    pf_rate = sum(o == "success" for o in pf_out) / n
    dwa_rate = sum(o == "success" for o in dwa_out) / n
    print(f"\nsuite generated against potential-field ({n} scenarios): potential-field success "
          f"{pf_rate:.1%}, dwa success {dwa_rate:.1%}")
    return {"n": n, "pf_success": pf_rate, "dwa_success": dwa_rate}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--part", choices=("all", "speed", "power", "suite"), default="all")
    ap.add_argument("--budget", type=int, default=100)
    ap.add_argument("--speed-budget", type=int, default=1000)
    ap.add_argument("--search-seeds", type=int, default=5)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--out", default="bench_search.json")
    ap.add_argument("--reuse-random", metavar="JSON", help="take the random-sampling rows from an earlier --out file")
    a = ap.parse_args()
    out: dict = {}
    if a.part in ("all", "speed"):
        out["speed"] = part_speed(a.speed_budget)
    if a.part in ("all", "power", "suite"):
        rows = part_power(a.budget, a.search_seeds, a.jobs, a.reuse_random)
        out["power"] = [{k: v for k, v in r.items() if not k.startswith("suite")} for r in rows]
        if a.part in ("all", "suite"):
            out["suite"] = part_suite(rows, a.jobs)
    Path(a.out).write_text(json.dumps(out, indent=1, default=str))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
