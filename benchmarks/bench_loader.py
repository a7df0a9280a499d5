"""Scenario loader speed: load/dump of the shipped seeds and of a 5000-obstacle file, against plain
``yaml.load(CSafeLoader)`` of the same text, and the time to refuse hostile files.

    python benchmarks/bench_loader.py [--repeat N] [--cpu]
    python benchmarks/bench_loader.py --paired OTHER_CHECKOUT [--rounds 10]

Prints medians (ms) and ratios; docs/reference/scenario-format.md and docs/benchmarks.md quote them.
``--paired`` compares this checkout's loader with another one's (e.g. main's, from ``git archive``):
A and B alternate as separate processes (A B A B ...), each timing the CPU time of loading every
shipped seed and the 5000-obstacle file; it prints the ratio B/A of each pair and their median.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pytest_navscenario.core.errors import ScenarioError  # noqa: E402
from pytest_navscenario.scenario.loader import SCENARIO_LIMITS, loads_scenario
from pytest_navscenario.scenario.dump import dump_scenario  # noqa: E402

CLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


CLOCK = time.perf_counter  # --cpu switches to process CPU time (stable on a shared, loaded machine)


def median_ms(fn, repeat: int) -> float:
    fn()  # warm up (imports, caches)
    times = []
    for _ in range(repeat):
        t0 = CLOCK()
        fn()
        times.append(CLOCK() - t0)
    return statistics.median(times) * 1e3


def refuse_ms(text: str, repeat: int) -> float:
    def run():
        try:
            loads_scenario(text)
        except ScenarioError:
            return
        raise AssertionError("expected a ScenarioError")
    return median_ms(run, repeat)


def many_obstacles(n: int) -> str:
    head = "version: 1\nmission:\n  start: {x: 0, y: 0, yaw: 90}\n  goal: {x: 0, y: 10, yaw: 90}\nobstacles:\n"
    return head + "".join(f"  - {{type: box, x: {10 + (i % 100) * 2}, y: {10 + (i // 100) * 2}, length: 1, "
                          f"width: 1, yaw: 15}}\n" for i in range(n))


def seeds_cpu_ms(repeat: int) -> tuple[float, float]:
    """CPU ms to load every shipped seed once (median of ``repeat``), and one 5000-obstacle file."""
    texts = [(p.read_text(), str(p)) for p in sorted((ROOT / "scenarios").glob("*.yaml"))]

    def seeds() -> None:
        for text, src in texts:
            loads_scenario(text, src)
    global CLOCK
    CLOCK = time.process_time
    big = many_obstacles(int(SCENARIO_LIMITS["max_obstacles"]))
    return median_ms(seeds, repeat), median_ms(lambda: loads_scenario(big), max(3, repeat // 20))


def paired(other: str, rounds: int, repeat: int) -> None:
    import os
    import subprocess
    code = ("import sys; sys.argv=['x']; sys.path.insert(0, {root!r}); import importlib.util as u; "
            "spec = u.spec_from_file_location('b', {script!r}); m = u.module_from_spec(spec); "
            "spec.loader.exec_module(m); print(*m.seeds_cpu_ms({repeat}))")
    checkouts = {"A": str(Path(other).resolve()), "B": str(ROOT)}
    results: dict[str, list[tuple[float, float]]] = {"A": [], "B": []}
    for _ in range(rounds):
        for label in ("A", "B"):
            root = checkouts[label]
            env = dict(os.environ, PYTHONPATH=root)
            env.pop("PYTHONDONTWRITEBYTECODE", None)
            out = subprocess.run([sys.executable, "-c", code.format(root=root, script=__file__, repeat=repeat)],
                                 env=env, capture_output=True, text=True, check=True, cwd=root).stdout.split()
            results[label].append((float(out[0]), float(out[1])))
    print(f"A = {checkouts['A']}\nB = {checkouts['B']}  (CPU ms, median of {repeat} loads per process)")
    for i, what in enumerate(("all shipped seeds", "5000 obstacles")):
        ratios = [b[i] / a[i] for a, b in zip(results["A"], results["B"])]
        print(f"{what:<18} A {statistics.median(r[i] for r in results['A']):8.3f}  "
              f"B {statistics.median(r[i] for r in results['B']):8.3f}  B/A per pair: "
              + " ".join(f"{r:.3f}" for r in ratios) + f"  median {statistics.median(ratios):.3f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=50)
    parser.add_argument("--cpu", action="store_true", help="time with process CPU time instead of wall time")
    parser.add_argument("--paired", metavar="OTHER_CHECKOUT", help="compare with another checkout's loader")
    parser.add_argument("--rounds", type=int, default=10, help="A/B pairs for --paired")
    args = parser.parse_args()
    if args.paired:
        paired(args.paired, args.rounds, args.repeat)
        return
    global CLOCK
    if args.cpu:
        CLOCK = time.process_time
    print(f"medians, {'CPU' if args.cpu else 'wall'} time")
    r = args.repeat
    rows = []
    for path in sorted((ROOT / "scenarios").glob("*.yaml")):
        text = path.read_text()
        s = loads_scenario(text, str(path))
        load = median_ms(lambda: loads_scenario(text, str(path)), r)
        plain = median_ms(lambda: yaml.load(text, Loader=CLoader), r)
        dump = median_ms(lambda: dump_scenario(s), r)
        rows.append((path.name, load, plain, dump))
    big = many_obstacles(int(SCENARIO_LIMITS["max_obstacles"]))
    s_big = loads_scenario(big)
    rr = max(3, r // 10)
    rows.append(("5000 obstacles", median_ms(lambda: loads_scenario(big), rr),
                 median_ms(lambda: yaml.load(big, Loader=CLoader), rr), median_ms(lambda: dump_scenario(s_big), rr)))
    print(f"{'scenario':<18}{'load ms':>10}{'safe_load ms':>14}{'ratio':>8}{'dump ms':>10}")
    for name, load, plain, dump in rows:
        print(f"{name:<18}{load:>10.3f}{plain:>14.3f}{load / plain:>8.2f}{dump:>10.3f}")

    bomb = "version: 1\na: &a [" + ",".join(['"lol"'] * 9) + "]\n" + "".join(
        f"{c}: &{c} [" + ",".join([f"*{p}"] * 9) + "]\n" for p, c in zip("abcdefgh", "bcdefghi")) + "mission: *i\n"
    hostile = {
        "alias bomb (9^9 values)": bomb,
        "100000 nested brackets": "version: 1\nmission: " + "[" * 100_000 + "]" * 100_000 + "\n",
        "20000 obstacles": many_obstacles(20_000),
        "a 2-million-character value": "version: 1\nx: " + "\u00e9" * 2_000_000 + "\n",
    }
    print(f"\n{'hostile input':<26}{'refused in ms':>14}")
    for name, text in hostile.items():
        print(f"{name:<26}{refuse_ms(text, 3):>14.1f}")


if __name__ == "__main__":
    main()
