"""What the failure search costs besides its episodes, and what it finds per CPU second (issue 35).

Run from the repository root (not a timed test; CPU time, which a heavily loaded machine still
inflates: compare runs made side by side):

    nice python benchmarks/bench_search_cost.py                          # budget 100, 10 search seeds
    nice python benchmarks/bench_search_cost.py --budget 1000 --search-seeds 1
    nice python benchmarks/bench_search_cost.py --part fixed --repeats 200 --steps   # per-episode fixed cost
    nice python benchmarks/bench_search_cost.py --part split --budget 1000 --repeats 3   # the 1000-search's parts
    nice python benchmarks/bench_search_cost.py --search-seeds 1 --seeds boxes1,boxes2 --variants insert0 \
        --check evolve=0.2,random=0.15,hillclimb=0.15         # the guard (exit 1 if over)

``--part share`` (default): for each seed (boxes1, boxes2, cylinders) x variant (``insert0``: the
seed's ``search: {insert: 0}``, only its own obstacles move; ``shipped``: its search section as
shipped) x strategy x search seed, one search against ``--subject`` without shrinking, in one
process. Per search: CPU of the whole search, CPU inside ``harness.runner.run_scenario`` (the
episodes), the rest (the search's own work: proposing, validity and ranking, reading episodes,
bookkeeping), distinct failures and whether it found one. Per strategy and variant: the sums, the
own work as a share of the episodes' CPU, failures found per CPU second, and evolve against random:
searches with a failure (Fisher's exact test, two-sided) and paired by seed and search seed
(McNemar's exact test on the discordant pairs). ``--check`` exits 1 when a strategy's own work
exceeds its share of its episodes' CPU: the benchmark that keeps the own work from growing back.

``--part split --budget 1000 --repeats 3``: the search of ``bench_search.py --part speed`` (issue
35.4), its CPU split into episodes (ticks: MuJoCo, lidar, planner, loop; fixed cost), the
shrinker's own work and the strategy's own work.

``--part fixed``: each seed's own episode (no search) ``--repeats`` times: CPU of the whole
``run_scenario`` and of its ticks (``Episode.run_ticks``), the compiled models forgotten before
each (a search's candidate is a layout not built before, of a structure built before: its MjData
pool and MjSpec kept; ``--fresh-structure``: forgotten too); the rest is the fixed per-episode cost
(building and compiling the MuJoCo model, the lidar, the planner's reset, metrics and verdict);
``--steps`` times those steps one by one.
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
SEEDS = ("boxes1", "boxes2", "cylinders")
STRATEGIES = ("evolve", "random", "hillclimb")
VARIANTS = ("insert0", "shipped")


def _load(name):
    from pytest_navscenario.scenario.loader import load_scenario
    return load_scenario(ROOT / "scenarios" / f"{name}.yaml")


def one_search(args) -> dict:
    """One search, its CPU split into episodes and the rest."""
    seed_name, variant, strategy, seed_value, budget, subject = args
    import pytest_navscenario.harness.runner as runner
    from pytest_navscenario.search.engine import run_search
    from pytest_navscenario.search.space import SearchSpace
    from pytest_navscenario.subjects.loading import load_subject

    seed = _load(seed_name)
    space = SearchSpace(seed, {"insert": 0}) if variant == "insert0" else SearchSpace(seed)
    inner, spent = runner.run_scenario, [0.0]

    def timed(*a, **k):
        c = time.process_time()
        try:
            return inner(*a, **k)
        finally:
            spent[0] += time.process_time() - c

    runner.run_scenario = timed
    try:
        c0 = time.process_time()
        r = run_search(seed, load_subject(subject), budget=budget, seed_value=seed_value, strategy=strategy,
                       shrink_budget=0, space=space)
        cpu = time.process_time() - c0
    finally:
        runner.run_scenario = inner
    return {"seed": seed_name, "variant": variant, "strategy": strategy, "search_seed": seed_value,
            "budget": budget, "sims": r.sims_used, "cpu": cpu, "episodes": spent[0], "own": cpu - spent[0],
            "failures": len(r.failures), "found": bool(r.failures),
            "signatures": sorted("/".join(map(str, f.found.signature)) for f in r.failures)}


def fisher_two_sided(a: int, b: int, c: int, d: int) -> float:
    """Fisher's exact test of the 2x2 table [[a, b], [c, d]], two-sided (tables no likelier)."""
    n1, n2, k = a + b, c + d, a + c

    def p(x: int) -> float:
        return math.comb(n1, x) * math.comb(n2, k - x) / math.comb(n1 + n2, k)
    observed = p(a)
    lo, hi = max(0, k - n2), min(k, n1)
    return min(1.0, sum(p(x) for x in range(lo, hi + 1) if p(x) <= observed * (1 + 1e-9)))


