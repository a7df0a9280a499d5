"""An ONNX multilayer-perceptron policy on the 500-scenario suite, on one core: episodes per second
batched (one inference call per tick for a batch, harness/batch.py) against the same policy called
one episode at a time (run_scenario per episode), paired, CPU time (issue 27: at least 5x).

    env -u PYTHONDONTWRITEBYTECODE python benchmarks/bench_onnx.py [--count 500] [--pairs 3] [--batch 16]
    python benchmarks/bench_onnx.py --part policy      # the policy's own per-tick work only

The policy is built here with the onnx package's graph helpers (tests/subjects/onnx_models.py):
72 inputs (64 lidar beams resampled from the scenario's 72 and clipped to 5 m, the target's
distance and bearing, the velocity, the previous command), two hidden layers of 256 tanh units,
3 tanh outputs scaled by the robot's limits, a dynamic batch dimension. Its weights are random
(Glorot) except for four hidden units that carry a reactive controller through the layers (the
target's distance to vx, its bearing to wz, open space left minus right to vy, space closed ahead
against vx), so that its episodes end as a suite's do (on 40 of the files: 24 successes, 11
timeouts, 5 safety stops), not all in the first second. The suite is bench_suite.py's: the five seeds with their obstacles moved
by up to 0.3 m, 100 each, the same files every run.

``--part suite`` (default, needs the batch engine): the whole suite alone, then batched, ``--pairs``
times alternated (A B A B ...), CPU time of this process pinned to one core (and ONNX Runtime on
one thread); episodes per second of each, the ratio per pair and the median ratio. It checks that
the two runs gave every episode the same trajectory bits, outcome and metrics.

``--part policy``: the policy's own work per tick (observation rows, inference, commands) for a
batch of ``--batch`` episodes: one ``act`` per episode against one ``act_batch``, on observations
recorded from real episodes, paired; what batching saves on the policy's side alone.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "subjects"))    # onnx_models: the tests' model builders
sys.path.insert(0, str(ROOT / "benchmarks"))

DECLARATION = """\
navscenario-policy: 1
name: mlp-bench
observation:
  - lidar: {beams: 64, fov: 360, resample: min, clip: [0.0, 5.0], std: 5.0}
  - target: {form: polar, clip: [[0.0, 10.0], [-3.1416, 3.1416]]}
  - velocity: {components: [vx, vy, wz]}
  - previous_command: {components: [vx, vy, wz]}
action:
  components: [vx, vy, wz]
  clip: [-1.0, 1.0]
  scale: limits
"""


def build_policy(folder: Path, hidden: list[int], seed: int = 0) -> Path:
    """The MLP of the module docstring, written with its declaration; its path."""
    from onnx_models import mlp_model, random_mlp, write_policy

    layers = random_mlp(72, hidden, 3, seed=seed)
    (w0, b0), (wn, bn) = layers[0], layers[-1]
    # hidden units 0-3 carry a reactive controller through the layers (the rest stay random):
    # 0 the target's distance, 1 its bearing, 2 open space on the left minus the right, 3 how
    # closed the space ahead is (beams: 64 from -180 degrees, 5.625 degrees apart; ahead = 32)
    w0[:, :4] = 0.0
    b0[:4] = 0.0
    w0[64, 0], w0[65, 1] = 0.5, 1.0
    w0[38:58, 2], w0[6:26, 2] = 0.3, -0.3
    w0[28:37, 3], b0[3] = -1.0, 6.0
    for w, b in layers[1:-1]:
        w[:, :4] = 0.0
        w[:4, :4] = np.eye(4) * 1.5
        b[:4] = 0.0
    wn[:4, :] = 0.0
    wn[0, 0], wn[1, 2] = 2.0, 2.5
    wn[2, 1], wn[3, 0], wn[3, 1] = 1.5, -2.5, 0.0
    return write_policy(folder, "mlp", mlp_model(layers, final_tanh=True), DECLARATION)


def one_core() -> str:
    """Pin this process to one CPU (the one it runs on): what 'one core' means here."""
    try:
        cpu = sorted(os.sched_getaffinity(0))[-1]
        os.sched_setaffinity(0, {cpu})
        return f"pinned to cpu {cpu}"
    except (AttributeError, OSError):
        return "not pinned (no sched_setaffinity)"


def load_suite(count: int) -> list:
    from bench_suite import generate

    from pytest_navscenario.scenario.loader import load_scenario

    folder = Path(tempfile.mkdtemp(prefix="bench-onnx-suite-"))
    generate(folder, count)
    return [load_scenario(p) for p in sorted(folder.rglob("*.yaml"))]


def fingerprint(result) -> tuple:
    """What must not change with batching: the trajectory's bits, the outcome, the metrics."""
    import hashlib

    if isinstance(result, Exception):
        return ("error", type(result).__name__, str(result))
    h = hashlib.sha256()
    traj = result.trajectory
    for key in ("t", "pose", "velocity", "tick_t", "command", "ranges"):
        h.update(np.ascontiguousarray(getattr(traj, key)).tobytes())
    return (h.hexdigest(), result.outcome.value, repr(result.metrics))


