"""Scenario loader speed: load/dump of the shipped seeds and of a 5000-obstacle file, against plain
``yaml.load(CSafeLoader)`` of the same text, and the time to refuse hostile files.

    python benchmarks/bench_loader.py [--repeat N] [--cpu]

Prints medians (ms) and ratios; docs/reference/scenario-format.md and docs/benchmarks.md quote them.
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=50)
    parser.add_argument("--cpu", action="store_true", help="time with process CPU time instead of wall time")
    args = parser.parse_args()
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
