"""Episodes per second of the warp batch engine (MuJoCo Warp) for batch sizes 1 to 4096, against the
CPU batch engine, and how closely the two agree (issue 27, docs/how-to/gpu-batches.md).

On a GPU machine, one command (after ``pip install -e ".[gpu]"``):

    python benchmarks/bench_gpu_batch.py

Without a GPU Warp runs its kernels on the CPU, slowly; small sizes and short episodes are enough
to check it end to end:

    python benchmarks/bench_gpu_batch.py --device cpu --sizes 1,4,16 --ticks 50 --agreement-ticks 20

A batch of size N is N variants of one seed scenario (default scenarios/boxes1.yaml), each
obstacle moved by up to ``--jitter`` metres (seeded), as a search's candidates are: they share one
device model. The planner is the built-in dwa, batched (one act_batch call a tick). Per size it
prints the warp engine's episodes per second (wall time, and the process's CPU seconds), and up
to ``--cpu-max`` episodes the CPU engine's on the same batch, the ratio, and the agreement of the
two runs. Then the agreement on every shipped seed (scenarios/, examples/): outcomes, positions and
headings at every physics step, against harness.agreement.AGREE. The first batch of each kind
loads (or compiles, the first time on a machine) Warp's kernels: timed apart, as "warm-up".
"""
from __future__ import annotations

import argparse
import glob
import os
import random
import sys
import time
from dataclasses import replace

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from pytest_navscenario.harness.agreement import AGREE, compare, summary  # noqa: E402
from pytest_navscenario.harness.batch import batch_planner_of  # noqa: E402
from pytest_navscenario.scenario.loader import load_scenario  # noqa: E402
from pytest_navscenario.sim.batching.batch import BatchEpisode, batch_engine  # noqa: E402
from pytest_navscenario.subjects.loading import make_planner  # noqa: E402

DEFAULT_SIZES = "1,2,4,8,16,32,64,128,256,512,1024,2048,4096"


def variants(seed_path: str, n: int, jitter: float, rng_seed: int = 0) -> list:
    """``n`` variants of the seed: its obstacles moved by up to ``jitter`` m each (seeded)."""
    sc = load_scenario(seed_path)
    rng = random.Random(rng_seed)
    out = []
    for k in range(n):
        obstacles = tuple(replace(o, x=o.x + rng.uniform(-jitter, jitter), y=o.y + rng.uniform(-jitter, jitter))
                          for o in sc.obstacles)
        out.append(replace(sc, name=f"{sc.name}-{k}", obstacles=obstacles))
    return out


def run(engine, scenarios, ticks: int | None):
    """(results, wall seconds, CPU seconds) of one batch of ``scenarios`` on ``engine``."""
    planner = batch_planner_of(make_planner("dwa")[0])
    requests = [BatchEpisode(sc, sc.simulation.seed + k, max_ticks=ticks) for k, sc in enumerate(scenarios)]
    w0, c0 = time.perf_counter(), time.process_time()
    results = engine.run(requests, planner)
    return results, time.perf_counter() - w0, time.process_time() - c0


def where_time_went(results, wall: float) -> str:
    """The batch's wall time split: the device (physics, contacts, rays and read-back), the
    planner's calls, and the rest (the host's per-episode work: observations, safety, records)."""
    done = [r for r in results if not isinstance(r, Exception)]
    device = sum(r.timings.get("physics", 0.0) + r.timings.get("rays", 0.0) for r in done)
    planner = sum(r.timings.get("planner", 0.0) for r in done)
    ticks = max((r.ticks for r in done), default=0)
    per_tick = f", {1000 * device / ticks:.2f} ms of device time a tick" if ticks else ""
    return (f"wall {wall:.2f} s: device {device:.2f} s{per_tick}, planner {planner:.2f} s, "
            f"host bookkeeping {max(0.0, wall - device - planner):.2f} s")


def agreement_rows(cpu, warp, names):
    rows, errors = [], []
    for name, a, b in zip(names, cpu, warp):
        if isinstance(a, Exception) or isinstance(b, Exception):
            errors.append(f"{name}: cpu {a!r:.100} / warp {b!r:.100}")
            continue
        rows.append(compare(a, b, name))
    return rows, errors


