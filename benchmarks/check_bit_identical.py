"""Bit-identical episodes across two versions of the code: the check to run after changing the loop.

    python benchmarks/check_bit_identical.py --against /path/to/other/checkout [--show]

Runs a fixed matrix of episodes (every scenario under scenarios/, examples/scenarios/ and
examples/pictures/suite/, against both built-in planners; lidar noise and dropout under several noise
seeds; safety layer off (collisions); diff drive; planners that raise, return NaN or a bad shape;
``max_ticks``; a slow tick under ``tick_limit``; a start inside an obstacle; a planner without
``act``; 0 beams and a partial fov; a divergence; any extra ``--scenario`` files) once with this
checkout and once with the other (``PYTHONPATH=<other>``, in a subprocess), then compares every
``Trajectory`` array byte for byte, the waypoint times, the end, the tick count and the ending event.
Works with the flat layout of before 0.2 and with the layered one. Exit status 1 on any difference.

``--dump FILE`` runs the matrix with the code on ``PYTHONPATH`` only and pickles the facts to FILE.
"""
from __future__ import annotations

import argparse
import dataclasses
import glob
import hashlib
import math
import os
import pickle
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
ARRAYS = ("t", "pose", "velocity", "tick_t", "command", "ranges", "angles")
PLANNERS = ("dwa", "potential-field")


def _imports():
    """(load_scenario, make_planner, simulate, model module) from either layout."""
    try:
        from pytest_navscenario.scenario.loader import load_scenario
        from pytest_navscenario.subjects.loading import make_planner
    except ImportError:            # the flat layout of before 0.2
        from pytest_navscenario.loader import load_scenario
        from pytest_navscenario.runner import make_planner
    import pytest_navscenario.scenario as model
    from pytest_navscenario.sim import simulate
    return load_scenario, make_planner, simulate, model


class Misbehaving:
    """A built-in planner that, from tick ``at`` on, raises, answers ``answer`` or sleeps."""

    def __init__(self, inner, mode: str, at: int = 5):
        self.inner, self.mode, self.at = inner, mode, at

    def reset(self, scenario):
        self.inner.reset(scenario)

    def act(self, obs):
        if obs.tick >= self.at:
            if self.mode == "raise":
                raise ZeroDivisionError(f"planner bug at tick {obs.tick}")
            if self.mode == "nan":
                return (float("nan"), 0.0, 0.0)
            if self.mode == "shape":
                return [0.1, 0.2]
            if self.mode == "slow" and obs.tick == self.at:
                time.sleep(0.3)
        return self.inner.act(obs)


class NoAct:
    def reset(self, scenario):
        pass


class Constant:
    def __init__(self, cmd):
        self.cmd = cmd

    def reset(self, scenario):
        pass

    def act(self, obs):
        return self.cmd


def _with(sc, **robot_parts):
    robot = sc.robot
    parts = {}
    for name, changes in robot_parts.items():
        value = getattr(robot, name)
        parts[name] = dataclasses.replace(value, **changes) if isinstance(changes, dict) else changes
    return dataclasses.replace(sc, robot=dataclasses.replace(robot, **parts))


UNLOADABLE: list[str] = []     # scenario files the code under test cannot load (newer format)


def cases(extra: list[str]):
    """(name, scenario, planner factory, seed, keyword arguments) of every episode of the matrix."""
    load_scenario, make_planner, _, model = _imports()

    def builtin(spec):
        return lambda: make_planner(spec)[0]

    shipped = sorted(glob.glob(os.path.join(ROOT, "scenarios", "*.yaml")))
    files = shipped + sorted(glob.glob(os.path.join(ROOT, "examples", "scenarios", "*.yaml"))) \
        + sorted(glob.glob(os.path.join(ROOT, "examples", "pictures", "suite", "*", "*.yaml"))) + extra
    for path in files:
        try:
            sc = load_scenario(path)
        except Exception:     # a scenario of a newer format (e.g. moving obstacles) in an older version
            UNLOADABLE.append(os.path.relpath(path, ROOT))
            continue
        for spec in PLANNERS:
            yield f"{os.path.relpath(path, ROOT)}|{spec}", sc, builtin(spec), sc.simulation.seed, {}
    for path in shipped:
        if os.path.relpath(path, ROOT) in UNLOADABLE:
            continue
        sc = load_scenario(path)
        base = os.path.basename(path)
        noisy = _with(sc, lidar={"noise_sigma": 0.03, "dropout": 0.05})
        for spec in PLANNERS:
            for seed in (0, 1, 12345, 2 ** 63 + 5):
                yield f"{base}|{spec}|noise seed {seed}", noisy, builtin(spec), seed, {}
            yield f"{base}|{spec}|safety off", _with(sc, safety={"enabled": False}), builtin(spec), 0, {}
            yield f"{base}|{spec}|diff drive", _with(sc, drive="diff"), builtin(spec), 0, {}
            for mode in ("raise", "nan", "shape"):
                yield (f"{base}|{spec}|planner {mode}s", sc,
                       lambda spec=spec, mode=mode: Misbehaving(make_planner(spec)[0], mode), 0, {})
        yield f"{base}|max_ticks 7", sc, builtin("dwa"), 0, {"max_ticks": 7}
        if sc.obstacles:                 # at the first obstacle: a safety stop, or a collision
            ob, st = sc.obstacles[0], sc.mission.start
            heading = math.atan2(ob.y - st.y, ob.x - st.x) - math.radians(st.yaw)
            at = (0.8 * math.cos(heading), 0.8 * math.sin(heading), 0.0)
            for safety in (True, False):
                yield (f"{base}|at {ob.name}, safety {'on' if safety else 'off'}",
                       _with(sc, safety={"enabled": safety}), lambda at=at: Constant(at), 0, {})
    sc = load_scenario(shipped[0])
    yield ("slow tick under tick_limit", sc, lambda: Misbehaving(make_planner("dwa")[0], "slow", 2), 0,
           {"tick_limit": 0.05})
    start = sc.mission.start
    under = model.BoxObstacle("under", start.x, start.y, 1.0, 1.0)
    yield "start inside an obstacle", dataclasses.replace(sc, obstacles=(under,)), builtin("dwa"), 0, {}
    yield "planner without act", sc, NoAct, 0, {}
    yield "0 beams", _with(sc, lidar={"beams": 0}), lambda: Constant((0.5, 0.0, 0.0)), 0, {}
    yield "partial fov", _with(sc, lidar={"beams": 31, "fov": 120.0}), builtin("dwa"), 0, {}
    blowup = _with(sc, limits={"max_speed": 1e12, "max_accel": 1e30})
    yield "divergence", blowup, lambda: Constant((1e12, 0.0, 0.0)), 0, {}


