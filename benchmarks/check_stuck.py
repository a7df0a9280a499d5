"""Evidence for the stuck-robot early stop's default (``--navsearch-stuck-after``, issue 13).

    python benchmarks/check_stuck.py                       # shipped seeds + example suites, 3 planners
    python benchmarks/check_stuck.py --search-budget 300   # + the failing episodes of a search

1. Runs every scenario under scenarios/ and examples/ (the frozen suites) against each planner
   with the early stop off and measures, from the trajectory at the control ticks, the longest
   *stall* of every episode under two "no progress" measures:
   * ``cell``: no new square of sim.episode.STUCK_CELL entered (what the episode checks);
   * ``route``: the farthest point reached along the scenario's shortest route (verdict.paths)
     grew by less than STUCK_CELL.
   A stop with window T changes an outcome only where an episode that did not time out stalled
   for T or longer, so the shortest safe window is the longest such stall plus one tick.
2. Runs them all again with each window of ``--stuck-after`` (default: the engine's
   DEFAULT_STUCK_AFTER) and compares the outcomes with the first run: exit status 1 on any
   difference with the first window.
3. With ``--search-budget N``: the timeouts of a search around boxes1 against dwa (shrinking
   off, stop off), and how much simulated time each measure would save on them at its own
   shortest safe window.
"""
from __future__ import annotations

import argparse
import glob
import math
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
PLANNERS = ("dwa", "potential-field", "examples.gap_follower:FollowTheGap")


def scenario_files() -> list[str]:
    pats = ("scenarios/*.yaml", "examples/scenarios/*.yaml", "examples/pictures/suite/*/*.yaml")
    return sorted(f for p in pats for f in glob.glob(os.path.join(ROOT, p)))


MEASURES = ("cell", "cell-0.5", "cell-1.0", "disc-0.5", "disc-1.0", "route")


def stalls(traj, route) -> dict[str, np.ndarray]:
    """Per checked control tick, the seconds since the last progress under each measure (the
    episode checks ticks 0 .. n-1 before it acts; the tick that reaches the goal is not checked):
    ``cell``: a new STUCK_CELL square (what the episode does), ``cell-S``: a new square of S m;
    ``disc-R``: the robot got more than R m from where it last made progress; ``route``: the
    farthest point reached along ``route`` grew by STUCK_CELL."""
    from pytest_navscenario.sim.episode import STUCK_CELL

    t, tick_t = np.asarray(traj.t), np.asarray(traj.tick_t)
    if not len(tick_t):
        return {m: np.zeros(0) for m in MEASURES}
    xy = np.asarray(traj.pose)[np.searchsorted(t, tick_t - 1e-9), :2]
    out = {}
    for name, size in (("cell", STUCK_CELL), ("cell-0.5", 0.5), ("cell-1.0", 1.0)):
        seen, last, s = set(), 0, []
        for k, (x, y) in enumerate(xy):
            cell = (math.floor(x / size), math.floor(y / size))
            if cell not in seen:
                seen.add(cell)
                last = k
            s.append(tick_t[k] - tick_t[last])
        out[name] = np.array(s)
    for name, r in (("disc-0.5", 0.5), ("disc-1.0", 1.0)):
        ax, ay, last, s = xy[0, 0], xy[0, 1], 0, []
        for k, (x, y) in enumerate(xy):
            if math.hypot(x - ax, y - ay) > r:
                ax, ay, last = x, y, k
            s.append(tick_t[k] - tick_t[last])
        out[name] = np.array(s)
    best, last, s = -math.inf, 0, []
    for k, (x, y) in enumerate(xy):
        d = route.fraction(x, y) * route.length
        if d >= best + STUCK_CELL or k == 0:
            best, last = d, k
        s.append(tick_t[k] - tick_t[last])
    out["route"] = np.array(s)
    return out


def run_matrix(planners, stuck_after):
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search.fitness import Route

    rows = []
    for path in scenario_files():
        sc = load_scenario(path)
        route = Route(sc)
        for planner in planners:
            res = run_scenario(sc, planner, stuck_after=stuck_after)
            rows.append({"file": os.path.relpath(path, ROOT), "planner": planner, "outcome": res.outcome.value,
                         "duration": res.metrics.duration, "stalls": stalls(res.trajectory, route)})
    return rows