def mcnemar_exact(b: int, c: int) -> float:
    """McNemar's exact test: two-sided binomial p of b against c discordant pairs."""
    n = b + c
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, i) for i in range(0, min(b, c) + 1)) / 2 ** n
    return min(1.0, 2 * tail)


def summary(rows: list[dict]) -> tuple[list[str], dict]:
    lines, shares = [], {}
    lines.append("| variant | strategy | searches | CPU s | episodes s | own s | own / episodes | searches "
                 "with a failure | distinct failures | failures per CPU s |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|")
    for variant in VARIANTS:
        for strategy in STRATEGIES:
            rs = [r for r in rows if r["variant"] == variant and r["strategy"] == strategy]
            if not rs:
                continue
            cpu, ep, own = (sum(r[k] for r in rs) for k in ("cpu", "episodes", "own"))
            fails = sum(r["failures"] for r in rs)
            shares[(variant, strategy)] = own / ep if ep else math.inf
            lines.append(f"| {variant} | {strategy} | {len(rs)} | {cpu:.2f} | {ep:.2f} | {own:.2f} | "
                         f"{own / ep:.0%} | {sum(r['found'] for r in rs)} | {fails} | {fails / cpu:.3f} |")
    for variant in VARIANTS:
        ev = {(r["seed"], r["search_seed"]): r for r in rows if r["variant"] == variant and r["strategy"] == "evolve"}
        ra = {(r["seed"], r["search_seed"]): r for r in rows if r["variant"] == variant and r["strategy"] == "random"}
        keys = sorted(set(ev) & set(ra))
        if not keys:
            continue
        a = sum(ev[k]["found"] for k in keys)
        c = sum(ra[k]["found"] for k in keys)
        b_only = sum(ev[k]["found"] and not ra[k]["found"] for k in keys)
        c_only = sum(ra[k]["found"] and not ev[k]["found"] for k in keys)
        rate_e = sum(ev[k]["failures"] for k in keys) / sum(ev[k]["cpu"] for k in keys)
        rate_r = sum(ra[k]["failures"] for k in keys) / sum(ra[k]["cpu"] for k in keys)
        ratio = rate_e / rate_r if rate_r else math.inf
        lines.append(f"{variant}: evolve vs random over {len(keys)} paired searches: with a failure {a} vs {c} "
                     f"(Fisher exact two-sided p = {fisher_two_sided(a, len(keys) - a, c, len(keys) - c):.3f}); "
                     f"discordant pairs {b_only} evolve only, {c_only} random only (McNemar exact p = "
                     f"{mcnemar_exact(b_only, c_only):.3f}); distinct failures per CPU s {rate_e:.3f} vs "
                     f"{rate_r:.3f} = {ratio:.2f}x")
    return lines, shares


# --part fixed --steps: the steps of an episode outside its ticks, timed one by one (owner, attribute, label)
FIXED_STEPS = (("sim.loop:Episode", "world_of", "the compiled model (sim.world.compiled_world)"),
               ("sim.world", "layout_spec", "  of it the MjSpec (layout_spec; the rest: compile, lookups)"),
               ("sim.loop:Episode", "_reset_planner", "the planner's reset"),
               ("sim.loop:Episode", "result", "the trajectory arrays (Episode.result)"),
               ("harness.runner", "verdict", "outcome and metrics (harness.runner.verdict)"),
               ("verdict.metrics", "compute_metrics", "  of it the metrics (compute_metrics)"))


