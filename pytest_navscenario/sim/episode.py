"""One episode's front door: ``simulate(scenario, planner, seed)`` runs the scenario's episode (the
planar ``loop.Episode``, or ``riding_episode.RidingEpisode`` for a robot that rides the ground) and
returns its raw facts. The loop itself, its steps and its cost are described in ``loop.py``; the
loop's names are re-exported here, where the rest of the package has always imported them."""
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