def run_alone(scenarios, spec) -> tuple[float, list]:
    from pytest_navscenario.harness.runner import run_scenario

    t0 = time.process_time()
    out = [run_scenario(s, spec) for s in scenarios]
    return time.process_time() - t0, out


def run_batched(scenarios, spec, batch: int) -> tuple[float, list, str]:
    from pytest_navscenario.harness.batch import Batching, run_batch

    how = Batching()
    t0 = time.process_time()
    out = run_batch(scenarios, spec, batch=batch, batching=how)
    return time.process_time() - t0, out, how.describe()


def part_suite(a: argparse.Namespace, spec: str) -> int:
    try:
        import pytest_navscenario.harness.batch  # noqa: F401
    except ImportError:
        print("suite: not measured: the batch engine (harness/batch.py, sim/batching/batch.py: the 'batch' helper's "
              "branch) is not in this tree; --part policy measures the policy's side alone")
        return 2
    scenarios = load_suite(a.count)
    ticks = None
    print(f"suite: {len(scenarios)} scenarios, batch {a.batch}, {a.pairs} pair(s), CPU time")
    from pytest_navscenario.harness.runner import run_scenario
    run_scenario(scenarios[0], spec)                  # load the model and warm the caches, untimed
    ratios, alone_rates, batch_rates = [], [], []
    reference = None
    for pair in range(a.pairs):
        t_a, res_a = run_alone(scenarios, spec)
        t_b, res_b, how = run_batched(scenarios, spec, a.batch)
        prints_a = [fingerprint(r) for r in res_a]
        prints_b = [fingerprint(r) for r in res_b]
        same = sum(x == y for x, y in zip(prints_a, prints_b))
        if reference is None:
            reference = prints_a
            ticks = sum(len(r.trajectory.tick_t) for r in res_a if not isinstance(r, Exception))
            outcomes: dict[str, int] = {}
            for r in res_a:
                key = type(r).__name__ if isinstance(r, Exception) else r.outcome.value
                outcomes[key] = outcomes.get(key, 0) + 1
            print(f"  episodes: {len(res_a)}, {ticks} control ticks; outcomes {outcomes}")
            print(f"  batched: {how}")
        n = len(scenarios)
        alone_rates.append(n / t_a)
        batch_rates.append(n / t_b)
        ratios.append(t_a / t_b)
        print(f"  pair {pair + 1}: alone {t_a:.2f} s CPU ({n / t_a:.1f} episodes/s), batched {t_b:.2f} s "
              f"({n / t_b:.1f} episodes/s): {t_a / t_b:.2f}x; identical episodes {same}/{n}; "
              f"load {os.getloadavg()[0]:.1f}")
        if same != n:
            bad = [i for i, (x, y) in enumerate(zip(prints_a, prints_b)) if x != y][:5]
            print(f"  DIFFERENT: episodes {bad} (first five)")
    print(f"suite: median alone {statistics.median(alone_rates):.1f} episodes/s, batched "
          f"{statistics.median(batch_rates):.1f} episodes/s, median ratio {statistics.median(ratios):.2f}x "
          f"(min {min(ratios):.2f}x, max {max(ratios):.2f}x)")
    if ticks:
        print(f"  per control tick: alone {1e6 * statistics.median([n / r for r in alone_rates]) / ticks:.0f} us, "
              f"batched {1e6 * statistics.median([n / r for r in batch_rates]) / ticks:.0f} us")
    return 0


