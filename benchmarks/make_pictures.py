"""Make the pictures of the README and docs from the shipped seeds and the two built-in planners.

    python benchmarks/make_pictures.py [--variants 12] [--out examples/pictures]

Suite (examples/pictures/suite/<seed>/*.yaml, written on the first run or with --new-suite): the
five paper seeds of scenarios/ plus, per seed, ``--variants`` jittered layouts (each obstacle moved
by up to +-0.4 m and, boxes, turned by up to +-20 degrees; numpy seed 0; layouts that block the
start or goal are skipped). Family = the seed's name (the folder). Every scenario runs with "dwa"
(A) and "potential-field" (B) in MuJoCo, exactly as ``pytest examples/pictures/suite
--nav-subject=dwa --nav-results=a.jsonl`` would run it; both results files are written next to
the pictures (a.jsonl, b.jsonl) and the ``navscenario compare`` text is printed.

Writes:
    trajectory.png   one episode that failed (the most interesting failure of B: smallest clearance)
    comparison.png   one scenario where A and B differ, side by side
    bars.png         success up / failures by outcome down per family, A beside B (the paper's chart)
"""
from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
PAPER_SEEDS = ("boxes1", "boxes2", "corridor", "cylinders", "L-corridor")


def variants(seed, n: int, rng: np.random.Generator):
    """Jittered copies of ``seed`` that keep start and goal clear (loader.check_scenario)."""
    from pytest_navscenario.core.errors import ScenarioError
    from pytest_navscenario.scenario.loader import check_scenario
    from pytest_navscenario.scenario.model import BoxObstacle

    out = []
    tries = 0
    while len(out) < n and tries < 20 * n:
        tries += 1
        obstacles = []
        for obs in seed.obstacles:
            dx, dy = rng.uniform(-0.4, 0.4, size=2)
            change = {"x": round(obs.x + dx, 3), "y": round(obs.y + dy, 3)}
            if isinstance(obs, BoxObstacle):
                change["yaw"] = round(obs.yaw + rng.uniform(-20, 20), 2)
            obstacles.append(dataclasses.replace(obs, **change))
        k = len(out) + 1
        candidate = dataclasses.replace(seed, obstacles=tuple(obstacles), name=f"{seed.name}-v{k:02d}",
                                        family=seed.name)
        try:
            check_scenario(candidate)
        except ScenarioError:
            continue
        out.append(candidate)
    return out


def write_suite(folder: Path, n: int) -> None:
    """The seeds and their variants as scenario files, one folder (= family) per seed."""
    import shutil

    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.scenario.dump import dump_scenario

    if folder.is_dir():
        shutil.rmtree(folder)
    rng = np.random.default_rng(0)
    for path in sorted((ROOT / "scenarios").glob("*.yaml")):
        if path.stem not in PAPER_SEEDS:    # the seeds of issue 12 (moving obstacles) have their own pictures
            continue
        seed = load_scenario(path)
        family = folder / seed.name
        family.mkdir(parents=True)
        shutil.copyfile(path, family / path.name)
        for v in variants(seed, n, rng):
            (family / f"{v.name}.yaml").write_text(dump_scenario(dataclasses.replace(v, family="")))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=12)
    parser.add_argument("--out", default=str(ROOT / "examples" / "pictures"))
    parser.add_argument("--new-suite", action="store_true", help="write the suite again")
    parser.add_argument("--repeats", type=int, default=7, help="renders per picture for the timing")
    args = parser.parse_args(argv)

    from pytest_navscenario.report.compare import compare_records, format_comparison
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.report.plots import save_bars, save_comparison, save_trajectory
    from pytest_navscenario.report.results_file import make_record, write_results
    from pytest_navscenario.harness.runner import run_scenario

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    folder = out / "suite"
    if args.new_suite or not folder.is_dir():
        write_suite(folder, args.variants)
    suite = []
    for path in sorted(folder.glob("*/*.yaml")):
        scenario = load_scenario(path)
        suite.append((f"{path.relative_to(ROOT).as_posix()}::{scenario.name}", scenario))

    results: dict[str, dict[str, object]] = {"a": {}, "b": {}}
    records: dict[str, list[dict]] = {"a": [], "b": []}
    t0 = time.perf_counter()
    for side, planner in (("a", "dwa"), ("b", "potential-field")):
        for nodeid, scenario in suite:
            res = run_scenario(scenario, planner)
            results[side][nodeid] = res
            records[side].append(make_record(res, nodeid=nodeid, path=nodeid.split("::")[0]))
    elapsed = time.perf_counter() - t0
    print(f"{2 * len(suite)} episodes in {elapsed:.1f} s ({1000 * elapsed / (2 * len(suite)):.0f} ms each)")
    write_results(out / "a.jsonl", records["a"])
    write_results(out / "b.jsonl", records["b"])

    cmp = compare_records(records["a"], records["b"], a_name="a.jsonl", b_name="b.jsonl")
    print(format_comparison(cmp, max_listed=8))
    save_bars(cmp, out / "bars.png")

    def is_seed(nodeid: str) -> bool:  # suite/<seed>/<seed>.yaml, not a variant
        path = Path(nodeid.split("::")[0])
        return path.stem == path.parent.name

    # comparison.png: a scenario A and B disagree on, a seed itself if possible (regressions first)
    differ = [p.nodeid for p in cmp.broke + cmp.fixed]
    pick = min(differ, key=lambda n: (not is_seed(n), differ.index(n))) if differ else suite[0][0]
    save_comparison(results["a"][pick], results["b"][pick], out / "comparison.png",
                    labels=("A (dwa)", "B (potential-field)"))
    print(f"comparison.png: {pick}")

    # trajectory.png: another failure of B (else A): a safety stop or collision, the one that got
    # furthest (the most path to look at)
    failures = [(side != "b", r.outcome.value not in ("safety-stop", "collision"),
                 -r.metrics.path_length, nodeid, r)
                for side in ("b", "a") for nodeid, r in results[side].items() if not r.passed and nodeid != pick]
    if failures:
        *_, nodeid, res = min(failures, key=lambda f: f[:4])
    else:
        nodeid, res = suite[0][0], results["b"][suite[0][0]]
    save_trajectory(res, out / "trajectory.png")
    print(f"trajectory.png: {nodeid} ({res.subject}): {res.outcome}: {res.message}")

    # cost of one picture (what --nav-plots adds per plotted item): CPU-time medians
    from pytest_navscenario.report.plots import bars_figure, comparison_figure, png_bytes, trajectory_figure
    for label, make in (("trajectory plot", lambda: trajectory_figure(res)),
                        ("side-by-side plot", lambda: comparison_figure(results["a"][pick], results["b"][pick])),
                        ("bar chart", lambda: bars_figure(cmp))):
        times = []
        for _ in range(args.repeats):
            t = time.process_time()
            png_bytes(make())
            times.append(time.process_time() - t)
        print(f"{label}: median {1000 * statistics.median(times):.0f} ms CPU (figure + PNG, {args.repeats} runs)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
