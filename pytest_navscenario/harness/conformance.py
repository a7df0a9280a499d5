"""``check_planner``: run a planner through a few real ticks and report protocol mistakes in
plain words, before a test run turns them into a wall of subject errors (like Gymnasium's
``check_env``).

Problems (the check fails): no reset/act, wrong reset/act signature, reset or act raising,
act returning None / the wrong type / the wrong length / NaN / inf, writing into the
observation's arrays, two fresh instances answering differently to the same observations.
Warnings: commands beyond the robot's limits (the simulation clips them), a sideways command
for a differential drive, slow ticks, no ``name``/``version`` attribute.
"""
from __future__ import annotations

from pathlib import Path

import copy
import dataclasses
import inspect
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.errors import SubjectLoadError
from ..subjects.protocol import Observation
from ..subjects.loading import load_subject
from ..scenario.model import BoxObstacle, CylinderObstacle, Mission, Pose, Scenario

SLOW_TICK = 0.05            # s: a tick slower than this gets a warning (10 Hz control leaves 0.1 s)
HUNG_TICK = 10.0            # s: an act() call this long is stopped and reported as a problem (longer
                            # than sim.deadline.DEFAULT_TICK_LIMIT: a slow tick is measured, not cut short)
LIMIT_SLACK = 1.05          # commands up to 5 % over a limit are not worth a warning
# frames in these folders are the harness's own, not the planner's
_HARNESS_FILES = tuple(str(Path(__file__).resolve().parents[1] / layer) for layer in ("sim", "harness"))
_OBS_ARRAYS = ("pose", "velocity", "ranges", "angles", "goal", "waypoints", "points", "attitude")


@dataclass
class PlannerCheck:
    """What ``check_planner`` found. ``ok`` is False when there is any problem."""
    subject: str
    problems: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    ticks: int = 0                       # act() calls observed
    max_tick_time: float = float("nan")  # s, slowest act()
    median_tick_time: float = float("nan")

    @property
    def ok(self) -> bool:
        return not self.problems

    def __str__(self) -> str:
        head = (f"check_planner({self.subject}): {'OK' if self.ok else 'FAILED'} after "
                f"{self.ticks} tick{'s' if self.ticks != 1 else ''}")
        if self.ticks and math.isfinite(self.max_tick_time):
            head += (f" (act: median {self.median_tick_time * 1e3:.2f} ms, "
                     f"max {self.max_tick_time * 1e3:.2f} ms)")
        lines = [head]
        lines += [f"  problem: {p}" for p in self.problems]
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def raise_if_failed(self) -> "PlannerCheck":
        """Raise SubjectLoadError listing the problems; return self when there are none."""
        if self.problems:
            raise SubjectLoadError(str(self))
        return self


def default_check_scenario() -> Scenario:
    """A short open scenario with a box and a cylinder in lidar range, default robot."""
    return Scenario(
        mission=Mission(start=Pose(0.0, 0.0, 90.0), goal=Pose(0.0, 6.0, 90.0), timeout=10.0),
        obstacles=(BoxObstacle("box", 1.5, 2.5, 1.0, 1.0), CylinderObstacle("cylinder", -1.5, 4.0, 0.5)),
        name="check-planner", description="built-in scenario of check_planner")


class _Recorder:
    """Wraps the planner under check: records each observation (as writable copies, handed
    to the planner so that writes can be detected), each answer and each act() time."""

    def __init__(self, planner: Any):
        self.planner = planner
        self.observations: list[Observation] = []
        self.answers: list[Any] = []
        self.times: list[float] = []
        self.mutated: list[str] = []
        self.reset_called = False

    def reset(self, scenario: Scenario) -> None:
        self.reset_called = True
        self.planner.reset(scenario)

    def act(self, obs: Observation) -> Any:
        self.observations.append(obs)
        mine = _writable_copy(obs)
        t0 = time.perf_counter()
        answer = self.planner.act(mine)
        self.times.append(time.perf_counter() - t0)
        self.answers.append(answer)
        for name in _OBS_ARRAYS:
            if getattr(obs, name) is None:      # points without a 3D lidar
                continue
            if not np.array_equal(getattr(mine, name), getattr(obs, name), equal_nan=True):
                self.mutated.append(f"obs.{name} (tick {obs.tick})")
        return answer


def _writable_copy(obs: Observation) -> Observation:
    return dataclasses.replace(obs, **{name: np.array(getattr(obs, name)) for name in _OBS_ARRAYS
                                       if getattr(obs, name) is not None})


def _make(planner: Any) -> tuple[Any, Any, str]:
    """(instance, factory or None, label) from a spec string, class/factory or instance."""
    if isinstance(planner, str):
        return None, load_subject(planner), planner
    if hasattr(planner, "act") and not isinstance(planner, type):
        return planner, None, type(planner).__qualname__
    if callable(planner):
        label = getattr(planner, "__qualname__", None) or repr(planner)
        return None, planner, label
    raise SubjectLoadError(
        f"check_planner needs a 'package.module:Attribute' string, a class/factory or a planner "
        f"object; got {type(planner).__name__} {planner!r:.60}")