def shipped() -> list[str]:
    return (sorted(glob.glob(os.path.join(ROOT, "scenarios", "*.yaml")))
            + sorted(glob.glob(os.path.join(ROOT, "examples", "scenarios", "*.yaml")))
            + sorted(glob.glob(os.path.join(ROOT, "examples", "pictures", "suite", "*", "*.yaml"))))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default=DEFAULT_SIZES, help=f"batch sizes, comma separated (default {DEFAULT_SIZES})")
    ap.add_argument("--device", default=None, help="Warp device: cuda:0, cpu... (default: Warp's, the first GPU)")
    ap.add_argument("--seed", default=os.path.join(ROOT, "scenarios", "boxes1.yaml"), help="the seed scenario")
    ap.add_argument("--jitter", type=float, default=0.25, help="m an obstacle of a variant moves at most")
    ap.add_argument("--ticks", type=int, default=None, help="end each episode after this many ticks (default: "
                                                            "run it to its end)")
    ap.add_argument("--cpu-max", type=int, default=64, help="largest size also run on the CPU engine (default 64)")
    ap.add_argument("--agreement", choices=("shipped", "none"), default="shipped",
                    help="compare the engines on every shipped seed (default) or not")
    ap.add_argument("--agreement-ticks", type=int, default=None, help="end those episodes after this many ticks")
    ap.add_argument("--no-graph", action="store_true", help="no CUDA graph capture of a tick (GPU only)")
    args = ap.parse_args(argv)

    from pytest_navscenario.sim.batching.warp_engine import WarpEngine, missing
    why = missing()
    if why is not None:
        print(f"the warp engine cannot run: {why}")
        return 2
    import warp as wp
    import mujoco_warp

    device = wp.get_device(args.device)
    warp = WarpEngine(str(device), graph=not args.no_graph)
    cpu = batch_engine("cpu")
    sizes = [int(s) for s in args.sizes.split(",") if s.strip()]
    print(f"command: python benchmarks/bench_gpu_batch.py {' '.join(argv if argv is not None else sys.argv[1:])}")
    print(f"device: {device} ({'GPU' if device.is_cuda else 'CPU kernels: CPU figures, not GPU ones'}); "
          f"warp {wp.config.version}, mujoco_warp {getattr(mujoco_warp, '__version__', '?')}; "
          f"load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"batch: variants of {os.path.relpath(args.seed, ROOT)} (obstacles moved up to {args.jitter} m), "
          f"dwa batched, episodes {'to their end' if args.ticks is None else f'of at most {args.ticks} ticks'}")

    _, wall, _ = run(warp, variants(args.seed, 1, args.jitter), 2)
    print(f"warm-up (Warp's kernels loaded or compiled): {wall:.1f} s")

    print(f"{'size':>6} {'warp ep/s':>10} {'warp wall s':>11} {'warp CPU s':>10} {'cpu ep/s':>9} {'cpu CPU s':>10} "
          f"{'warp/cpu':>8}  agreement with the CPU engine (ep/s: wall; warp/cpu: wall time ratio)")
    for n in sizes:
        scenarios = variants(args.seed, n, args.jitter)
        res_w, wall_w, cpu_w = run(warp, scenarios, args.ticks)
        line = f"{n:>6} {n / wall_w:>10.2f} {wall_w:>11.2f} {cpu_w:>10.2f}"
        split = where_time_went(res_w, wall_w)
        if n <= args.cpu_max:
            res_c, wall_c, cpu_c = run(cpu, scenarios, args.ticks)
            rows, errors = agreement_rows(res_c, res_w, [s.name for s in scenarios])
            line += f" {n / wall_c:>9.2f} {cpu_c:>10.2f} {wall_c / wall_w:>8.2f}  {summary(rows)}"
            if errors:
                line += f"; {len(errors)} error(s): {errors[0]}"
        else:
            line += f" {'-':>9} {'-':>10} {'-':>8}  (above --cpu-max)"
        print(line, flush=True)
        print(f"{'':>6} {split}", flush=True)

    if args.agreement == "shipped":
        names, scenarios, refused = [], [], []
        for path in shipped():
            sc = load_scenario(path)
            reason = warp.unsupported(sc)
            if reason is None:
                names.append(os.path.relpath(path, ROOT))
                scenarios.append(sc)
            else:
                refused.append(f"{os.path.relpath(path, ROOT)}: {reason}")
        res_c, _, _ = run(cpu, scenarios, args.agreement_ticks)
        res_w, wall_w, _ = run(warp, scenarios, args.agreement_ticks)
        rows, errors = agreement_rows(res_c, res_w, names)
        print(f"shipped seeds ({len(scenarios)} on the warp engine in one batch, {wall_w:.1f} s; "
              f"{len(refused)} refused, run on the CPU): {summary(rows)}")
        for r in rows:
            if not r.within(AGREE):
                print(f"  outside the tolerance: {r.describe()}")
        for e in errors + refused:
            print(f"  {e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
