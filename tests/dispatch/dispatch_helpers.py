"""Shared by the dispatch tests: a bitwise comparison of episode results, and test planners that
let a test find and kill the worker process running a chosen episode."""
from __future__ import annotations

import pickle
from dataclasses import fields
from typing import Any

MEASURED = {"wall_time", "timings"}   # durations measured in the worker: never the same twice


def assert_same_bits(a: Any, b: Any) -> None:
    """Every field of two EpisodeResults (measured durations aside) has the same bits: floats
    (NaN included) and arrays compared through their pickled bytes."""
    assert type(a) is type(b)
    for f in fields(a):
        if f.name in MEASURED:
            continue
        x, y = getattr(a, f.name), getattr(b, f.name)
        assert pickle.dumps(x) == pickle.dumps(y), f"{f.name} differs: {x!r:.200} vs {y!r:.200}"


# A planner module for kill tests, written into a folder on the workers' path. On the first
# reset of the scenario named "victim" it writes its process id to victim.pid and sleeps, so the
# test can kill that worker mid-episode; every reset appends "pid name node" to resets.log (the log shows
# the victim started twice, in two processes). Otherwise it drives straight at its target.
KILLABLE_PLANNER = '''
import math, os, time

LOG_DIR = {log_dir!r}


class Planner:
    name = "killable"

    def reset(self, scenario):
        try:
            import ray
            node = ray.get_runtime_context().get_node_id() if ray.is_initialized() else "-"
        except ImportError:
            node = "-"
        with open(os.path.join(LOG_DIR, "resets.log"), "a") as fh:
            fh.write(f"{{os.getpid()}} {{scenario.name}} {{node}}\\n")
        marker = os.path.join(LOG_DIR, "victim.pid")
        if scenario.name == "victim" and not os.path.exists(marker):
            with open(marker + ".tmp", "w") as fh:
                fh.write(str(os.getpid()))
            os.replace(marker + ".tmp", marker)
            time.sleep(60)

    def act(self, obs):
        x, y, yaw = obs.pose
        tx, ty = obs.target
        c, s = math.cos(yaw), math.sin(yaw)
        return (c * (tx - x) + s * (ty - y), -s * (tx - x) + c * (ty - y), 0.0)
'''


def scenario_text(name: str, x: float) -> str:
    """A short scenario (2 m, a crate beside the line at ``x``); distinct per ``x``."""
    return (f"version: 1\nname: {name}\n"
            "mission: {start: {x: 0, y: 0, yaw: 90}, goal: {x: 0, y: 2, yaw: 90}, timeout: 6}\n"
            f"obstacles: [{{type: box, name: crate, x: {x}, y: 1, length: 0.5, width: 0.5}}]\n")
