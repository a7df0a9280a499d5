"""Benchmark: retargeting the generated suite (the paper's table I, issue 13).

Run from the repository root (not a timed test; the machine may be shared, so use nice):

    nice python benchmarks/bench_retarget.py                      # potential-field and dwa
    nice python benchmarks/bench_retarget.py --subject examples.gap_follower:FollowTheGap
    nice python benchmarks/bench_retarget.py --seeds all          # every shipped seed, not only the paper's 5

For each planner P (potential-field, dwa and every --subject) the suite TS-P is generated with
real pytest runs: ``pytest --navsearch SEED ... --nav-subject=P --budget B --navsearch-seed S
--navsearch-shrink-budget 0 --navsearch-suite WORK/TS-P`` (the default strategy unless --strategy
says otherwise), i.e. every candidate the search simulated around each seed, failing or not, as in
the paper's TS-Exp-A.
Then every planner runs every suite, again with pytest (``pytest WORK/TS-P --nav-subject=Q
--nav-results=...``), and the table is computed from the results files: per suite and planner,
per seed and overall, the success and safety-stop rates (% of the suite's test cases, as in the
paper), and overall the collision and timeout rates. It also checks that each planner's re-run of
its own suite gives the outcomes the search saw (they can differ only where the search's stuck
stop ended an episode that a full run lets recover).

Everything is kept under --work (default benchmarks/out/retarget): the suites, the frozen
failures and search logs, the results files and rows.json. At most --jobs pytest processes
run at once (default 2), each on one core.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PAPER_SEEDS = ("boxes1", "boxes2", "corridor", "cylinders", "L-corridor")
PLANNERS = ("potential-field", "dwa")
OUTCOMES = ("success", "safety-stop", "collision", "timeout", "subject-error")


def label(subject: str) -> str:
    """A folder-safe short name of a subject spec."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", subject.split(":")[-1] if ":" in subject else subject)