NEWER_EVENT_FIELDS = ("robot_speed", "robot_moving", "obstacle_speed", "terrain",   # terrain: issue 25
                      "ground",     # a safety stop before the ground (issue 25): older code has none
                      "yaw_rate")   # the turn rate at a safety stop (issue 32): older code has none


def _event(ev):
    if ev is None:
        return None
    out = dataclasses.asdict(ev)
    for key in NEWER_EVENT_FIELDS:     # who moved in a collision (issue 12): older code has none
        out.pop(key, None)
    if out.get("traceback"):       # file paths differ between checkouts: keep the planner's last line
        last = out["traceback"].strip().splitlines()[-1]     # and modules move: drop the package path
        out["traceback"] = re.sub(r"^[\w.]+\.(\w+):", r"\1:", last)
    return out


def run_matrix(extra: list[str]) -> dict:
    _, _, simulate, _ = _imports()
    facts = {}
    for name, sc, factory, seed, kwargs in cases(extra):
        try:
            res = simulate(sc, factory(), seed, **kwargs)
        except Exception as exc:   # e.g. SimulationDivergedError: compare the type and the text
            facts[name] = {"raised": f"{type(exc).__name__}: {exc}"}
            continue
        traj = res.trajectory
        one = {k: (getattr(traj, k).dtype.str, getattr(traj, k).shape, getattr(traj, k).tobytes())
               for k in ARRAYS}
        one.update(waypoint_times=traj.waypoint_times, end=res.end, ticks=res.ticks,
                   goal_reached=res.goal_reached, collision=_event(res.collision),
                   safety_stop=_event(res.safety_stop), subject_failure=_event(res.subject_failure))
        believed = getattr(traj, "believed", None)     # localisation drift's poses, when it drifts
        if believed is not None:
            one["believed"] = (believed.dtype.str, believed.shape, believed.tobytes())
        facts[name] = one
    return facts


def digest(one: dict) -> str:
    return hashlib.sha256(repr(sorted(one.items())).encode()).hexdigest()[:16]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", help="the other checkout (its root, put on PYTHONPATH)")
    ap.add_argument("--dump", help="run the matrix with the code on PYTHONPATH and pickle it here")
    ap.add_argument("--scenario", action="append", default=[], help="extra scenario file (repeatable)")
    ap.add_argument("--show", action="store_true", help="print every case with its digest")
    args = ap.parse_args(argv)
    if args.dump:
        facts = run_matrix(args.scenario)
        facts["__unloadable__"] = list(UNLOADABLE)
        with open(args.dump, "wb") as f:
            pickle.dump(facts, f)
        return 0
    if not args.against:
        ap.error("give --against DIR (or --dump FILE)")
    mine = run_matrix(args.scenario)
    mine["__unloadable__"] = list(UNLOADABLE)
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "other.pkl")
        env = dict(os.environ, PYTHONPATH=os.path.abspath(args.against))
        cmd = [sys.executable, os.path.abspath(__file__), "--dump", out]
        for extra in args.scenario:
            cmd += ["--scenario", extra]
        subprocess.run(cmd, env=env, check=True)
        with open(out, "rb") as f:
            other = pickle.load(f)
    newer = set(other.pop("__unloadable__", ())) - set(mine.pop("__unloadable__", ()))
    if newer:
        print(f"not comparable (the other version cannot load them): {', '.join(sorted(newer))}")
        names = newer | {os.path.basename(n) for n in newer}
        mine = {k: v for k, v in mine.items() if k.split("|")[0] not in names}
    bad = 0
    for name in sorted(set(mine) | set(other)):
        a, b = mine.get(name), other.get(name)
        diff = [] if a is not None and b is not None else ["missing on one side"]
        if not diff:
            diff = [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
        bad += bool(diff)
        if diff or args.show:
            end = a.get("end") or a.get("raised", "") if a else "?"
            print(f"{'DIFFERS' if diff else 'same':7s} {digest(a) if a else '-':16s} {name} "
                  f"[{end}]" + (f": {', '.join(diff)}" if diff else ""))
    ends: dict[str, int] = {}
    for one in mine.values():
        key = one.get("end") or "raised"
        ends[key] = ends.get(key, 0) + 1
    print(f"{len(mine)} episodes, {bad} differ; ends: "
          + ", ".join(f"{k} {v}" for k, v in sorted(ends.items())))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
