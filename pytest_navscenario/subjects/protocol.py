"""The planner protocol: what a subject under test sees each tick and what it must answer.

A planner is any object with::

    reset(self, scenario: Scenario) -> None        # once per episode, before the first tick
    act(self, obs: Observation) -> Command          # once per control tick

and optionally ``name`` / ``version`` string attributes (copied into the results file).
Angles here are in **radians** (YAML scenarios use degrees; see the scenario model).

A planner may also implement the **batch protocol** (``BatchPlanner``), so that the harness can
run many episodes in lockstep with one planner call per tick for all of them (sim/batching/batch.py)::

    reset_batch(self, scenarios: Sequence[Scenario]) -> None
        # once per batch; episode i is scenarios[i] (its id)
    act_batch(self, ids: Sequence[int], observations: Sequence[Observation]) -> commands
        # once per control tick, for the episodes still running: ids ascending, observations[k]
        # is episode ids[k]'s; returns one command per id, in the same order: a sequence of
        # Commands (or 3-sequences), or an array of shape (len(ids), 3)

One planner object serves the whole batch (the harness makes it with the subject's factory, once
per batch). Observations come as a list, not stacked arrays: the episodes of one batch may be
different scenarios (beam counts, fields of view, waypoints, maps), and each ``Observation`` is
exactly what ``act`` would get, so a batched planner can reuse its single code; one that wants
stacked arrays (a learned policy) stacks what it needs itself (``np.stack([o.ranges for o in
observations])``), one call. Episodes end at different ticks: an episode that ended is not in
later calls (ids are never renumbered). What a failing call means: ``reset_batch`` that raises
fails every episode of the batch; ``act_batch`` that raises, overruns or answers the wrong number
of commands fails the episodes of that call (subject-error at that tick), the others ended before
and keep their results; one bad command (NaN, wrong length) fails its own episode only. The tick
limit of a batch call is the limit times the number of episodes in it (the time they would have
had one at a time). A planner that kills its process takes the batch's worker with it; the
dispatcher then runs that batch's episodes one at a time, so only the episode whose call kills
the process fails. A planner with only the batch methods still runs alone, as a batch of one
(``SingleFromBatch``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, NamedTuple, Protocol, Sequence, runtime_checkable

from ..scenario.model import Obstacle, Scenario

if TYPE_CHECKING:  # numpy is not imported at plugin load: only episodes need it
    import numpy as np


class Command(NamedTuple):
    """Velocity command in the robot frame: vx forward (m/s), vy left (m/s), wz (rad/s).

    A differential-drive robot cannot move sideways: its ``vy`` is ignored by the drive.
    A planner may also return any length-3 sequence of finite floats.
    """
    vx: float
    vy: float = 0.0
    wz: float = 0.0


@dataclass(frozen=True)
class Observation:
    """What the planner sees at one control tick (arrays are read-only)."""
    tick: int                     # 0, 1, 2, ...
    time: float                   # s since the episode started
    pose: np.ndarray              # (3,) x, y (m), yaw (rad) in the world frame
    velocity: np.ndarray          # (3,) vx, vy (m/s), wz (rad/s) in the robot frame, measured
    ranges: np.ndarray            # (beams,) m; no return reads as lidar.range_max
    angles: np.ndarray            # (beams,) rad, beam directions in the robot frame
    goal: np.ndarray              # (3,) x, y, yaw (rad) of the final goal
    waypoints: np.ndarray         # (k, 2) remaining intermediate waypoints, in order (k may be 0)
    obstacles: tuple[Obstacle, ...]  # static map, for planners that use one (YAML units)
    # Added with terrain (issue 25); planners that ignore them work as before.
    points: np.ndarray | None = None  # (N, 3) float32 3D lidar returns (m) in the sensor's frame
                                      # (x forward, z up; robot.lidar3d's mount), ring by ring; None
                                      # without robot.lidar3d
    attitude: np.ndarray | None = None  # (2,) roll, pitch (rad) of the robot's base (an IMU; pitch
                                        # positive nose down); (0, 0) for the planar body

    @property
    def target(self) -> np.ndarray:
        """The next point to drive to: the first remaining waypoint, else the goal position."""
        return self.waypoints[0] if len(self.waypoints) else self.goal[:2]


@runtime_checkable
class Planner(Protocol):
    def reset(self, scenario: Scenario) -> None: ...

    def act(self, obs: Observation) -> Any: ...


PlannerFactory = Callable[[], Planner]


@runtime_checkable
class BatchPlanner(Protocol):
    """The batch protocol (see the module docstring): one planner for a batch of episodes."""

    def reset_batch(self, scenarios: Sequence[Scenario]) -> None: ...

    def act_batch(self, ids: Sequence[int], observations: Sequence[Observation]) -> Any: ...


def is_batch_planner(planner: Any) -> bool:
    """True if ``planner`` answers the batch protocol (both methods callable)."""
    return callable(getattr(planner, "reset_batch", None)) and callable(getattr(planner, "act_batch", None))


class SingleFromBatch:
    """A planner with only the batch methods, run alone: ``reset`` is ``reset_batch([scenario])``,
    ``act`` is ``act_batch([0], [obs])``'s one command. Its ``name`` and ``version`` are the
    wrapped planner's."""

    def __init__(self, planner: Any):
        self.planner = planner
        self.name = getattr(planner, "name", None)
        self.version = getattr(planner, "version", None)

    def reset(self, scenario: Scenario) -> None:
        self.planner.reset_batch([scenario])

    def act(self, obs: Observation) -> Any:
        answer = self.planner.act_batch([0], [obs])
        if len(answer) != 1:
            raise ValueError(f"act_batch answered {len(answer)} commands for 1 episode")
        return answer[0]
