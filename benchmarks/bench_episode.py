"""Episode speed: median wall time of one episode per shipped seed x built-in planner, and the
bare-loop floor (the same model, the same number of physics steps and ray casts, nothing else).

    python benchmarks/bench_episode.py [--repeats 21] [--scenarios scenarios/*.yaml]

Columns: ``episode`` = sim.simulate (the control loop), ``run_scenario`` = + oracle and metrics,
``replay`` = the same episode with a trivial planner that replays the recorded commands (same
path, same physics, same safety-layer work: the loop without the planner's cost), ``floor`` =
bare MuJoCo, mj_step + one mj_multiRay per tick for as many ticks and nothing else; then the
shares of the episode: ``physics`` (stepping with per-step contact check and recording), ``rays``,
``planner`` (the planner's own code), ``safety`` and ``harness`` = everything but physics, rays and
the planner (safety layer included: observation, validation, limits, goal checks), each in ms and
the planner's and harness's shares in %. Medians over ``--repeats`` runs, after a warm-up
run (model compiled and cached, as in a search or a suite). Times are CPU time of this process
(time.process_time), which stays meaningful on a machine shared with other jobs; ``wall`` is the
episode's wall-clock median for comparison. Phase shares come from the episode's own perf_counter
timings.
"""
from __future__ import annotations

import argparse
import glob
import math
import os
import statistics
import sys
import time

import mujoco
import numpy as np

from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.subjects.loading import make_planner
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.sim.episode import simulate
from pytest_navscenario.sim.lidar import lidar_angles
from pytest_navscenario.sim.world import LIDAR_HEIGHT, compiled_world, steps_per_tick

PLANNERS = ("dwa", "potential-field")


class Replay:
    """The trivial planner: answers each tick with the command the real planner's run applied."""

    def __init__(self, commands):
        self.commands = [tuple(c) for c in commands.tolist()]

    def reset(self, scenario):
        pass

    def act(self, obs):
        return self.commands[obs.tick]


def bare_floor(scenario, ticks: int) -> float:
    """CPU seconds for ``ticks`` control ticks of pure MuJoCo: one multi-ray, then spt mj_steps; NaN
    for a body that rides the ground (its own loop: benchmarks/bench_terrain.py measures it)."""
    from pytest_navscenario.sim.body_world import rides_the_ground

    if rides_the_ground(scenario):
        return math.nan
    world = compiled_world(scenario)
    m = world.model
    d = world.take_data()
    try:
        mission = scenario.mission
        d.qpos[:] = (mission.start.x, mission.start.y, mission.start.yaw_rad)
        d.ctrl[:] = (0.5, 0.0, 0.0)
        mujoco.mj_step1(m, d)
        angles = lidar_angles(scenario)
        n = len(angles)
        vec = np.zeros((n, 3))
        vec[:, 0], vec[:, 1] = np.cos(angles), np.sin(angles)
        vec = vec.reshape(-1)
        pnt = np.array([mission.start.x, mission.start.y, LIDAR_HEIGHT])
        geom, dist = np.empty(n, np.int32), np.empty(n)
        spt = steps_per_tick(scenario)
        rmax = scenario.robot.lidar.range_max
        step, ray = mujoco.mj_step, mujoco.mj_multiRay
        t0 = time.process_time()
        for _ in range(ticks):
            ray(m, d, pnt, vec, None, 1, world.robot_body, geom, dist, None, n, rmax)
            for _ in range(spt):
                step(m, d)
        return time.process_time() - t0
    finally:
        world.give_back(d)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=21)
    ap.add_argument("--scenarios", nargs="*", default=sorted(glob.glob(
        os.path.join(os.path.dirname(__file__), "..", "scenarios", "*.yaml"))))
    args = ap.parse_args(argv)

    print(f"python {sys.version.split()[0]}, mujoco {mujoco.__version__}, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f}, median of {args.repeats} runs")
    head = (f"{'scenario':12s} {'planner':16s} {'outcome':11s} {'sim s':>6s} {'ticks':>5s} "
            f"{'episode':>8s} {'wall':>8s} {'run_scen':>8s} {'replay':>8s} {'floor':>7s} {'physics':>7s} {'rays':>6s} "
            f"{'planner':>7s} {'safety':>6s} {'harness':>7s} {'plan %':>6s} {'harn %':>6s}")
    print(head)
    print("-" * len(head))
    for path in args.scenarios:
        sc = load_scenario(path)
        for spec in PLANNERS:
            res = run_scenario(sc, spec)            # warm-up: compile + cache the model
            ticks = len(res.trajectory.tick_t)
            phases = ("physics", "rays", "planner", "safety", "harness")
            eps, walls, runs, replays, floors = [], [], [], [], []
            parts = {k: [] for k in phases}      # share of the episode's own wall time
            absolute = {k: [] for k in phases}   # seconds (wall, from the episode's timings)
            for _ in range(args.repeats):
                planner, _ = make_planner(spec)
                t0, w0 = time.process_time(), time.perf_counter()
                facts = simulate(sc, planner, sc.simulation.seed)
                eps.append(time.process_time() - t0)
                walls.append(time.perf_counter() - w0)
                for k in parts:
                    parts[k].append(facts.timings[k] / facts.timings["total"])
                    absolute[k].append(facts.timings[k])
                t0 = time.process_time()
                run_scenario(sc, spec)
                runs.append(time.process_time() - t0)
                t0 = time.process_time()
                again = simulate(sc, Replay(facts.trajectory.command), sc.simulation.seed)
                replays.append(time.process_time() - t0)
                assert again.trajectory.pose.tobytes() == facts.trajectory.pose.tobytes(), "replay differs"
                floors.append(bare_floor(sc, ticks))
            share = {k: statistics.median(v) * 100 for k, v in parts.items()}
            ms = {k: statistics.median(v) * 1e3 for k, v in absolute.items()}
            print(f"{sc.name:12s} {spec:16s} {res.outcome.value:11s} {res.trajectory.duration:6.1f} "
                  f"{ticks:5d} {statistics.median(eps) * 1e3:6.2f}ms {statistics.median(walls) * 1e3:6.2f}ms "
                  f"{statistics.median(runs) * 1e3:6.2f}ms {statistics.median(replays) * 1e3:6.2f}ms "
                  f"{statistics.median(floors) * 1e3:5.2f}ms "
                  f"{ms['physics']:5.2f}ms {ms['rays']:4.2f}ms {ms['planner']:5.2f}ms {ms['safety']:4.2f}ms "
                  f"{ms['harness']:5.2f}ms {share['planner']:5.0f}% {share['harness']:5.1f}%")
    print(f"load average after: {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