def shortest_safe(rows, measure: str) -> tuple[float, dict]:
    """(longest stall of an episode that did not time out, that episode)."""
    worst, who = 0.0, {}
    for r in rows:
        s = r["stalls"][measure]
        if r["outcome"] != "timeout" and len(s) and s.max() > worst:
            worst, who = float(s.max()), r
    return worst, who


def search_timeouts(budget: int) -> list[dict]:
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search.engine import run_search
    from pytest_navscenario.search.fitness import Route
    from pytest_navscenario.subjects.loading import load_subject

    seed = load_scenario(os.path.join(ROOT, "scenarios", "boxes1.yaml"))
    report = run_search(seed, load_subject("dwa"), budget=budget, shrink_budget=0, stuck_after=None)
    route = Route(seed)
    rows = []
    for c in report.candidates:
        if c.outcome != "timeout":
            continue
        res = run_scenario(c.scenario, "dwa")
        rows.append({"file": f"boxes1 candidate {c.sim}", "planner": "dwa", "outcome": res.outcome.value,
                     "duration": res.metrics.duration, "stalls": stalls(res.trajectory, route),
                     "tick_t": np.asarray(res.trajectory.tick_t)})
    return rows


def main() -> int:
    from pytest_navscenario.search.engine import DEFAULT_STUCK_AFTER

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--planners", default=",".join(PLANNERS))
    ap.add_argument("--stuck-after", type=lambda v: [float(x) for x in v.split(",")], default=[DEFAULT_STUCK_AFTER],
                    help="windows to check, comma-separated (default: the engine's default); the exit "
                         "status is 1 when the first one changes an outcome")
    ap.add_argument("--search-budget", type=int, default=0)
    a = ap.parse_args()
    planners = a.planners.split(",")
    c0 = time.process_time()
    plain = run_matrix(planners, None)
    n_ok = sum(r["outcome"] != "timeout" for r in plain)
    print(f"{len(plain)} episodes ({len(scenario_files())} scenarios x {len(planners)} planners), stop off: "
          f"{n_ok} did not time out")
    for measure in MEASURES:
        worst, who = shortest_safe(plain, measure)
        print(f"  {measure:<8}: longest stall recovered from {worst:.1f} s ({who.get('planner')} on "
              f"{who.get('file')}, {who.get('outcome')}): a window of {worst + 0.1:.1f} s or more changes "
              f"no outcome")
    diffs = 0
    for window in a.stuck_after:
        early = run_matrix(planners, window)
        diff = [(p["file"], p["planner"], p["outcome"], e["outcome"]) for p, e in zip(plain, early)
                if p["outcome"] != e["outcome"]]
        stopped = sum(e["duration"] < p["duration"] - 1e-9 for p, e in zip(plain, early))
        print(f"with --navsearch-stuck-after {window:g}: {len(diff)} outcome(s) differ, {stopped} episode(s) "
              f"ended early, simulated {sum(p['duration'] for p in plain):.0f} s -> "
              f"{sum(e['duration'] for e in early):.0f} s")
        for d in diff:
            print("  DIFFERS:", *d)
        diffs += len(diff) if window == a.stuck_after[0] else 0
    if a.search_budget:
        rows = search_timeouts(a.search_budget)
        print(f"search around boxes1 vs dwa, budget {a.search_budget}, stop off: {len(rows)} timeouts")
        for measure in MEASURES:
            window = shortest_safe(plain, measure)[0] + 0.1
            for w in sorted({window, *a.stuck_after}):
                full = sum(r["duration"] for r in rows)
                short, n = 0.0, 0
                for r in rows:
                    hit = np.nonzero(r["stalls"][measure] >= w - 1e-9)[0]
                    short += float(r["tick_t"][hit[0]]) if len(hit) else r["duration"]
                    n += bool(len(hit))
                print(f"  {measure:<8} window {w:4.1f} s: {n}/{len(rows)} stopped early, simulated {full:.0f} s "
                      f"-> {short:.0f} s ({short / max(full, 1e-9):.0%})")
    print(f"CPU {time.process_time() - c0:.0f} s")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
