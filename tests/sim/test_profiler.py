"""MuJoCo's profiler (the ``mjcb_time`` timer its bindings install) is off while episodes run,
alone or in a batch, and put back after: a third of a small world's physics step, and it never
changes a bit of the physics (sim/profiler.py)."""
from __future__ import annotations

import contextlib
import os
import threading

import mujoco

import pytest_navscenario.sim.episode as episode_module
import pytest_navscenario.sim.batching.lockstep as lockstep_module
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.sim import profiler
from pytest_navscenario.sim.batching.batch import BatchEpisode, simulate_batch
from pytest_navscenario.sim.episode import simulate
from pytest_navscenario.subjects.planners.dwa import DynamicWindowPlanner

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ARRAYS = ("t", "pose", "velocity", "tick_t", "command", "ranges")


def boxes1():
    return load_scenario(os.path.join(ROOT, "scenarios", "boxes1.yaml"))


class Watching(DynamicWindowPlanner):
    """dwa that notes, at every call, whether MuJoCo's timer callback is installed."""

    def __init__(self):
        super().__init__()
        self.timer_on = set()

    def act(self, obs):
        self.timer_on.add(profiler._slot().value is not None)
        return super().act(obs)

    def act_batch(self, ids, observations):
        self.timer_on.add(profiler._slot().value is not None)
        return super().act_batch(ids, observations)


def test_episodes_run_with_the_profiler_off_and_put_it_back():
    slot = profiler._slot()
    assert slot is not False, "MuJoCo's mjcb_time global was not found"
    mujoco.MjData(mujoco.MjModel.from_xml_string("<mujoco/>"))     # the bindings' timer is installed
    before = slot.value
    assert before is not None
    alone, batch = Watching(), Watching()
    simulate(boxes1(), alone, 0, max_ticks=5)
    assert slot.value == before
    simulate_batch([BatchEpisode(boxes1(), 0, max_ticks=5)] * 2, batch)
    assert slot.value == before
    assert alone.timer_on == {False} and batch.timer_on == {False}


def test_overlapping_episodes_in_threads_leave_the_profiler_as_it_was():
    slot = profiler._slot()
    before = slot.value
    threads = [threading.Thread(target=simulate, args=(boxes1(), DynamicWindowPlanner(), k), kwargs={"max_ticks": 20})
               for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert slot.value == before


def test_the_physics_is_the_same_bits_with_the_profiler_on(monkeypatch):
    sc = boxes1()
    off = simulate(sc, DynamicWindowPlanner(), 0)
    off_batch = simulate_batch([BatchEpisode(sc, 0)], DynamicWindowPlanner())[0]
    monkeypatch.setattr(episode_module, "profiler_off", contextlib.nullcontext)
    monkeypatch.setattr(lockstep_module, "profiler_off", contextlib.nullcontext)
    on = simulate(sc, DynamicWindowPlanner(), 0)
    on_batch = simulate_batch([BatchEpisode(sc, 0)], DynamicWindowPlanner())[0]
    for a, b in ((off, on), (off_batch, on_batch), (off, off_batch)):
        assert all(getattr(a.trajectory, k).tobytes() == getattr(b.trajectory, k).tobytes() for k in ARRAYS)
        assert (a.end, a.ticks) == (b.end, b.ticks)
