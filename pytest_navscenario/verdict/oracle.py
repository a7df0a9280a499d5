"""The oracle: which outcome an episode had and one line saying why.

A pure function of the scenario, the recorded trajectory and the events the simulation
reported (collision, safety stop, planner failure, a terrain event). Precedence, first match
wins: subject-error, collision, fall, safety-stop, requirement, timeout, success. On terrain a collision may be
the chassis against a terrain face; a fall is falling off an edge or into a hole, or tipping over;
being stuck on terrain (driven but held by a step or a slope) is a timeout with that cause. Success needs the goal reached
(after every waypoint, the runner decides that) within ``mission.timeout``.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..sim.trajectory import Collision, SafetyStop, SubjectFailure, TerrainEvent, Trajectory
from .result import Outcome
from ..scenario.model import Scenario

MAX_MESSAGE = 300  # characters of a planner's own error message kept in the one-line summary


def classify(scenario: Scenario, trajectory: Trajectory, *, collision: Collision | None,
             safety_stop: SafetyStop | None, subject_failure: SubjectFailure | None,
             goal_reached: bool, stuck_after: float | None = None,
             terrain_event: TerrainEvent | None = None, requirements: Sequence = ()) -> tuple[Outcome, str]:
    """Return ``(outcome, message)`` for one episode; the message is one line for a failure report.
    ``stuck_after``: the episode was ended early because the robot was stuck that long (a timeout).
    ``requirements``: the scenario's requirements checked (verdict/requirements.py); one violated
    is the outcome ``requirement`` unless a collision, fall or safety stop came first."""
    if subject_failure is not None:
        return Outcome.SUBJECT_ERROR, (
            f"planner error at tick {subject_failure.tick} (t={subject_failure.time:.2f} s): "
            f"{_one_line(subject_failure.message)}")
    if collision is not None:
        return Outcome.COLLISION, _collision_message(collision)
    if terrain_event is not None and terrain_event.kind in ("fell", "tipped"):
        return Outcome.FALL, terrain_message(terrain_event)
    if safety_stop is not None:
        if getattr(safety_stop, "ground", ""):
            return Outcome.SAFETY_STOP, (
                f"safety stop at t={safety_stop.time:.2f} s: predicted to drive into {safety_stop.ground} "
                f"{stop_motion(safety_stop)} (seen by the 3D lidar)")
        return Outcome.SAFETY_STOP, (
            f"safety stop at t={safety_stop.time:.2f} s: predicted to hit "
            f"{stop_target(scenario, safety_stop.obstacle)} {stop_motion(safety_stop)}")
    violated = [r for r in requirements if r.violated]
    if violated:
        from .requirements import violation_message
        return Outcome.REQUIREMENT, violation_message(violated)
    duration = trajectory.duration
    timeout = scenario.mission.timeout
    if goal_reached and duration <= timeout:
        return Outcome.SUCCESS, f"success in {duration:.1f} s"
    if terrain_event is not None and terrain_event.kind in ("stuck", "still") and not goal_reached:
        return Outcome.TIMEOUT, (f"timeout: {terrain_message(terrain_event)}; episode ended early at "
                                 f"{duration:.1f} s of {timeout:.1f} s")
    if stuck_after is not None and not goal_reached:
        pose = np.asarray(trajectory.pose)
        where = (f" at ({float(pose[-1, 0]):.2f}, {float(pose[-1, 1]):.2f})" if len(pose) else "")
        return Outcome.TIMEOUT, (f"timeout: the robot was stuck{where}, covering no new ground for "
                                 f"{stuck_after:g} s; episode ended early at {duration:.1f} s of "
                                 f"{timeout:.1f} s")
    return Outcome.TIMEOUT, _timeout_message(scenario, trajectory, goal_reached)


def stop_target(scenario, name: str) -> str:
    """What a safety stop was predicted to hit: "'crate'" (an obstacle), or "the face of steps
    'stairs' (0.17 m step)" (a terrain face the body cannot cross, named after its element)."""
    from .gaps import is_terrain_face
    return f"the face of {name}" if is_terrain_face(scenario, name) else f"'{name}'"


def stop_motion(stop: SafetyStop) -> str:
    """How the robot moved when the safety layer halted it: "at 0.82 m/s", or, for a robot that
    turned in place (its speed rounds to 0.00 but its footprint still sweeps), "turning in place at
    35 deg/s" ("at 0.00 m/s" read as a robot standing still that was stopped for nothing)."""
    if stop.speed >= 0.005:
        return f"at {stop.speed:.2f} m/s"
    return f"turning in place at {abs(math.degrees(getattr(stop, 'yaw_rate', 0.0))):.0f} deg/s"