def _patch_steps(acc: dict) -> list:
    """Time each of FIXED_STEPS into ``acc`` (CPU); returns what to put back."""
    import importlib

    saved = []
    for where, attr, label in FIXED_STEPS:
        module, _, cls = where.partition(":")
        owner = importlib.import_module(f"pytest_navscenario.{module}")
        owner = getattr(owner, cls) if cls else owner
        inner = owner.__dict__[attr] if cls else getattr(owner, attr)
        func = inner.__func__ if isinstance(inner, staticmethod) else inner

        def timed(*a, _f=func, _label=label, **k):
            c = time.process_time()
            try:
                return _f(*a, **k)
            finally:
                acc[_label] = acc.get(_label, 0.0) + time.process_time() - c
        setattr(owner, attr, staticmethod(timed) if isinstance(inner, staticmethod) else timed)
        saved.append((owner, attr, inner))
    return saved


def part_fixed(subject: str, repeats: int, fresh_structure: bool = False, steps: bool = False) -> list[str]:
    """Each seed's own episode: CPU of run_scenario and of its ticks (the rest is the fixed cost);
    ``steps``: also the steps of that rest, one by one (FIXED_STEPS; their timers add a little)."""
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.sim import episode
    from pytest_navscenario.sim import world
    from pytest_navscenario.sim.world import clear_model_cache
    from pytest_navscenario.subjects.loading import load_subject

    inner, ticks = episode.Episode.run_ticks, [0.0]

    def timed(self, *a, **k):
        c = time.process_time()
        try:
            return inner(self, *a, **k)
        finally:
            ticks[0] += time.process_time() - c

    episode.Episode.run_ticks = timed
    acc: dict[str, float] = {}
    saved = _patch_steps(acc) if steps else []
    lines = ["| seed | episode CPU ms (median) | ticks ms | fixed ms | fixed share |", "|---|---|---|---|---|"]
    per_step: dict[str, list[float]] = {}
    try:
        for name in SEEDS:
            seed, factory = _load(name), load_subject(subject)
            run_scenario(seed, factory())   # warm: imports, caches
            whole, tick = [], []
            for _ in range(repeats):
                ticks[0] = 0.0
                if fresh_structure:
                    clear_model_cache()   # nothing built before
                else:
                    world._CACHE.clear()  # as for a search's candidate: a layout not built before, of a
                                          # structure built before (its MjData pool kept)
                acc.clear()
                c = time.process_time()
                run_scenario(seed, factory())
                whole.append(time.process_time() - c)
                tick.append(ticks[0])
                for label, value in acc.items():
                    per_step.setdefault(f"{name}: {label}", []).append(value)
            w, t = statistics.median(whole), statistics.median(tick)
            lines.append(f"| {name} | {w * 1e3:.2f} | {t * 1e3:.2f} | {(w - t) * 1e3:.2f} | {(w - t) / w:.0%} |")
    finally:
        episode.Episode.run_ticks = inner
        for owner, attr, value in saved:
            setattr(owner, attr, value)
    if steps:
        lines += ["", "| seed: step outside the ticks | CPU ms (median) |", "|---|---|"]
        lines += [f"| {name}: {label} | {statistics.median(per_step[f'{name}: {label}']) * 1e3:.3f} |"
                  for name in SEEDS for _, _, label in FIXED_STEPS if f"{name}: {label}" in per_step]
    return lines


