"""Localisation drift and latency: what the planner is handed differs from the truth.

The episode's true state (the safety layer, the mission, the recorded trajectory, the verdict) is
never changed; only the observation the planner gets and when its commands take effect:

* drift: the planner's pose is the true pose plus an error that is a random walk, seeded per episode
  (its own stream of the episode seed, apart from the lidar's): each tick the position error takes a
  Gaussian step of variance ``drift_per_metre**2 * metres + drift_per_second**2 * seconds`` per axis
  (the distance the robot travelled and the time since the last tick), the heading error one of
  variance ``yaw_drift_per_metre**2 * metres`` (degrees). The believed poses are recorded for the
  pictures (``Trajectory.believed``).
* latency: the planner gets the observation of ``observation`` seconds ago (the first one until
  then), and the setpoint it answered takes effect ``command`` seconds later (the robot holds still
  until the first one does).
"""
from __future__ import annotations

import math

import numpy as np

from ..scenario.model import Scenario
from ..subjects.protocol import Observation

TWO_PI = 2.0 * math.pi
HOLD = (0.0, 0.0, 0.0)


class Faults:
    """The localisation error and delays of one episode (see the module docstring)."""

    def __init__(self, scenario: Scenario, seed: int, seen: np.ndarray, tick_period: float):
        loc, lat = scenario.robot.localisation, scenario.robot.latency
        rate = scenario.simulation.control_rate
        self.drift = loc.drifts
        self.per_metre, self.per_second = float(loc.drift_per_metre), float(loc.drift_per_second)
        self.yaw_per_metre = math.radians(loc.yaw_drift_per_metre)
        self.rng = (np.random.Generator(np.random.PCG64([int(seed) & 0xFFFFFFFFFFFFFFFF, 0x10CA1]))
                    if self.drift else None)
        self.error = [0.0, 0.0, 0.0]
        self.last: tuple[float, float] | None = None
        self.seen = seen                    # the episode's rows of what the planner sees (writable base)
        self.believed: list[tuple[float, float, float]] = []
        self.tick_period = tick_period
        self.obs_delay = int(round(lat.observation * rate))
        self.cmd_delay = int(round(lat.command * rate))
        self.history: list[Observation] = []
        self.pending: list[tuple[float, float, float]] = []

    def observation(self, tick: int, state: tuple[float, ...], obs: Observation) -> Observation:
        """What the planner is handed at ``tick``: the observation with the drifted pose, as it was
        ``observation`` seconds ago."""
        if self.drift:
            _, x, y, yaw = state[:4]
            moved = 0.0 if self.last is None else math.hypot(x - self.last[0], y - self.last[1])
            elapsed = 0.0 if self.last is None else self.tick_period
            self.last = (x, y)
            sd = math.sqrt(self.per_metre ** 2 * moved + self.per_second ** 2 * elapsed)
            step = self.rng.normal(0.0, 1.0, 3)
            self.error[0] += sd * step[0]
            self.error[1] += sd * step[1]
            self.error[2] += self.yaw_per_metre * math.sqrt(moved) * step[2]
            believed = (x + self.error[0], y + self.error[1],
                        (yaw + self.error[2] + math.pi) % TWO_PI - math.pi)
            self.seen[tick, :3] = believed
            self.believed.append(believed)
        if not self.obs_delay:
            return obs
        self.history.append(obs)
        return self.history[max(0, tick - self.obs_delay)]

    def applied(self, setpoint: tuple[float, float, float]) -> tuple[float, float, float]:
        """The setpoint that takes effect now: the one answered ``command`` seconds ago."""
        if not self.cmd_delay:
            return setpoint
        self.pending.append(setpoint)
        k = len(self.pending) - 1 - self.cmd_delay
        return self.pending[k] if k >= 0 else HOLD

    def believed_poses(self) -> np.ndarray | None:
        """(ticks, 3) believed poses, or None without drift."""
        return np.array(self.believed, dtype=float).reshape(-1, 3) if self.drift else None
