"""Episodes in batches (issue 27): what batching saves, paired with the same work unbatched.

    nice python benchmarks/bench_batch.py search --budget 1000 --repeats 2   # the search, both ways
    nice python benchmarks/bench_batch.py episodes --count 128 --batch 16      # per-part CPU per tick
    nice python benchmarks/bench_batch.py planner --batch 16                   # dwa: act against act_batch
    nice python benchmarks/bench_batch.py physics                               # rollout, threads, mj_step

``search``: the search of ``bench_search.py --part speed`` (boxes1 vs dwa, evolve, search seed 0,
shrinking on, the engine's stuck window) run unbatched (--nav-batch 1) and batched
(search/batched.batch_evaluator, ``--batch`` episodes at most), alternately, ``--repeats`` pairs in
one process; CPU seconds of each, the ratio per pair and the median ratio; each pair's two reports
must be the same search (every candidate's offsets, outcome, metrics, signature; the failures and
their shrinks), else the script exits 1.

``episodes``: ``--count`` search-like candidates of boxes1 (every parameter drawn at random within
half its bounds, valid ones kept) run alone and in batches of ``--batch``, chunk by chunk
alternately, against dwa and against a planner that replays dwa's commands and costs nothing (the
same trajectories, checked; the free planner answers tuples, as planners do); CPU per control tick
of the four; then, in runs of their own with timers (process_time) on the engine's parts, where a
batched episode-tick goes, with dwa and with the free planner: the episodes' start, the cohorts'
observation (the lidar scan and MuJoCo's mj_multiRay inside it), the planner call, the commands,
the physics (MuJoCo's rollout call inside it), the results, and the tick loop's rest.

``planner``: dwa alone, on the recorded observations of ``--batch`` episodes: ``act`` per episode
against ``act_batch`` per tick, replayed to fresh planners (no simulation between the calls).

``free``: only the batches of ``episodes`` with the free planner (``--count`` candidates, batches of
``--batch``, ``--repeats`` runs, the least CPU per episode-tick printed): to pair two versions of
the engine, run it alternately with ``--code`` pointing at each checkout (the package is imported
from there; the candidates and the replayed commands are this script's)::

    for i in 1 2 3 4 5; do python benchmarks/bench_batch.py free --code /tmp/old; \
        python benchmarks/bench_batch.py free; done

``physics``: MuJoCo alone for a batch of 8 boxes1 episodes x 100 ticks of 10 steps: a plain
``mj_step`` loop recording every state, ``mj_step(nstep=10)``, ``mujoco.rollout`` (1 and 2 threads:
CPU and wall), each with MuJoCo's profiler on (the bindings' default) and off (as episodes run it,
sim/profiler.py).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)


def _fingerprint(report) -> str:
    cands = [(c.phase, c.sim, c.origin, c.offsets, c.outcome, repr(c.clearance), c.culprit, c.message,
              c.scenario_hash, c.signature, repr(sorted(c.metrics.items()))) for c in report.candidates]
    fails = [(f.found.sim, f.shrunk.phase, f.shrunk.sim, f.shrink_sims, f.note) for f in report.failures]
    return json.dumps([cands, fails], default=repr)


def part_search(budget: int, repeats: int, batch: int) -> int:
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search.batched import batch_evaluator
    from pytest_navscenario.search.engine import run_search
    from pytest_navscenario.subjects.loading import load_subject

    seed = load_scenario(os.path.join(ROOT, "scenarios", "boxes1.yaml"))
    rows, bad = [], 0
    for rep in range(repeats):
        pair = {}
        for mode in ("unbatched", "batched"):
            ev = batch_evaluator() if mode == "batched" else None
            c0, t0 = time.process_time(), time.perf_counter()
            r = run_search(seed, load_subject("dwa"), budget=budget, seed_value=0, evaluator=ev,
                           batch=batch if mode == "batched" else 1)
            pair[mode] = (time.process_time() - c0, time.perf_counter() - t0, _fingerprint(r), r)
            print(f"  pair {rep + 1} {mode}: {pair[mode][0]:.1f} s CPU, {pair[mode][1]:.1f} s wall, "
                  f"{r.sims_used} + {r.shrink_sims} simulations, {len(r.failures)} failures"
                  + (f"; {r.batching}" if r.batching else ""), flush=True)
        same = pair["unbatched"][2] == pair["batched"][2]
        bad += not same
        rows.append((pair["unbatched"][0], pair["batched"][0], same))
    ratios = [a / b for a, b, _ in rows]
    print(f"search budget {budget} (+ shrinking) boxes1 vs dwa: unbatched median "
          f"{statistics.median(a for a, _, _ in rows):.1f} s CPU, batched (--nav-batch {batch}) "
          f"{statistics.median(b for _, b, _ in rows):.1f} s CPU; ratio per pair "
          f"{', '.join(f'{x:.2f}' for x in ratios)}, median {statistics.median(ratios):.2f}x; "
          f"same search both ways: {sum(s for _, _, s in rows)} of {len(rows)} pairs")
    return 1 if bad else 0


def _candidates(count: int):
    import numpy as np

    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search.space import SearchSpace, invalid_reason

    seed = load_scenario(os.path.join(ROOT, "scenarios", "boxes1.yaml"))
    space = SearchSpace(seed)
    rng = np.random.default_rng(0)
    out = []
    while len(out) < count:
        sc = space.apply(tuple(float(rng.uniform(p.lo, p.hi)) * 0.5 for p in space.params))
        if invalid_reason(sc) is None:
            out.append(sc)
    return out


def part_episodes(count: int, batch: int) -> int:
    from pytest_navscenario.sim.batching.batch import BatchEpisode, simulate_batch
    from pytest_navscenario.sim.episode import simulate
    from pytest_navscenario.subjects.planners.dwa import DynamicWindowPlanner

    scenarios = _candidates(count)
    cpu = {"alone": 0.0, "batched": 0.0, "alone, free planner": 0.0, "batched, free planner": 0.0}
    ticks = 0
    ratios, free_ratios = [], []
    chunks = []
    for rep in range(2):
        for a in range(0, len(scenarios), batch):
            chunk = scenarios[a:a + batch]
            c0 = time.process_time()
            res = [simulate(s, DynamicWindowPlanner(), 0, stuck_after=15.0) for s in chunk]
            c1 = time.process_time()
            batched = simulate_batch([BatchEpisode(s, 0, stuck_after=15.0) for s in chunk], DynamicWindowPlanner())
            c2 = time.process_time()
            commands = [[tuple(c) for c in r.trajectory.command.tolist()] for r in res]   # tuples, as planners answer
            c3 = time.process_time()
            free = [simulate(s, Replay(cmd), 0, stuck_after=15.0) for s, cmd in zip(chunk, commands)]
            c4 = time.process_time()
            free_b = simulate_batch([BatchEpisode(s, 0, stuck_after=15.0) for s in chunk], ReplayBatch(commands))
            c5 = time.process_time()
            same = all(x.trajectory.pose.tobytes() == y.trajectory.pose.tobytes() == z.trajectory.pose.tobytes()
                       == w.trajectory.pose.tobytes() for x, y, z, w in zip(res, batched, free, free_b))
            if not same:
                print("DIFFERENT TRAJECTORIES: the comparison is void")
                return 1
            cpu["alone"] += c1 - c0
            cpu["batched"] += c2 - c1
            cpu["alone, free planner"] += c4 - c3
            cpu["batched, free planner"] += c5 - c4
            ticks += sum(r.ticks for r in res)
            ratios.append((c1 - c0) / (c2 - c1))
            free_ratios.append((c4 - c3) / (c5 - c4))
            if rep == 0:
                chunks.append((chunk, commands))
    per = 1e6 / ticks
    print(f"{count} candidates x 2, batches of {batch}, {ticks} episode-ticks (the same trajectories every way):")
    for key, seconds in cpu.items():
        print(f"  {key}: {seconds * per:.1f} us CPU per episode-tick")
    print(f"  median ratio per chunk, alone / batched: dwa {statistics.median(ratios):.2f}x, "
          f"free planner {statistics.median(free_ratios):.2f}x")
    _where_it_goes(chunks, ticks // 2)
    return 0


def _where_it_goes(chunks, ticks: int) -> None:
    """The batches once more, with timers on the engine's parts (process_time; the timers add
    about 1 us an episode-tick, so these runs are apart from the paired ones above)."""
    import mujoco

    import pytest_navscenario.sim.batching.cohort as cohort
    import pytest_navscenario.sim.batching.lockstep as lockstep
    from pytest_navscenario.sim.batching.batch import BatchEpisode, simulate_batch
    from pytest_navscenario.subjects.planners.dwa import DynamicWindowPlanner

    acc: dict[str, float] = {}
    clock = time.process_time

    def timed(owner, name, label):
        fn = getattr(owner, name)

        def wrapper(*a, **k):
            c0 = clock()
            try:
                return fn(*a, **k)
            finally:
                acc[label] = acc.get(label, 0.0) + clock() - c0
        setattr(owner, name, wrapper)

    class Rollout:      # MuJoCo's own time inside the cohort's physics
        def __init__(self, inner):
            self.inner = inner

        def rollout(self, *args):
            c0 = clock()
            self.inner.rollout(*args)
            acc["  of which mujoco.rollout (C)"] = acc.get("  of which mujoco.rollout (C)", 0.0) + clock() - c0

    cast = mujoco.mj_multiRay

    def multi_ray(*args):   # MuJoCo's own time of the lidar casts (the timer adds ~0.2 us a call)
        c0 = clock()
        cast(*args)
        acc["  of which mj_multiRay (C)"] = acc.get("  of which mj_multiRay (C)", 0.0) + clock() - c0

    cohort._ROLLOUT = Rollout(cohort._rollout_pool())
    mujoco.mj_multiRay = multi_ray
    timed(lockstep.Lockstep, "_act", "planner (act_batch)")
    timed(cohort.Cohort, "observe", "observation: mission, lidar, safety layer (cohorts)")
    timed(cohort.Cohort, "_scan", "  of which the lidar scan")
    timed(cohort.Cohort, "step", "physics (cohorts)")
    timed(lockstep.Lockstep, "_setpoint", "commands validated, limited, recorded")
    timed(lockstep.Lockstep, "_start", "start: episodes built, placed, reset_batch")
    timed(lockstep.Lockstep, "_form_cohorts", "start: cohorts formed")
    timed(lockstep.Lockstep, "_finish", "end: results (trajectories trimmed)")
    per = 1e6 / ticks
    for name, make in (("dwa", lambda commands: DynamicWindowPlanner()), ("free planner", ReplayBatch)):
        acc.clear()
        c0 = clock()
        for chunk, commands in chunks:
            simulate_batch([BatchEpisode(s, 0, stuck_after=15.0) for s in chunk], make(commands))
        total = (clock() - c0) * per
        print(f"  where a batched episode-tick goes, {name}: {total:.1f} us with the timers, of which")
        for label in ORDER:
            if label in acc:
                print(f"    {label}: {acc[label] * per:.1f} us")
        top = sum(v for k, v in acc.items() if not k.startswith("  ")) * per
        print(f"    the rest (the tick loop: ids, cohorts' turns, sorting): {total - top:.1f} us")


ORDER = ("start: episodes built, placed, reset_batch", "start: cohorts formed",
         "observation: mission, lidar, safety layer (cohorts)", "  of which the lidar scan",
         "  of which mj_multiRay (C)", "planner (act_batch)", "commands validated, limited, recorded",
         "physics (cohorts)", "  of which mujoco.rollout (C)", "end: results (trajectories trimmed)")


class Replay:
    """A planner that answers each tick with a recorded command: no planning cost at all."""

    def __init__(self, commands):
        self.commands = commands

    def reset(self, scenario):
        pass

    def act(self, obs):
        return self.commands[obs.tick]


class ReplayBatch:
    """``Replay`` for a batch (episode i replays ``commands[i]``)."""

    def __init__(self, commands):
        self.commands = commands

    def reset_batch(self, scenarios):
        pass

    def act_batch(self, ids, observations):
        return [self.commands[i][obs.tick] for i, obs in zip(ids, observations)]


def part_planner(count: int, batch: int) -> int:
    """dwa alone: the observations of a batch's episodes recorded once, then replayed to fresh
    planners: act per episode against act_batch per tick (the planner's own cost, no simulation
    between the calls)."""
    from pytest_navscenario.sim.batching.batch import BatchEpisode, simulate_batch
    from pytest_navscenario.subjects.planners.dwa import DynamicWindowPlanner

    class Recording(DynamicWindowPlanner):
        def act_batch(self, ids, observations):
            log.append((list(ids), list(observations)))
            return super().act_batch(ids, observations)

    scenarios = _candidates(count)[:batch]
    log: list = []
    simulate_batch([BatchEpisode(s, 0, stuck_after=15.0) for s in scenarios], Recording())
    n = sum(len(ids) for ids, _ in log)

    def single():
        planners = [DynamicWindowPlanner() for _ in scenarios]
        for p, s in zip(planners, scenarios):
            p.reset(s)
        c0 = time.process_time()
        for ids, observations in log:
            for i, obs in zip(ids, observations):
                planners[i].act(obs)
        return time.process_time() - c0

    def batched():
        planner = DynamicWindowPlanner()
        planner.reset_batch(scenarios)
        c0 = time.process_time()
        for ids, observations in log:
            planner.act_batch(ids, observations)
        return time.process_time() - c0

    a, b = [], []
    for _ in range(5):
        a.append(single())
        b.append(batched())
    print(f"dwa on the recorded observations of {len(scenarios)} episodes ({n} episode-ticks, {len(log)} "
          f"calls): act {statistics.median(a) / n * 1e6:.1f} us per episode-tick, act_batch "
          f"{statistics.median(b) / n * 1e6:.1f} us (median of 5 paired runs, ratio "
          f"{statistics.median(x / y for x, y in zip(a, b)):.2f}x)")
    return 0


def part_physics() -> int:
    import mujoco
    import numpy as np
    from mujoco import _rollout

    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.sim.world import compiled_world

    sc = load_scenario(os.path.join(ROOT, "scenarios", "boxes1.yaml"))
    model = compiled_world(sc).model
    k, ticks, spt = 8, 100, 10
    nstate = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)

    def datas():
        out = []
        for _ in range(k):
            d = mujoco.MjData(model)
            d.qpos[:] = (sc.mission.start.x, sc.mission.start.y, 0.0)
            d.ctrl[:] = (0.5, 0.0, 0.1)
            mujoco.mj_step1(model, d)
            out.append(d)
        return out

    def plain():
        ds = datas()
        bufs = [(np.empty((ticks * spt + 1, 3)), np.empty((ticks * spt + 1, 3))) for _ in ds]
        for t in range(ticks):
            for d, (pb, qb) in zip(ds, bufs):
                mujoco.mj_step2(model, d)
                i = t * spt + 1
                pb[i], qb[i] = d.qpos, d.qvel
                for _ in range(spt - 1):
                    mujoco.mj_step(model, d)
                    i += 1
                    pb[i], qb[i] = d.qpos, d.qvel
                mujoco.mj_step1(model, d)

    def nstep():
        for t in range(ticks):
            for d in ds_n:
                mujoco.mj_step(model, d, nstep=spt)

    def roll(threads):
        pool = _rollout.Rollout(nthread=threads)
        scratch = [mujoco.MjData(model) for _ in range(max(1, threads))]
        state0 = np.zeros((k, nstate))
        mujoco.mj_getState(model, datas()[0], state0[0], mujoco.mjtState.mjSTATE_FULLPHYSICS)
        state0[:] = state0[0]
        control = np.tile([0.5, 0.0, 0.1], (k, spt + 1, 1))
        states, sens = np.empty((k, spt + 1, nstate)), np.empty((k, spt + 1, model.nsensordata))
        for _ in range(ticks):
            pool.rollout([model] * k, scratch, spt + 1, int(mujoco.mjtState.mjSTATE_CTRL), state0, None, control,
                         states, sens, None)
            state0[:] = states[:, spt - 1]
        del pool

    ds_n = datas()
    rows = [("plain mj_step loop, every state recorded", plain), (f"mj_step(nstep={spt})", nstep),
            (f"mujoco.rollout, {spt} + 1 steps (the batch engine's)", lambda: roll(0)),
            ("mujoco.rollout, 2 threads", lambda: roll(2))]
    import contextlib

    from pytest_navscenario.sim.profiler import profiler_off

    for label, fn in rows:
        for profiler, scope in (("on", contextlib.nullcontext), ("off", profiler_off)):
            cpu, wall = [], []
            for _ in range(3):
                with scope():
                    c0, t0 = time.process_time(), time.perf_counter()
                    fn()
                    cpu.append(time.process_time() - c0)
                    wall.append(time.perf_counter() - t0)
            n = k * ticks
            print(f"{label}, MuJoCo's profiler {profiler}: {statistics.median(cpu) / n * 1e6:.1f} us CPU, "
                  f"{statistics.median(wall) / n * 1e6:.1f} us wall per episode-tick")
    return 0


def part_free(count: int, batch: int, repeats: int) -> int:
    from pytest_navscenario.sim.batching.batch import BatchEpisode, simulate_batch
    from pytest_navscenario.sim.episode import simulate
    from pytest_navscenario.subjects.planners.dwa import DynamicWindowPlanner

    scenarios = _candidates(count)
    commands = [[tuple(c) for c in simulate(s, DynamicWindowPlanner(), 0, stuck_after=15.0).trajectory.command.tolist()]
                for s in scenarios]
    ticks = sum(len(c) for c in commands)
    runs = []
    for _ in range(repeats):
        c0 = time.process_time()
        for a in range(0, count, batch):
            simulate_batch([BatchEpisode(s, 0, stuck_after=15.0) for s in scenarios[a:a + batch]],
                           ReplayBatch(commands[a:a + batch]))
        runs.append(time.process_time() - c0)
    import pytest_navscenario
    print(f"free planner, batches of {batch}, {count} candidates, {ticks} episode-ticks: "
          f"{min(runs) / ticks * 1e6:.2f} us CPU per episode-tick (least of {repeats}; "
          f"package {os.path.dirname(os.path.dirname(pytest_navscenario.__file__))})")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("part", choices=("search", "episodes", "planner", "physics", "free"))
    ap.add_argument("--code", help="import pytest_navscenario from this checkout (default: this one)")
    ap.add_argument("--budget", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--batch", type=int, default=16)
    ap.add_argument("--count", type=int, default=128)
    a = ap.parse_args()
    if a.code:
        sys.path.insert(0, os.path.abspath(a.code))
    print(f"load average before: {os.getloadavg()}", flush=True)
    if a.part == "search":
        code = part_search(a.budget, a.repeats, a.batch)
    elif a.part == "episodes":
        code = part_episodes(a.count, a.batch)
    elif a.part == "planner":
        code = part_planner(a.count, a.batch)
    elif a.part == "free":
        code = part_free(a.count, a.batch, a.repeats)
    else:
        code = part_physics()
    print(f"load average after: {os.getloadavg()}")
    return code


if __name__ == "__main__":
    sys.exit(main())