def terrain_message(event: TerrainEvent) -> str:
    """One line for a terrain event: "fell off platform 'dock' at t=6.2 s, 1.2 m drop", "tipped over
    on ramp 'bank' at t=3.1 s (roll 52 deg)", "stuck on terrain at t=8.0 s at (4.55, 0.00): cannot
    climb the 0.15 m step of platform 'kerb'"."""
    where = f"at ({event.x:.2f}, {event.y:.2f})"
    if event.kind == "fell":
        what = f"fell {event.element}" if event.element else "fell off an edge"
        drop = f"{event.drop:.2f}"          # 0.15 and 0.25 m are not "0.1" and "0.2", 1.2 m still "1.2"
        drop = drop[:-1] if drop.endswith("0") else drop
        return f"{what} at t={event.time:.1f} s, {drop} m drop, {where}"
    if event.kind == "tipped":
        on = ("" if not event.element else f" {event.element}" if event.element.startswith("off ")
              else f" on {event.element}")
        angle = (f"roll {abs(event.roll):.0f} deg" if abs(event.roll) >= abs(event.pitch)
                 else f"pitch {abs(event.pitch):.0f} deg")
        return f"tipped over{on} at t={event.time:.1f} s ({angle}) {where}"
    if event.kind == "still":
        return f"did not move at t={event.time:.1f} s {where}: {event.detail}"
    of = f" of {event.element}" if event.element else ""
    return f"stuck on terrain at t={event.time:.1f} s {where}: {event.detail}{of}"


def _collision_message(collision: Collision) -> str:
    """Where, and who moved: a robot standing still that a moving obstacle walked into reads
    differently from one that drove into something (both are collisions)."""
    if getattr(collision, "terrain", False):
        return (f"collision with the face of {collision.obstacle} at t={collision.time:.2f} s "
                f"(depth {max(collision.depth, 0.0) * 1000:.0f} mm) at ({collision.x:.2f}, {collision.y:.2f}): "
                f"the chassis drove into terrain it cannot climb")
    text = (f"collision with '{collision.obstacle}' at t={collision.time:.2f} s "
            f"(depth {max(collision.depth, 0.0) * 1000:.0f} mm) at ({collision.x:.2f}, {collision.y:.2f})")
    moving = getattr(collision, "obstacle_speed", 0.0) > 0.0
    if not getattr(collision, "robot_moving", True):
        return text + (f": the robot stood still and '{collision.obstacle}' walked into it at "
                       f"{collision.obstacle_speed:.2f} m/s" if moving else ": the robot stood still")
    if moving:
        return text + (f": the robot drove into it at {collision.robot_speed:.2f} m/s, the obstacle "
                       f"moving at {collision.obstacle_speed:.2f} m/s")
    return text


def _timeout_message(scenario: Scenario, trajectory: Trajectory, goal_reached: bool) -> str:
    mission = scenario.mission
    duration = trajectory.duration
    if goal_reached:  # reached, but too late
        return f"timeout: goal reached after {duration:.1f} s, later than the {mission.timeout:.1f} s allowed"
    pose = np.asarray(trajectory.pose)
    if len(pose):
        dist = math.hypot(float(pose[-1, 0]) - mission.goal.x, float(pose[-1, 1]) - mission.goal.y)
        where = f", {dist:.2f} m from the goal"
    else:
        where = ""
    n_wp = len(mission.waypoints)
    passed = f" ({len(trajectory.waypoint_times)} of {n_wp} waypoints passed)" if n_wp else ""
    if duration < timeout_floor(mission.timeout, scenario.simulation.timestep):
        # The episode ended early without an event: say so instead of pretending the clock ran out.
        return f"timeout: episode ended at {duration:.1f} s without reaching the goal{where}{passed}"
    return f"timeout after {duration:.1f} s{where}{passed}"


def timeout_floor(timeout: float, timestep: float) -> float:
    """The earliest time at which an episode counts as having run out its clock (one step of slack)."""
    return timeout - 1.5 * timestep


def _one_line(text: str) -> str:
    line = " ".join(str(text).split())
    return line if len(line) <= MAX_MESSAGE else line[: MAX_MESSAGE - 3] + "..."
