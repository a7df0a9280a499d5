"""What a budget-1000 search would cost with a planner that costs nothing (issue 13's 15 s target).

    nice python benchmarks/check_floor.py                  # boxes1 vs dwa, budget 1000, as --part speed
    nice python benchmarks/check_floor.py --budget 200     # quicker, same shape

Runs the search of ``bench_search.py --part speed`` (evolve, search seed 0, shrinking on, the
engine's stuck window) and times its CPU. Then re-simulates every candidate it simulated (search
and shrink phases) twice:

1. against the planner, recording its commands: the episodes' share of the search's CPU; the rest
   is the search's own work (Hypothesis drawing and shrinking, validity checks, fitness, hashes);
2. against a planner that replays those commands and costs nothing (the same trajectory bits,
   checked per episode): what the same episodes cost the harness alone (world, physics, lidar,
   safety layer, loop, metrics).

And, per candidate, MuJoCo's own C time for the same number of physics steps (one ``mj_step`` call
with ``nstep``) and lidar scans (``mj_multiRay`` calls), the part no change in Python can remove
at this timestep, control rate and beam count. The printed floor is what the whole search would
cost if the planner were free: episodes with the replay planner plus the search's own work.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

from bench_search_ticks import episode_digest   # benchmarks/ is on the path when run as a script

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)


class Replay:
    """A planner that answers each tick with a recorded command: no planning cost at all."""

    def __init__(self, commands: np.ndarray):
        self.commands = commands.tolist()

    def reset(self, scenario) -> None:
        pass

    def act(self, obs):
        return self.commands[obs.tick]


def _mujoco_alone(scenario, steps: int, ticks: int) -> tuple[float, float]:
    """CPU s of ``steps`` physics steps (one call) and ``ticks`` lidar scans on this world, from
    the start pose: MuJoCo's C time at the episode's size, without the loop around it."""
    import mujoco

    from pytest_navscenario.sim.lidar import Lidar
    from pytest_navscenario.sim.world import compiled_world

    try:      # episodes run with MuJoCo's profiler off (sim/profiler.py): so is its C time here
        from pytest_navscenario.sim.profiler import profiler_off
    except ImportError:     # a checkout from before it
        from contextlib import nullcontext as profiler_off

    world = compiled_world(scenario)
    d = world.take_data()
    try:
        start = scenario.mission.start
        d.qpos[:] = (start.x, start.y, start.yaw_rad)
        lidar = Lidar(scenario, world, d, 1, 0)
        args = (world.model, d, lidar.pnt, lidar.dirs_flat, lidar.groups, 1, lidar.body, lidar.geom,
                lidar.dist, None, lidar.beams, lidar.range_max)
        ray = mujoco.mj_multiRay
        with profiler_off():
            c0 = time.process_time()
            mujoco.mj_step(world.model, d, nstep=max(steps, 1))
            c1 = time.process_time()
            for _ in range(ticks):
                ray(*args)
            c2 = time.process_time()
    finally:
        world.give_back(d)
    return c1 - c0, c2 - c1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", default="boxes1")
    ap.add_argument("--subject", default="dwa")
    ap.add_argument("--budget", type=int, default=1000)
    ap.add_argument("--target", type=float, default=15.0, help="the issue's budget, s of CPU")
    a = ap.parse_args()

    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search.engine import DEFAULT_STUCK_AFTER, run_search
    from pytest_navscenario.subjects.loading import load_subject

    print(f"load average before: {os.getloadavg()}")
    seed = load_scenario(os.path.join(ROOT, "scenarios", f"{a.seed}.yaml"))
    c0 = time.process_time()
    report = run_search(seed, load_subject(a.subject), budget=a.budget, seed_value=0)
    search_cpu = time.process_time() - c0
    cands = report.candidates
    planner_cpu = replay_cpu = steps_cpu = rays_cpu = 0.0
    steps = ticks = differ = 0
    per_tick: list[float] = []
    for cand in cands:
        c0 = time.process_time()
        res = run_scenario(cand.scenario, a.subject, stuck_after=DEFAULT_STUCK_AFTER)
        planner_cpu += time.process_time() - c0
        traj = res.trajectory
        c0 = time.process_time()
        rep = run_scenario(cand.scenario, Replay(traj.command), stuck_after=DEFAULT_STUCK_AFTER)
        spent = time.process_time() - c0
        replay_cpu += spent
        differ += episode_digest(rep) != episode_digest(res)
        n_steps, n_ticks = len(traj.t) - 1, len(traj.tick_t)
        steps, ticks = steps + n_steps, ticks + n_ticks
        if n_ticks:
            per_tick.append(spent / n_ticks)
        s, r = _mujoco_alone(cand.scenario, n_steps, n_ticks)
        steps_cpu, rays_cpu = steps_cpu + s, rays_cpu + r
    own = search_cpu - planner_cpu
    floor = replay_cpu + own
    print(f"{a.seed} vs {a.subject}, budget {a.budget}: {len(cands)} simulations ({report.sims_used} "
          f"counted), {ticks} ticks, {steps} physics steps, {steps * seed.simulation.timestep:.0f} s simulated")
    print(f"the search: {search_cpu:.1f} s CPU")
    print(f"  its episodes against {a.subject} (re-simulated): {planner_cpu:.1f} s")
    print(f"  the search's own work (the rest): {own:.1f} s")
    print(f"the same episodes with a free planner (replayed commands; {differ} of {len(cands)} "
          f"trajectories differ): {replay_cpu:.1f} s, median {statistics.median(per_tick) * 1e6:.0f} us a tick")
    print(f"  of which MuJoCo alone, in C: physics {steps_cpu:.1f} s ({steps_cpu / max(steps, 1) * 1e6:.2f} us "
          f"a step), lidar {rays_cpu:.1f} s ({rays_cpu / max(ticks, 1) * 1e6:.1f} us a scan)")
    print(f"floor (free planner + the search's own work): {floor:.1f} s CPU against the {a.target:g} s target"
          f" ({floor / a.target:.2f}x); MuJoCo alone + the search's own work: {steps_cpu + rays_cpu + own:.1f} s")
    print(f"load average after: {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
