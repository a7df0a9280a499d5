"""One episode: the control loop that runs a planner against a scenario in the MuJoCo world.

``simulate(scenario, planner, seed)`` runs an ``Episode`` and returns the raw facts (trajectory,
collision, safety stop, planner failure, goal reached, timings); ``harness.runner.run_scenario``
turns them into an outcome and metrics. The episode starts the robot at the start pose and resets
the planner; then each control tick it observes (true state, mission progress, lidar scan), checks
the safety layer, asks the planner to act (under the tick deadline, command validated, drive
limits), records, and steps the physics one step at a time with a contact check after each step.

The loop is the hot path of every suite and search (besides MuJoCo and the planner, ~10 us a tick):
each step is a method that binds its hot values to locals; per-tick facts go into lists,
physics-rate states into preallocated arrays, and the planner sees read-only views of rows written
once. ``benchmarks/bench_episode.py`` measures it, ``benchmarks/check_bit_identical.py`` checks that
a change to it keeps every trajectory's bits.
"""
from __future__ import annotations

from typing import Any

from ..scenario.model import Scenario
from .body_world import rides_the_ground
from .loop import STILL, STUCK_CELL, Episode, EpisodeOver, SimResult  # noqa: F401  (the loop's names, as before)
from .riding_episode import RidingEpisode

__all__ = ["Episode", "EpisodeOver", "RidingEpisode", "SimResult", "simulate"]


def simulate(scenario: Scenario, planner: Any, seed: int, max_ticks: int | None = None, *,
             tick_limit: float | None = None, stuck_after: float | None = None) -> SimResult:
    """Run one episode of ``scenario`` against ``planner`` (an object with reset/act).

    Calls ``planner.reset(scenario)`` first. ``seed`` drives the lidar noise. ``max_ticks`` stops
    after that many planner ticks (for quick protocol checks). ``tick_limit`` (s) makes a slower
    planner tick a subject failure. ``stuck_after`` (s) ends the episode early (``end ==
    "stuck"``, a timeout) when the robot has entered no new STUCK_CELL square for that long.
    Raises SimulationDivergedError if the physics blows up. A robot with a body that rides the
    ground (or any terrain) runs as a ``riding_episode.RidingEpisode``.
    """
    if rides_the_ground(scenario):
        return RidingEpisode(scenario, planner, seed, max_ticks, tick_limit=tick_limit,
                             stuck_after=stuck_after).run()
    return Episode(scenario, planner, seed, max_ticks, tick_limit=tick_limit, stuck_after=stuck_after).run()
