"""Where a search's episodes spend their CPU time, per control tick (issue 13's speed target).

    nice python benchmarks/bench_search_ticks.py                 # budget 1000 around boxes1 vs dwa
    nice python benchmarks/bench_search_ticks.py --every 4 --digest /tmp/digests.txt

Runs one search (evolve, search seed 0, shrinking on, as ``bench_search.py --part speed``), then
re-simulates every ``--every``-th of its candidates (search and shrink phases, in order) with the
episode's phase timers reading CPU time instead of wall time, and prints microseconds of CPU per
control tick: the whole episode (world, planner reset, metrics included), physics, lidar rays,
planner, safety layer, the rest of the loop ("harness", which holds the safety layer), metrics.
``--digest FILE`` writes one hash per episode of its trajectory, outcome and message: two
checkouts that write the same file simulate the same bits (paired with
``check_bit_identical.py``, which covers the shipped scenarios and the misbehaving planners).
"""
from __future__ import annotations

import argparse
import collections
import hashlib
import os
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)


def episode_digest(res) -> str:
    """A hash of an episode's trajectory bits, outcome and message: equal digests, same episode."""
    h = hashlib.sha256()
    traj = res.trajectory
    for key in ("t", "pose", "velocity", "tick_t", "command", "ranges"):
        h.update(getattr(traj, key).tobytes())
    h.update(repr((res.outcome.value, res.message)).encode())
    return h.hexdigest()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", default="boxes1")
    ap.add_argument("--subject", default="dwa")
    ap.add_argument("--budget", type=int, default=1000)
    ap.add_argument("--every", type=int, default=4, help="re-simulate every N-th candidate")
    ap.add_argument("--digest", default=None, help="write one trajectory hash per episode here")
    a = ap.parse_args()

    import pytest_navscenario.sim.episode as episode
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search.engine import DEFAULT_STUCK_AFTER, run_search
    from pytest_navscenario.subjects.loading import load_subject

    print(f"load average before: {os.getloadavg()}")
    seed = load_scenario(os.path.join(ROOT, "scenarios", f"{a.seed}.yaml"))
    report = run_search(seed, load_subject(a.subject), budget=a.budget, seed_value=0)
    picked = report.candidates[::a.every]
    episode.perf_counter = time.process_time        # the phase timers read CPU time from here on
    acc: dict[str, float] = collections.defaultdict(float)
    outcomes: collections.Counter = collections.Counter()
    digests, ticks = [], 0
    for cand in picked:
        c0 = time.process_time()
        res = run_scenario(cand.scenario, a.subject, stuck_after=DEFAULT_STUCK_AFTER)
        acc["episode"] += time.process_time() - c0
        for key, value in res.timings.items():
            acc[key] += value
        traj = res.trajectory
        ticks += len(traj.tick_t)
        outcomes[res.outcome.value] += 1
        digests.append(episode_digest(res)[:16])
    print(f"{a.seed} vs {a.subject}, budget {a.budget}: {len(picked)} of {len(report.candidates)} episodes "
          f"re-simulated, {ticks} ticks, outcomes {dict(outcomes)}")
    print("CPU us per tick: " + ", ".join(f"{k} {v / max(ticks, 1) * 1e6:.1f}" for k, v in acc.items()))
    print(f"load average after: {os.getloadavg()}")
    if a.digest:
        with open(a.digest, "w") as f:
            f.write("\n".join(digests) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