def _instantiate(factory: Any, label: str, check: PlannerCheck) -> Any | None:
    try:
        return factory()
    except Exception as exc:
        check.problems.append(f"calling {label}() to make a planner raised {type(exc).__name__}: {exc} "
                              f"(a subject must be a class or a zero-argument factory)")
        return None


def _signature_problem(obj: Any, method: str, arg: str) -> str | None:
    fn = getattr(obj, method, None)
    if fn is None:
        return (f"the planner ({type(obj).__name__}) has no {method}() method; add "
                f"`def {method}(self, {arg}):`")
    if not callable(fn):
        return f"{type(obj).__name__}.{method} is a {type(fn).__name__}, not a method"
    try:
        inspect.signature(fn).bind(None)
    except TypeError:
        return (f"{type(obj).__name__}.{method}{inspect.signature(fn)} cannot be called with one "
                f"argument; it must be `def {method}(self, {arg}):`")
    except ValueError:  # builtins without a signature: let the run tell
        pass
    return None


def check_planner(planner: Any, scenario: Scenario | None = None, *, ticks: int = 20,
                  seed: int = 0, slow_tick: float = SLOW_TICK,
                  tick_limit: float | None = HUNG_TICK) -> PlannerCheck:
    """Run ``planner`` through ``ticks`` ticks of ``scenario`` (default: a short built-in one)
    in the real simulation and report protocol mistakes in plain words.

    ``planner`` follows the rules of ``run_scenario``: a spec (``"dwa"``, ``"pkg.mod:Planner"``),
    a class or zero-argument factory, or a planner object. With a spec, class or factory a second
    fresh instance replays the same observations to check determinism; an object is deep-copied
    for that (before its first reset). An act() call longer than ``tick_limit`` seconds is
    stopped and reported (None: no limit). Never raises for a broken planner (see
    ``raise_if_failed``); raises SubjectLoadError only when the spec cannot be loaded.
    """
    from ..sim.command import validate_command
    from ..sim.episode import simulate

    scenario = scenario or default_check_scenario()
    instance, factory, label = _make(planner)
    check = PlannerCheck(subject=label)
    if instance is None:
        instance = _instantiate(factory, label, check)
        if instance is None:
            return check
    twin = _twin(instance, factory, label, check)
    bad = [msg for msg in (_signature_problem(instance, "reset", "scenario"),
                           _signature_problem(instance, "act", "obs")) if msg]
    if bad:
        check.problems.extend(bad)
        return check
    recorder = _Recorder(instance)
    facts = simulate(scenario, recorder, seed, max_ticks=ticks, tick_limit=tick_limit)
    check.ticks = len(recorder.observations)
    if recorder.times:
        check.max_tick_time = max(recorder.times)
        check.median_tick_time = float(np.median(recorder.times))

    _check_failure(check, facts.subject_failure, recorder)
    _check_names(check, instance)
    _check_limits(check, scenario, recorder.answers, validate_command)
    _check_speed(check, scenario, recorder.times, slow_tick)
    if twin is not None and facts.subject_failure is None and recorder.observations:
        _check_determinism(check, scenario, twin, recorder, validate_command)
    return check


def _twin(instance: Any, factory: Any, label: str, check: PlannerCheck) -> Any | None:
    """A second fresh planner for the determinism check: from the factory, or a deep copy of
    the object (before its first reset); None (with a warning) when neither works."""
    if factory is not None:
        return _instantiate(factory, label, PlannerCheck(label))
    try:
        return copy.deepcopy(instance)
    except Exception as exc:
        check.warnings.append(f"determinism not checked: the planner object cannot be deep-copied "
                              f"({type(exc).__name__}: {exc}); pass its class or a factory instead")
        return None


def _check_failure(check: PlannerCheck, failure: Any, recorder: _Recorder) -> None:
    """The episode's subject failure (raised, bad answer, hung) with the planner's own frame,
    and any write into the observation's arrays, as problems."""
    if failure is not None:
        message = failure.message
        if "read-only" in message:
            message += (" -- the observation's arrays are read-only: copy before changing them, "
                        "e.g. `ranges = np.array(obs.ranges)`")
        where = f"at tick {failure.tick} (t={failure.time:.2f} s)" if recorder.reset_called else ""
        check.problems.append(f"{message} {where}".strip())
        if failure.traceback:
            frames = [ln.strip() for ln in failure.traceback.splitlines()
                      if ln.strip().startswith("File ")]
            # the planner's own frame: the last one outside the harness (deadline, sim)
            own = [f for f in frames if not any(h in f for h in _HARNESS_FILES)]
            origin = (own or frames or [""])[-1]
            if origin:
                check.problems[-1] += f" [{origin}]"
    if recorder.mutated:
        check.problems.append(
            "act() wrote into the observation's arrays: " + ", ".join(recorder.mutated[:3])
            + "; the harness passes read-only arrays, so copy before changing them")


