"""Failure-finding on requirements (issue 34 part 7): evolve against random at budget 100 on the
seeds with requirements, counted in violations that hold under noise.

Run from the repository root (not a timed test; the machine may be shared, so use nice):

    nice python benchmarks/bench_requirements.py --jobs 2
    nice python benchmarks/bench_requirements.py --part cost      # the check's share of an episode
    nice python benchmarks/bench_requirements.py --part rate      # how often layouts violate (seed 0)

For each seed (default: people-distance, people-speed, dock-tour) x search seed (0-4) x strategy
(evolve, random): one search at budget 100 without shrinking, the realistic lidar model in the seed
(2 cm noise, 1 % dropout) and failures confirmed at the default hold (0.9), as
``pytest --navsearch SEED --nav-sensor-model realistic`` does. Each frozen failure whose cause is a
requirement (signature ``requirement:<name>``) is then run under 5 fresh noise seeds (``--nav-seed 7
--nav-repeat 5``); it *holds* when that requirement is violated in at least 4 of them (whatever the
outcome's precedence says). Per seed and strategy: frozen failures, frozen violations, violations
that hold and the distinct requirements among them; then totals and the evolve/random ratio.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SEEDS = ("people-distance", "people-speed", "dock-tour")


def one_search(args: tuple) -> dict:
    seed_name, strategy, seed_value, budget, fresh_seed, fresh_runs = args
    from pytest_navscenario import load_scenario
    from pytest_navscenario.core.seeds import repeat_seed
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.scenario.sensor_model import MODELS, with_sensor_model
    from pytest_navscenario.search.engine import run_search
    from pytest_navscenario.subjects.loading import load_subject

    seed = with_sensor_model(load_scenario(ROOT / "scenarios" / f"{seed_name}.yaml"), MODELS["realistic"])
    factory = load_subject("dwa")
    t0, c0 = time.perf_counter(), time.process_time()
    report = run_search(seed, factory, budget=budget, seed_value=seed_value, strategy=strategy, shrink_budget=0)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    violations = []
    for f in report.failures:
        outcome, culprit = f.found.signature[0], f.found.signature[1]
        if outcome != "requirement":
            continue
        name = culprit.split(":", 1)[1]
        held = 0
        for k in range(fresh_runs):
            res = run_scenario(f.found.scenario, factory(), seed=repeat_seed(fresh_seed, k))
            held += any(r.name == name and r.violated for r in res.requirements)
        violations.append({"signature": "/".join(map(str, f.found.signature)), "requirement": name,
                           "fresh_violated": held})
    return {"seed": seed_name, "strategy": strategy, "search_seed": seed_value, "budget": budget,
            "frozen": len(report.failures), "violations": violations, "wall": wall, "cpu": cpu}


def table(rows: list[dict], fresh_hold: int, fresh_runs: int) -> str:
    lines = [f"dwa, budget {rows[0]['budget'] if rows else 100}, realistic lidar in the seed, hold 0.9, no shrinking; a violation holds when "
             f"its requirement is violated in >= {fresh_hold} of {fresh_runs} fresh noise seeds",
             f"{'seed':<16} {'strategy':<8} {'frozen':>6} {'violations':>10} {'hold':>5} {'distinct held':>14} "
             f"{'CPU s/search':>12}"]
    totals: dict[str, int] = {}
    for seed in SEEDS:
        for strategy in ("evolve", "random"):
            rs = [r for r in rows if r["seed"] == seed and r["strategy"] == strategy]
            if not rs:
                continue
            held = [v for r in rs for v in r["violations"] if v["fresh_violated"] >= fresh_hold]
            distinct = sorted({v["requirement"] for v in held})
            totals[strategy] = totals.get(strategy, 0) + len(held)
            cpu = sorted(r["cpu"] for r in rs)[len(rs) // 2]
            lines.append(f"{seed:<16} {strategy:<8} {sum(r['frozen'] for r in rs):>6} "
                         f"{sum(len(r['violations']) for r in rs):>10} {len(held):>5} "
                         f"{len(distinct):>3} {','.join(distinct):<10} {cpu:>12.1f}")
    lines.append("totals (violations that hold, over the seeds and search seeds): " +
                 ", ".join(f"{k} {v}" for k, v in totals.items()))
    if totals.get("random"):
        lines.append(f"evolve / random = {totals.get('evolve', 0) / totals['random']:.2f}")
    return "\n".join(lines)


def part_cost(calls: int = 50, episodes: int = 5) -> str:
    """CPU time of checking a seed's requirements after its episode (its signals computed from the
    trajectory, then each formula evaluated: ``verdict.requirements.check_requirements``) against
    the CPU time of the whole episode (``run_scenario`` with dwa, the check included); medians."""
    import statistics

    from pytest_navscenario import load_scenario
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.verdict.requirements import check_requirements

    lines = ["seed             requirements  ticks  check (ms)  episode (ms)  share"]
    for name in SEEDS:
        seed = load_scenario(ROOT / "scenarios" / f"{name}.yaml")
        result = run_scenario(seed, "dwa")
        check_requirements(seed, result.trajectory)      # warm: formulas parsed, plans compiled
        check = []
        for _ in range(calls):
            c0 = time.process_time()
            check_requirements(seed, result.trajectory)
            check.append(time.process_time() - c0)
        episode = []
        for _ in range(episodes):
            c0 = time.process_time()
            run_scenario(seed, "dwa")
            episode.append(time.process_time() - c0)
        c, e = statistics.median(check) * 1e3, statistics.median(episode) * 1e3
        ticks = len(result.trajectory.tick_t)
        lines.append(f"{name:<16} {len(seed.requirements):>12}  {ticks:>5}  {c:>10.2f}  {e:>12.1f}  {100 * c / e:>4.1f} %")
    return "\n".join(lines)


def part_rate(budget: int = 100) -> str:
    """How often a search's layouts violate a requirement (search seed 0, realistic lidar, no
    confirmation, no shrinking): the share of violating simulations and the first one."""
    from pytest_navscenario import load_scenario
    from pytest_navscenario.scenario.sensor_model import MODELS, with_sensor_model
    from pytest_navscenario.search.engine import run_search
    from pytest_navscenario.subjects.loading import load_subject

    lines = []
    for name in SEEDS:
        seed = with_sensor_model(load_scenario(ROOT / "scenarios" / f"{name}.yaml"), MODELS["realistic"])
        for strategy in ("random", "evolve"):
            r = run_search(seed, load_subject("dwa"), budget=budget, seed_value=0, strategy=strategy,
                           shrink_budget=0, hold=0)
            sims = [c for c in r.candidates if c.phase == "search" and not c.run]
            hits = [i for i, c in enumerate(sims) if c.signature and c.signature[0] == "requirement"]
            lines.append(f"{name:<16} {strategy:<7} sims {len(sims)} violating {len(hits)} "
                         f"({100 * len(hits) / max(len(sims), 1):.0f} %), first at sim {hits[0] + 1 if hits else None}")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--part", choices=("power", "cost", "rate"), default="power")
    ap.add_argument("--budget", type=int, default=100)
    ap.add_argument("--search-seeds", type=int, default=5)
    ap.add_argument("--strategies", default="evolve,random")
    ap.add_argument("--seeds", default=",".join(SEEDS))
    ap.add_argument("--fresh-seed", type=int, default=7)
    ap.add_argument("--fresh-runs", type=int, default=5)
    ap.add_argument("--fresh-hold", type=int, default=4)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--out", default=str(Path(__file__).parent / "out" / "bench_requirements.json"))
    a = ap.parse_args()
    print(f"load average before: {os.getloadavg()}", flush=True)
    if a.part in ("cost", "rate"):
        print(part_cost() if a.part == "cost" else part_rate(a.budget))
        print(f"load average after: {os.getloadavg()}")
        return
    tasks = [(s, strat, k, a.budget, a.fresh_seed, a.fresh_runs) for s in a.seeds.split(",")
             for strat in a.strategies.split(",") for k in range(a.search_seeds)]
    with ProcessPoolExecutor(a.jobs) as pool:
        rows = list(pool.map(one_search, tasks))
    print(table(rows, a.fresh_hold, a.fresh_runs))
    print(f"load average after: {os.getloadavg()}")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps({"command": " ".join(sys.argv), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