def part_split(subject: str, budget: int, repeats: int) -> list[str]:
    """The search of ``bench_search.py --part speed`` (boxes1, evolve, search seed 0, shrinking at
    the default share, stuck_after as shipped, one process), its CPU split: the episodes (searching
    and shrinking) into their ticks and their fixed cost, the ticks by the loop's own clocks
    (MuJoCo's steps, the lidar's rays, the planner, the loop: wall clocks, so run it on a
    free core; CPU clocks there would cost ~3 s), the shrinker's own work (the shrink
    phase less its episodes) and the rest, the strategy's own work (issue 35.4)."""
    import pytest_navscenario.harness.runner as runner
    from pytest_navscenario.search import engine, shrinker
    from pytest_navscenario.search.engine import DEFAULT_SHRINK_BUDGET, DEFAULT_STUCK_AFTER, run_search
    from pytest_navscenario.sim import episode
    from pytest_navscenario.subjects.loading import load_subject

    acc: dict[str, float] = {}
    shrinking = [False]

    def add(key: str, value: float) -> None:
        acc[key] = acc.get(key, 0.0) + value

    def timed(inner, key, *, result=None):
        def call(*a, **k):
            c = time.process_time()
            try:
                out = inner(*a, **k)
            finally:
                add(key + (":shrink" if shrinking[0] and key != "shrink" else ""), time.process_time() - c)
            if result is not None:
                result(out)
            return out
        return call

    def loop_clocks(res):   # the loop's own clocks (perf_counter: CPU time on a free core)
        for k in ("physics", "rays", "planner", "safety"):
            add(k, res.timings.get(k, 0.0))
        add("episodes_n", 1)

    def in_shrink(inner):
        def call(*a, **k):
            shrinking[0] = True
            try:
                return timed(inner, "shrink")(*a, **k)
            finally:
                shrinking[0] = False
        return call

    saved = (runner.run_scenario, episode.Episode.run_ticks, engine.shrink_failure, shrinker.shrink_failure)
    runner.run_scenario = timed(saved[0], "episodes", result=loop_clocks)
    episode.Episode.run_ticks = timed(saved[1], "ticks")
    engine.shrink_failure = shrinker.shrink_failure = in_shrink(saved[2])
    runs = []
    try:
        for _ in range(repeats):
            acc.clear()
            c0 = time.process_time()
            r = run_search(_load("boxes1"), load_subject(subject), budget=budget, seed_value=0,
                           shrink_budget=DEFAULT_SHRINK_BUDGET, stuck_after=DEFAULT_STUCK_AFTER)
            acc["total"] = time.process_time() - c0
            acc["sims"], acc["shrink_sims"], acc["failures"] = r.sims_used, r.shrink_sims, len(r.failures)
            runs.append(dict(acc))
    finally:
        runner.run_scenario, episode.Episode.run_ticks, engine.shrink_failure, shrinker.shrink_failure = saved
    return _split_lines(runs, budget, subject)