class Recorder:
    """Runs the policy and keeps what it saw, for replaying the same observations."""

    def __init__(self, planner):
        self.planner, self.seen = planner, []

    def reset(self, scenario):
        self.planner.reset(scenario)

    def act(self, obs):
        self.seen.append(obs)
        return self.planner.act(obs)


def part_policy(a: argparse.Namespace, spec: str) -> int:
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.subjects.loading import load_subject

    from bench_suite import generate
    from pytest_navscenario.scenario.loader import load_scenario

    folder = Path(tempfile.mkdtemp(prefix="bench-onnx-policy-"))
    generate(folder, a.batch)
    scenarios = [load_scenario(p) for p in sorted(folder.rglob("*.yaml"))][:a.batch]
    factory = load_subject(spec)
    recs = []
    for s in scenarios:
        rec = Recorder(factory())
        run_scenario(s, rec)
        recs.append(rec)
    ticks = min(len(r.seen) for r in recs)
    k = len(recs)
    print(f"policy: {k} episodes, {ticks} ticks each replayed (their shortest), paired, CPU time")
    ratios, alone_us, batch_us = [], [], []
    for pair in range(a.pairs * 3):
        singles = [factory() for _ in recs]
        for p, s in zip(singles, scenarios):
            p.reset(s)
        t0 = time.process_time()
        for t in range(ticks):
            for p, r in zip(singles, recs):
                p.act(r.seen[t])
        t_a = time.process_time() - t0
        batched = factory()
        batched.reset_batch(scenarios)
        ids = list(range(k))
        t0 = time.process_time()
        for t in range(ticks):
            batched.act_batch(ids, [r.seen[t] for r in recs])
        t_b = time.process_time() - t0
        alone_us.append(1e6 * t_a / (ticks * k))
        batch_us.append(1e6 * t_b / (ticks * k))
        ratios.append(t_a / t_b)
    print(f"policy: per episode per tick: alone {statistics.median(alone_us):.1f} us, batched "
          f"{statistics.median(batch_us):.1f} us; median ratio {statistics.median(ratios):.2f}x "
          f"(min {min(ratios):.2f}x, max {max(ratios):.2f}x), load {os.getloadavg()[0]:.1f}")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=["suite", "policy", "both"], default="suite")
    ap.add_argument("--count", type=int, default=500, help="scenarios in the suite (default 500)")
    ap.add_argument("--pairs", type=int, default=3, help="alone/batched pairs (default 3)")
    ap.add_argument("--batch", type=int, default=16, help="episodes per batch (default 16, --nav-batch's)")
    ap.add_argument("--hidden", default="256,256", help="hidden layer sizes (default 256,256)")
    a = ap.parse_args()
    print(f"bench_onnx: {one_core()}, load {os.getloadavg()}")
    folder = Path(tempfile.mkdtemp(prefix="bench-onnx-model-"))
    path = build_policy(folder, [int(h) for h in a.hidden.split(",")])
    spec = str(path)
    print(f"policy: {path} (MLP 72-{a.hidden.replace(',', '-')}-3, tanh, dynamic batch)")
    status = 0
    if a.part in ("policy", "both"):
        status |= part_policy(a, spec)
    if a.part in ("suite", "both"):
        status |= part_suite(a, spec)
    print(f"load after: {os.getloadavg()}")
    return status


if __name__ == "__main__":
    sys.exit(main())
