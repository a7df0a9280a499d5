"""Cost of checking requirements: stl.evaluate against RTAMT's own offline evaluator (#34, part 5).

    env -u PYTHONDONTWRITEBYTECODE python benchmarks/bench_stl.py [--repeats 300] [--json out.json]

Four typical requirements (a person distance, a speed near people, a deadline, a mission of
two visits and a keep-out zone), plus an until, over synthetic smooth signals of 300 samples at
dt = 0.1 s (a seed episode's length) and longer traces (3000, 30000 samples). Each formula is
parsed once (as a scenario's requirements are, at load); the timed call is ``evaluate`` (the
robustness at every sample, the verdict and, when violated, the first violation) or, for RTAMT,
``spec.evaluate`` on its dataset (built before the clock starts). Medians of ``--repeats`` calls, wall and this thread's CPU.
The target: the four together at most 10 % of a ~7 ms seed episode (0.7 ms).
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pytest_navscenario.stl import evaluate, parse  # noqa: E402

DT = 0.1
REQUIREMENTS = {
    "keep-away": "always (d_walker >= 0.8)",
    "slow-near-people": "always ((d_walker < 1.5) implies (speed <= 0.3))",
    "deadline": "eventually[0:5] (d_goal < 0.3)",
    "visit-a-then-b": "eventually ((d_a <= 0.5) and eventually (d_b <= 0.5)) and always (d_keepout > 0)",
}
EXTRA = {"until": "(speed <= 1.0) until[0:10] (d_goal < 0.3)",
         # the RTAMT figure: a 50 s window, longer than a 300-sample episode at dt = 0.1 s
         "deadline-50s": "eventually[0:50] (d_goal < 0.3)"}


def signals(n: int, kept: bool, seed: int = 0) -> dict[str, np.ndarray]:
    """Smooth random signals of ``n`` samples (sums of a few sines), metres and m/s: an episode
    that keeps every requirement (``kept``) or one that violates every one (the first violation
    is then searched for too)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT

    def smooth(lo, hi):
        f = sum(rng.uniform(0.2, 1) * np.sin(rng.uniform(0.05, 0.5) * t + rng.uniform(0, 6)) for _ in range(3))
        return lo + (hi - lo) * (f - f.min()) / (np.ptp(f) or 1.0)
    sig = {"d_walker": smooth(0.5, 4), "speed": smooth(0, 1.2), "d_goal": smooth(0.5, 8),
           "d_a": smooth(0.8, 6), "d_b": smooth(0.8, 6), "d_keepout": smooth(-0.5, 3)}
    if kept:
        sig["d_walker"] = smooth(0.9, 4)
        sig["speed"] = np.where(sig["d_walker"] < 1.5, np.minimum(sig["speed"], 0.25), sig["speed"])
        sig["speed"][:31] = np.minimum(sig["speed"][:31], 1.0)
        sig["d_goal"][30] = 0.2
        sig["d_a"][n // 3] = sig["d_b"][2 * n // 3] = 0.3
        sig["d_keepout"] = smooth(0.2, 3)
    return sig


def timed(fn, repeats: int) -> dict[str, float]:
    """Median wall and CPU milliseconds of ``fn()``."""
    wall, cpu = [], []
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.thread_time()
        fn()
        cpu.append(time.thread_time() - c0)
        wall.append(time.perf_counter() - w0)
    return {"wall_ms": statistics.median(wall) * 1e3, "cpu_ms": statistics.median(cpu) * 1e3}


def rtamt_evaluator(text: str, sig: dict[str, np.ndarray]):
    """RTAMT's offline discrete-time evaluation of ``text`` as a call (dataset built once)."""
    import rtamt
    spec = rtamt.StlDiscreteTimeSpecification()
    for name in sig:
        spec.declare_var(name, "float")
    spec.spec = text
    spec.set_sampling_period(round(DT * 1000), "ms", 0.1)
    spec.parse()
    n = len(next(iter(sig.values())))
    data = {"time": [i * DT for i in range(n)], **{k: v.tolist() for k, v in sig.items()}}
    return lambda: spec.evaluate({k: list(v) for k, v in data.items()})


def measure(formulas, n: int, kept: bool, args, out: dict) -> list[dict]:
    """One table: every formula on one trace, ours and RTAMT's (up to 3000 samples)."""
    sig = signals(n, kept)
    rows = []
    repeats = max(5, args.repeats * 300 // n) if n > 300 else args.repeats
    print(f"\n{n} samples ({n * DT:g} s at dt = {DT} s), an episode that {'keeps' if kept else 'violates'} "
          f"the four, medians of {repeats} calls (CPU)")
    print(f"  {'requirement':18s} {'stl ms':>9s} {'rtamt ms':>10s} {'ratio':>7s}  verdict")
    total = {"stl": 0.0, "rtamt": 0.0}
    for name, f in formulas.items():
        ours = timed(lambda: evaluate(f, sig, DT), repeats)
        verdict = "violated" if evaluate(f, sig, DT).violated else "kept"
        row = {"samples": n, "kept": kept, "requirement": name, "formula": f.text, "stl": ours,
               "verdict": verdict}
        ref_ms = None
        if not args.no_rtamt and n <= 3000:
            ref = timed(rtamt_evaluator(f.text, sig), max(3, repeats // 20))
            row["rtamt"] = ref
            ref_ms = ref["cpu_ms"]
        if name in REQUIREMENTS:
            total["stl"] += ours["cpu_ms"]
            total["rtamt"] += ref_ms or 0.0
        ratio = f"{ref_ms / ours['cpu_ms']:6.0f}x" if ref_ms else "      -"
        ref_text = f"{ref_ms:10.3f}" if ref_ms else "         -"
        print(f"  {name:18s} {ours['cpu_ms']:9.4f} {ref_text} {ratio}  {verdict}")
        rows.append(row)
    ref_total = f"{total['rtamt']:10.3f}" if total["rtamt"] else "         -"
    ratio = f"{total['rtamt'] / total['stl']:6.0f}x" if total["rtamt"] else "      -"
    print(f"  {'four requirements':18s} {total['stl']:9.4f} {ref_total} {ratio}")
    out[f"four_requirements_{n}_{'kept' if kept else 'violated'}_cpu_ms"] = total
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=300)
    ap.add_argument("--lengths", type=int, nargs="+", default=[300, 3000, 30000])
    ap.add_argument("--no-rtamt", action="store_true", help="leave RTAMT out (not installed, or slow)")
    ap.add_argument("--json", type=Path, help="also write the figures here")
    args = ap.parse_args()
    out: dict[str, object] = {"repeats": args.repeats, "dt": DT, "rows": []}
    formulas = {name: parse(text) for name, text in {**REQUIREMENTS, **EXTRA}.items()}
    for n in args.lengths:
        for kept in (True, False):
            out["rows"] += measure(formulas, n, kept, args, out)
    if args.json:
        args.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