def _check_names(check: PlannerCheck, instance: Any) -> None:
    for attr in ("name", "version"):   # read after reset: some planners name themselves there
        if getattr(instance, attr, None) is None:
            check.warnings.append(f"no `{attr}` attribute: results files will name the planner by "
                                  f"its spec only; add e.g. `{attr} = \"...\"` to the class")


def _check_speed(check: PlannerCheck, scenario: Scenario, times: list[float], slow_tick: float) -> None:
    from ..sim.deadline import DEFAULT_TICK_LIMIT

    over = [k for k, t in enumerate(times) if t > DEFAULT_TICK_LIMIT]
    if over:
        check.warnings.append(
            f"act() took {max(times):.2f} s (at tick {times.index(max(times))}; {len(over)} tick(s) over "
            f"{DEFAULT_TICK_LIMIT:g} s): over the {DEFAULT_TICK_LIMIT:g} s a tick may take by default in "
            f"pytest and navscenario run, where that episode would end as a subject-error; make act() "
            f"faster or raise --nav-tick-limit / --tick-limit")
    steady = times[1:]   # the first tick may pay one-time set-up (caches, tables)
    if steady and max(steady) > slow_tick:
        slow = sum(t > slow_tick for t in steady)
        check.warnings.append(
            f"act() is slow: {slow} of {len(steady)} ticks after the first took more than "
            f"{slow_tick * 1e3:.0f} ms (max {max(steady) * 1e3:.1f} ms); the control period "
            f"is {1e3 / scenario.simulation.control_rate:.0f} ms and a search runs thousands of episodes")


def _check_limits(check: PlannerCheck, scenario: Scenario, answers: list[Any], validate) -> None:
    robot = scenario.robot
    lim = robot.limits
    max_w = math.radians(lim.max_yaw_rate)
    worst = {"vx": 0.0, "vy": 0.0, "wz": 0.0}
    for answer in answers:
        cmd = validate(answer)
        if isinstance(cmd, str):
            continue
        vx, vy, wz = cmd
        worst["vx"] = max(worst["vx"], abs(vx))
        worst["vy"] = max(worst["vy"], abs(vy))
        worst["wz"] = max(worst["wz"], abs(wz))
    if worst["vx"] > lim.max_speed * LIMIT_SLACK:
        check.warnings.append(f"vx up to {worst['vx']:.3g} m/s exceeds robot.limits.max_speed "
                              f"{lim.max_speed:g} m/s (the simulation clips it)")
    if robot.drive == "diff" and worst["vy"] > 1e-9:
        check.warnings.append(f"vy up to {worst['vy']:.3g} m/s on a differential drive: the robot "
                              f"cannot move sideways and ignores it")
    elif worst["vy"] > lim.max_lateral_speed * LIMIT_SLACK:
        check.warnings.append(f"vy up to {worst['vy']:.3g} m/s exceeds robot.limits.max_lateral_speed "
                              f"{lim.max_lateral_speed:g} m/s (the simulation clips it)")
    if worst["wz"] > max_w * LIMIT_SLACK:
        hint = ""
        if worst["wz"] > 3.0 * max_w:
            hint = "; wz is in rad/s, the YAML's max_yaw_rate in deg/s: did you send degrees?"
        check.warnings.append(f"wz up to {worst['wz']:.3g} rad/s exceeds robot.limits.max_yaw_rate "
                              f"{lim.max_yaw_rate:g} deg/s = {max_w:.3g} rad/s (the simulation clips it)"
                              + hint)


def _check_determinism(check: PlannerCheck, scenario: Scenario, twin: Any, recorder: _Recorder,
                       validate) -> None:
    """A fresh instance fed the same observations must answer the same, bit for bit."""
    try:
        twin.reset(scenario)
        for obs, first in zip(recorder.observations, recorder.answers):
            again = twin.act(_writable_copy(obs))
            a, b = validate(first), validate(again)
            if a != b:
                check.problems.append(
                    f"nondeterministic: two fresh instances given the same observations answered "
                    f"{_fmt(a)} and {_fmt(b)} at tick {obs.tick}; seed any random generator in "
                    f"reset() (e.g. from scenario.simulation.seed) and do not keep state across "
                    f"episodes in class attributes or globals")
                return
    except Exception as exc:
        check.problems.append(f"a second fresh instance raised {type(exc).__name__}: {exc} when "
                              f"replaying the same observations (nondeterministic or stateful)")


def _fmt(cmd: Any) -> str:
    if isinstance(cmd, tuple):
        return "(" + ", ".join(f"{v:.6g}" for v in cmd) + ")"
    return str(cmd)
