"""The planner protocol: what a subject under test sees each tick and what it must answer.

A planner is any object with::

    reset(self, scenario: Scenario) -> None        # once per episode, before the first tick
    act(self, obs: Observation) -> Command          # once per control tick

and optionally ``name`` / ``version`` string attributes (copied into the results file).
Angles here are in **radians** (YAML scenarios use degrees; see scenario.py).
A subject is named as ``package.module:Attribute``: a class or a zero-argument factory that
returns a fresh planner; the harness calls it once per episode.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, NamedTuple, Protocol, runtime_checkable

from .errors import SubjectLoadError
from .scenario import Obstacle, Scenario

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

    @property
    def target(self) -> np.ndarray:
        """The next point to drive to: the first remaining waypoint, else the goal position."""
        return self.waypoints[0] if len(self.waypoints) else self.goal[:2]


@runtime_checkable
class Planner(Protocol):
    def reset(self, scenario: Scenario) -> None: ...

    def act(self, obs: Observation) -> Any: ...


PlannerFactory = Callable[[], Planner]

BUILTIN_SUBJECTS = {
    "dwa": "pytest_navscenario.planners.dwa:DynamicWindowPlanner",
    "potential-field": "pytest_navscenario.planners.potential_field:PotentialFieldPlanner",
}
DEFAULT_SUBJECT = "dwa"


def load_subject(spec: str) -> PlannerFactory:
    """Resolve ``package.module:Attribute``, a built-in name such as ``dwa``, or
    ``exec:PROGRAM [ARGS]`` (an external planner, see exec_subject.py) to a planner factory.

    Raises SubjectLoadError with what is wrong and how to fix it.
    """
    spec = spec.strip()
    if spec.startswith("exec:"):
        from .exec_subject import exec_factory
        return exec_factory(spec[len("exec:"):].strip())
    target = BUILTIN_SUBJECTS.get(spec, spec)
    if ":" not in target:
        raise SubjectLoadError(
            f"subject {spec!r} is not of the form 'package.module:Attribute' "
            f"(built-in subjects: {', '.join(sorted(BUILTIN_SUBJECTS))})")
    module_name, _, attr_path = target.partition(":")
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # ImportError, or an error raised by the module's own code
        raise SubjectLoadError(
            f"subject {spec!r}: cannot import module {module_name!r}: {type(exc).__name__}: {exc} "
            f"(is it installed, or on sys.path / the rootdir?)") from exc
    obj: Any = module
    for part in attr_path.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            public = sorted(n for n in dir(module) if not n.startswith("_"))
            raise SubjectLoadError(
                f"subject {spec!r}: module {module_name!r} has no attribute {attr_path!r} "
                f"(it has: {', '.join(public[:20])})") from None
    if not callable(obj):
        raise SubjectLoadError(
            f"subject {spec!r}: {attr_path!r} is a {type(obj).__name__}, not a class or factory")
    return obj


def subject_identity(planner: Any, spec: str) -> tuple[str, str | None]:
    """(name, version) of a planner for reports: its ``name``/``version`` attributes or the spec."""
    name = getattr(planner, "name", None) or spec
    version = getattr(planner, "version", None)
    return str(name), (str(version) if version is not None else None)
