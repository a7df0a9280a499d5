"""What an episode produces: the trajectory the simulation recorded, the events that ended it,
the outcome the oracle assigned and the metrics computed from them. Plain data, no logic."""
from __future__ import annotations

import enum
from dataclasses import dataclass, field, fields
from typing import Any


from ..scenario.model import Scenario
from ..sim.trajectory import Collision, SafetyStop, SubjectFailure, TerrainEvent, Trajectory


class Outcome(str, enum.Enum):
    """Outcome categories, in precedence order (the first that applies wins)."""
    SUBJECT_ERROR = "subject-error"  # the planner raised, returned NaN/wrong shape, or was too slow
    COLLISION = "collision"          # any robot-obstacle contact, or the chassis against a terrain face
    FALL = "fall"                    # the robot fell (off an edge, into a hole) or tipped over (terrain)
    SAFETY_STOP = "safety-stop"      # the safety layer halted the robot
    TIMEOUT = "timeout"              # the goal was not reached in time
    SUCCESS = "success"              # goal (after all waypoints) reached within tolerance, in time

    def __str__(self) -> str:
        return self.value

    @property
    def passed(self) -> bool:
        return self is Outcome.SUCCESS


@dataclass(frozen=True)
class Metrics:
    """Per-episode figures. Distances in m, times in s, yaw error in degrees. NaN = not defined."""
    min_clearance: float              # min distance footprint-obstacle over the run (0 on contact)
    min_clearance_obstacle: str       # which obstacle it was ("" with no obstacles)
    min_clearance_time: float
    min_clearance_x: float            # robot position at that moment
    min_clearance_y: float
    min_obstacle_gap: float           # narrowest obstacle-obstacle gap in the scenario (inf if < 2)
    min_gap_obstacles: str            # "a|b"
    path_length: float
    shortest_path_length: float       # collision-free for the footprint, through the waypoints
    path_efficiency: float            # shortest / (driven + still to go); 1 = optimal (metrics.py)
    max_deviation: float              # from the shortest path
    mean_deviation: float
    duration: float
    mean_speed: float
    goal_position_error: float
    goal_yaw_error: float             # degrees
    smoothness: float                 # mean |jerk| of the planar motion, m/s^3 (lower is smoother)
    angular_smoothness: float         # mean |angular acceleration|, rad/s^2
    reference_mean_deviation: float = float("nan")  # only with a scenario reference trajectory
    reference_max_deviation: float = float("nan")
    max_pitch: float = float("nan")     # degrees, largest |pitch| of the chassis (a body riding the ground)
    max_roll: float = float("nan")      # degrees, largest |roll|
    climb: float = float("nan")         # m, the most the robot rose above its start

    def as_dict(self) -> dict[str, Any]:
        """The fields by name (all plain floats and strings: no deep copy needed, ~7x faster than
        ``dataclasses.asdict``, once per episode record)."""
        return {name: getattr(self, name) for name in _METRIC_NAMES}


_METRIC_NAMES = tuple(f.name for f in fields(Metrics))


@dataclass
class EpisodeResult:
    """Everything one run of one scenario produced."""
    scenario: Scenario
    outcome: Outcome
    metrics: Metrics
    trajectory: Trajectory
    seed: int                                   # the episode's effective noise seed
    subject: str = ""                           # subject name (or spec)
    subject_version: str | None = None
    message: str = ""                           # one line: why this outcome
    collision: Collision | None = None
    safety_stop: SafetyStop | None = None
    subject_failure: SubjectFailure | None = None
    wall_time: float = 0.0                      # s, the whole run_scenario call (+ a feasibility check before it)
    timings: dict[str, float] = field(default_factory=dict)  # s: physics, rays, planner, harness
    terrain_event: TerrainEvent | None = None   # fell, tipped over or stuck on terrain
    left_running: tuple[str, ...] = ()          # processes the planner started and left running ("pid N: cmd")
    error: str | None = None                    # the episode never finished: the exception's type (WorkerDied, ...)

    @property
    def passed(self) -> bool:
        return self.outcome.passed


def headline(outcome: Any, message: str) -> str:
    """"outcome: message", a failure's first line, without saying the outcome twice: some
    messages carry it themselves ("timeout: stuck on terrain ...") since they are read alone too."""
    outcome = str(outcome)
    if not message:
        return outcome
    return message if message.startswith(f"{outcome}:") else f"{outcome}: {message}"
