"""What an early end for a robot that can no longer make it in time would save (issue 13).

    python benchmarks/check_reachable.py                  # a budget-1000 search around boxes1 vs dwa
    python benchmarks/check_reachable.py --budget 200 --subject potential-field --seed corridor

An episode cannot end as a success any more once the robot, even at its drive limit, cannot cover
a lower bound of the distance left before the mission's timeout. The bound: straight lines from
the robot to the next waypoint, through the waypoints not passed yet, to the goal, each shortened
by the tolerances at its ends (a waypoint counts when the robot is within its tolerance); the
speed bound: the drive's limit (hypot of the forward and lateral maxima) plus ``--speed-margin``
for the physics, and ``--time-margin`` seconds more. An early end there could only turn a later
collision, safety stop or planner error into a timeout, never a success into a failure.

This script does not change the episode: it runs the search (shrinking included, the engine's
stuck stop on, as the search runs), re-simulates every failing candidate with the same settings,
and reports, from each trajectory at the control ticks, when such a rule would first have ended it
and how much simulated time that saves, against all the simulated time of the search.
"""
from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)


def speed_bound(scenario) -> float:
    """The fastest the drive lets the robot's centre move, m/s (forward and lateral at their limits)."""
    lim = scenario.robot.limits
    lateral = lim.max_lateral_speed if scenario.robot.drive == "omni" else 0.0
    return math.hypot(lim.max_speed, lateral)


def first_unreachable(scenario, traj, speed_margin: float, time_margin: float) -> float | None:
    """The first control tick's time at which the rule would end the episode, or None."""
    m = scenario.mission
    v_bound = speed_bound(scenario) * (1.0 + speed_margin)
    waypoints = [(w.x, w.y) for w in m.waypoints]
    passed = np.asarray(traj.waypoint_times, dtype=float)
    rows = np.minimum(np.searchsorted(traj.t, traj.tick_t - 1e-9), len(traj.pose) - 1)
    for t, row in zip(traj.tick_t, rows):
        left = waypoints[int((passed <= t + 1e-9).sum()):]
        points = [tuple(traj.pose[row, :2])] + left + [(m.goal.x, m.goal.y)]
        tols = [0.0] + [m.waypoint_tolerance] * len(left) + [m.goal_tolerance.position]
        bound = sum(max(0.0, math.dist(a, b) - ta - tb)
                    for a, b, ta, tb in zip(points, points[1:], tols, tols[1:]))
        if bound / v_bound > (m.timeout - t) + time_margin:
            return float(t)
    return None


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", default="boxes1", help="a seed scenario under scenarios/")
    ap.add_argument("--subject", default="dwa")
    ap.add_argument("--budget", type=int, default=1000)
    ap.add_argument("--speed-margin", type=float, default=0.1, help="share added to the speed bound")
    ap.add_argument("--time-margin", type=float, default=0.5, help="seconds added to the time left")
    a = ap.parse_args()

    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search.engine import DEFAULT_STUCK_AFTER, run_search
    from pytest_navscenario.subjects.loading import load_subject

    seed = load_scenario(os.path.join(ROOT, "scenarios", f"{a.seed}.yaml"))
    report = run_search(seed, load_subject(a.subject), budget=a.budget, seed_value=0)
    total = sum(c.metrics.get("duration", 0.0) or 0.0 for c in report.candidates)
    failing, failing_s, saved, cut, fastest = 0, 0.0, 0.0, 0, 0.0
    for c in report.candidates:
        if not c.failed:
            continue
        res = run_scenario(c.scenario, a.subject, stuck_after=DEFAULT_STUCK_AFTER)
        traj = res.trajectory
        speed = np.hypot(traj.velocity[:, 0], traj.velocity[:, 1]).max() if len(traj.velocity) else 0.0
        fastest = max(fastest, speed / speed_bound(c.scenario))
        end = float(traj.t[-1]) if len(traj.t) else 0.0
        failing, failing_s = failing + 1, failing_s + end
        at = first_unreachable(c.scenario, traj, a.speed_margin, a.time_margin)
        if at is not None:
            cut, saved = cut + 1, saved + end - at
    print(f"{a.seed} vs {a.subject}, budget {a.budget} + {report.shrink_sims} shrinking: {total:.0f} s simulated "
          f"in {len(report.candidates)} episodes; {failing} failing episodes, {failing_s:.0f} s simulated")
    print(f"the rule (speed bound +{a.speed_margin:.0%}, {a.time_margin} s margin) would end {cut} of them early "
          f"and save {saved:.0f} s simulated: {saved / max(failing_s, 1e-9):.1%} of the failing episodes' time, "
          f"{saved / max(total, 1e-9):.1%} of the search's")
    print(f"fastest robot speed seen in them: {fastest:.3f} x the drive's speed bound")
    return 0


if __name__ == "__main__":
    sys.exit(main())