def pytest_run(args: list[str], log: Path) -> float:
    """``python -m pytest ARGS`` from the repository root; output kept in ``log``. Exit codes 0
    and 1 (some items failed) are results; anything else stops the benchmark."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    cmd = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", *args]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    log.write_text(" ".join(cmd) + "\n\n" + proc.stdout + proc.stderr)
    if proc.returncode not in (0, 1):
        tail = "\n".join((proc.stdout + proc.stderr).splitlines()[-15:])
        raise SystemExit(f"pytest exited with {proc.returncode}: {' '.join(cmd)}\n{tail}\n(full output: {log})")
    return time.perf_counter() - t0


def generate(subject: str, seeds: list[str], a: argparse.Namespace) -> tuple[str, float]:
    """TS-<subject>: one pytest run with a search per seed, the suite kept as scenario files."""
    name = label(subject)
    args = [f"--nav-subject={subject}", "--budget", str(a.budget), "--navsearch-seed", str(a.search_seed),
            "--navsearch-strategy", a.strategy,
            "--navsearch-shrink-budget", "0", "--navsearch-suite", str(a.work / f"TS-{name}"),
            "--navsearch-out", str(a.work / f"frozen-{name}")]
    for seed in seeds:
        args += ["--navsearch", seed]
    return name, pytest_run(args, a.work / f"generate-{name}.log")


def rerun(suite: str, subject: str, a: argparse.Namespace) -> float:
    results = a.work / f"results-{label(subject)}-on-TS-{suite}.jsonl"
    return pytest_run([str(a.work / f"TS-{suite}"), f"--nav-subject={subject}", f"--nav-results={results}",
                       "--nav-artifacts=none"], a.work / f"rerun-{label(subject)}-on-TS-{suite}.log")


def rates(records: list[dict], seeds: list[str]) -> dict:
    """Per seed (family) and overall: n and the count of each outcome."""
    out = {}
    for key in [*seeds, "overall"]:
        sel = [r for r in records if key == "overall" or r["family"] == key]
        out[key] = {"n": len(sel), **{o: sum(r["outcome"] == o for r in sel) for o in OUTCOMES}}
    return out


def search_outcomes(a: argparse.Namespace, suite: str) -> dict[str, str]:
    """scenario_hash -> the outcome the generating search saw (its search logs, search phase)."""
    found = {}
    for log in sorted((a.work / f"frozen-{suite}").glob("*/search-log.jsonl")):
        for line in log.read_text().splitlines():
            rec = json.loads(line)
            if rec.get("record", "candidate") == "candidate" and rec["phase"] == "search":
                found[rec["scenario_hash"]] = rec["outcome"]
    return found


def pct(k: int, n: int) -> str:
    return f"{100 * k / n:.1f} %" if n else "n/a"


def table(rows: list[dict], seeds: list[str]) -> str:
    head = ["planner", "suite (n)"] + [f"{s} {w}" for s in seeds for w in ("succ.", "S-stop")] + \
        ["overall succ.", "overall S-stop", "collision", "timeout"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [r["planner"], f"TS-{r['suite']} ({r['rates']['overall']['n']})"]
        for s in [*seeds, "overall"]:
            c = r["rates"][s]
            cells += [pct(c["success"], c["n"]), pct(c["safety-stop"], c["n"])]
        o = r["rates"]["overall"]
        cells += [pct(o["collision"], o["n"]), pct(o["timeout"], o["n"])]
        if r["planner"] == r["generator"]:
            cells = [f"**{c}**" if i < 2 or "overall" in head[i] else c for i, c in enumerate(cells)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def parse() -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--subject", action="append", default=[],
                   help="another planner to generate a suite against and run on every suite (repeatable)")
    p.add_argument("--budget", type=int, default=100, help="simulations per search (default 100)")
    p.add_argument("--search-seed", type=int, default=0, help="the searches' seed (default 0)")
    p.add_argument("--strategy", default="evolve", help="the search strategy (default evolve, the plugin's default)")
    p.add_argument("--seeds", default="",
                   help="comma-separated seed names added to the paper's five, or 'all' for every "
                        "scenario in scenarios/")
    p.add_argument("--jobs", type=int, default=2, help="pytest processes at once (default 2)")
    p.add_argument("--work", type=Path, default=ROOT / "benchmarks" / "out" / "retarget",
                   help="folder for suites, frozen failures, logs and results (default benchmarks/out/retarget)")
    a = p.parse_args()
    a.work = a.work.resolve()
    return a


def seed_names(a: argparse.Namespace) -> list[str]:
    extra = ([p.stem for p in sorted((ROOT / "scenarios").glob("*.yaml"))] if a.seeds.strip() == "all"
             else [s.strip() for s in a.seeds.split(",") if s.strip()])
    return list(dict.fromkeys([*PAPER_SEEDS, *extra]))


def main() -> None:
    a = parse()
    a.work.mkdir(parents=True, exist_ok=True)
    seeds = seed_names(a)
    planners = list(dict.fromkeys([*PLANNERS, *a.subject]))
    print(f"load average before: {os.getloadavg()}; seeds {', '.join(seeds)}; strategy {a.strategy}, budget "
          f"{a.budget}, search seed {a.search_seed}, shrinking off; work folder {a.work}", flush=True)
    t0 = time.perf_counter()
    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        generated = dict(pool.map(lambda s: generate(s, seeds, a), planners))
        print("generated: " + ", ".join(f"TS-{k} in {v:.0f} s" for k, v in generated.items()), flush=True)
        jobs = [(suite, q) for suite in generated for q in planners]
        walls = list(pool.map(lambda j: rerun(j[0], j[1], a), jobs))
    rows, by_label = [], {label(q): q for q in planners}
    for (suite, q), wall in zip(jobs, walls):
        records = [json.loads(line) for line in
                   (a.work / f"results-{label(q)}-on-TS-{suite}.jsonl").read_text().splitlines()]
        row = {"planner": q, "suite": suite, "generator": by_label[suite], "wall": wall,
               "rates": rates(records, seeds)}
        if label(q) == suite:   # the generating planner: does the re-run repeat what the search saw?
            seen = search_outcomes(a, suite)
            row["differs_from_search"] = sorted(r["scenario"] for r in records
                                                if seen.get(r["scenario_hash"]) != r["outcome"])
        rows.append(row)
    cpu = resource.getrusage(resource.RUSAGE_CHILDREN)
    (a.work / "rows.json").write_text(json.dumps(rows, indent=1))
    print()
    print(table(rows, seeds))
    print()
    for r in rows:
        if "differs_from_search" in r:
            d = r["differs_from_search"]
            print(f"{r['planner']} re-running TS-{r['suite']}: {len(d)} case(s) with another outcome than in "
                  f"the search" + (f": {', '.join(d[:10])}" + (" ..." if len(d) > 10 else "") if d else ""))
    print(f"wall {time.perf_counter() - t0:.0f} s, CPU of the pytest processes {cpu.ru_utime + cpu.ru_stime:.0f} s, "
          f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