def _split_lines(runs: list[dict], budget: int, subject: str) -> list[str]:
    """The table of ``part_split``: medians over the runs, seconds of CPU."""
    def med(f):
        return statistics.median(f(r) for r in runs)
    g = lambda r, k: r.get(k, 0.0)   # noqa: E731
    episodes = lambda r: g(r, "episodes") + g(r, "episodes:shrink")   # noqa: E731
    ticks = lambda r: g(r, "ticks") + g(r, "ticks:shrink")   # noqa: E731
    rows = [("whole search (CPU)", lambda r: r["total"]),
            ("episodes (run_scenario), search + shrink", episodes),
            ("  of which the shrink phase's episodes", lambda r: g(r, "episodes:shrink")),
            ("  ticks (Episode.run_ticks)", ticks),
            ("    MuJoCo steps (loop clock 'physics')", lambda r: g(r, "physics")),
            ("    lidar rays (loop clock 'rays')", lambda r: g(r, "rays")),
            ("    planner reset + act (loop clock 'planner')", lambda r: g(r, "planner")),
            ("    the loop's own (ticks less the three)", lambda r: ticks(r) - g(r, "physics") - g(r, "rays")
             - g(r, "planner")),
            ("  per-episode fixed cost (episodes less ticks)", lambda r: episodes(r) - ticks(r)),
            ("shrinker's own work (shrink phase less its episodes)",
             lambda r: g(r, "shrink") - g(r, "episodes:shrink")),
            ("strategy's own work (the rest)", lambda r: r["total"] - episodes(r) - g(r, "shrink")
             + g(r, "episodes:shrink"))]
    total = med(lambda r: r["total"])
    lines = [f"budget {budget} on boxes1 vs {subject} (evolve, search seed 0, default shrink, one process), "
             f"{len(runs)} run(s), medians: {med(lambda r: r['sims']):.0f} search + "
             f"{med(lambda r: r['shrink_sims']):.0f} shrink simulations, {med(lambda r: r['episodes_n']):.0f} "
             f"episodes, {med(lambda r: r['failures']):.0f} distinct failures",
             "| part | CPU s | share |", "|---|---|---|"]
    lines += [f"| {name} | {med(f):.2f} | {med(f) / total:.0%} |" for name, f in rows]
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--part", choices=("share", "fixed", "split"), default="share",
                    help="share: own work vs episodes per strategy; fixed: per-episode fixed cost; split: "
                         "the budget-1000 search (--budget 1000) split into its parts")
    ap.add_argument("--subject", default="dwa", help="planner spec: dwa, potential-field, pkg.mod:Class")
    ap.add_argument("--budget", type=int, default=100)
    ap.add_argument("--search-seeds", type=int, default=10)
    ap.add_argument("--seeds", default=",".join(SEEDS))
    ap.add_argument("--strategies", default=",".join(STRATEGIES))
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--repeats", type=int, default=20, help="fixed: episodes per seed (median)")
    ap.add_argument("--fresh-structure", action="store_true", help="fixed: empty the MjData pools too "
                    "(a model of a structure never built before)")
    ap.add_argument("--steps", action="store_true", help="fixed: also time the steps outside the ticks one by "
                    "one (the model, the planner's reset, the trajectory arrays, the verdict and metrics)")
    ap.add_argument("--jobs", type=int, default=1, help="processes (CPU time is per search, so any number)")
    ap.add_argument("--check", default=None, help="exit 1 if a strategy's own work is over this share of its "
                    "episodes' CPU: one share for all (0.2) or per strategy (evolve=1.0,random=0.2,hillclimb=0.2)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "out" / "bench_search_cost.json"))
    ap.add_argument("--table", default=None, help="print the table of a rows file (.jsonl, also of a run "
                    "cut short) and exit")
    a = ap.parse_args()
    print(f"load average before: {os.getloadavg()}")
    print("command:", " ".join(sys.argv))
    if a.table:
        rows = [json.loads(line) for line in Path(a.table).read_text().splitlines() if line.strip()]
        lines, shares = summary(rows)
        print("\n".join(lines))
        _check(a.check, shares)
        return
    if a.part == "split":
        print("\n".join(part_split(a.subject, a.budget, a.repeats)))
        print(f"load average after: {os.getloadavg()}")
        return
    if a.part == "fixed":
        print("\n".join(part_fixed(a.subject, a.repeats, a.fresh_structure, a.steps)))
        print(f"load average after: {os.getloadavg()}")
        return
    # search seed first: a run cut short has every cell of the table at about the same count
    tasks = [(s, v, strat, k, a.budget, a.subject) for k in range(a.search_seeds) for v in a.variants.split(",")
             for s in a.seeds.split(",") for strat in a.strategies.split(",")]
    rows = []
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    with ProcessPoolExecutor(a.jobs) as pool, open(a.out + "l", "w") as stream:   # rows as they come: .jsonl
        for row in pool.map(one_search, tasks):
            rows.append(row)
            stream.write(json.dumps(row) + "\n")
            stream.flush()
    lines, shares = summary(rows)
    print(f"budget {a.budget}, subject {a.subject}, seeds {a.seeds}, search seeds 0-{a.search_seeds - 1}, "
          f"no shrinking, CPU time")
    print("\n".join(lines))
    print(f"load average after: {os.getloadavg()}")
    Path(a.out).write_text(json.dumps({"command": " ".join(sys.argv), "rows": rows}, indent=1))
    _check(a.check, shares)


def _check(check: str | None, shares: dict) -> None:
    """Exit 1 when a strategy's own work is over its limit (``--check``)."""
    if check is None:
        return
    limits = _limits(check)
    over = {k: v for k, v in shares.items() if v > limits.get(k[1], limits.get("*", math.inf))}
    if over:
        print(f"CHECK FAILED: own work over its limit ({check}) of the episodes' CPU: "
              + ", ".join(f"{s} ({v}) {x:.0%}" for (v, s), x in over.items()))
        sys.exit(1)
    print(f"check: every strategy's own work within its limit ({check}) of its episodes' CPU")


def _limits(text: str) -> dict[str, float]:
    """``0.2`` (every strategy) or ``evolve=1.0,random=0.2``: strategy -> largest own/episodes."""
    out = {}
    for part in text.split(","):
        name, _, value = part.rpartition("=")
        out[name.strip() or "*"] = float(value)
    return out


if __name__ == "__main__":
    main()
