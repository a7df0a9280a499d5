"""Scenarios no planner can pass, or that pass without one: told before the episode runs.

A scenario whose goal cannot be reached at all (walled in; a waypoint or the goal, with its whole
tolerance, closer to an obstacle than half the robot's width) would run to its timeout and be
blamed on the planner; one whose start already satisfies the goal passes in 0 s and tests
nothing; one whose shortest way cannot be driven within its timeout even at the robot's top speed
times out whatever the planner does (``too_slow``); one whose moving obstacle walks through a wall
simulates the impossible (``movers.mover_through``). ``infeasible`` says which, with the field to
fix (``impassable_reason``: the same in words), or None for an ordinary scenario. A hand-written
scenario gets it as a setup error; the search discards such a candidate (search/space.py,
``invalid_reason``), counted by its code.

Cost: the common case is one ``paths.shortest_path`` (cached; the metrics need the same path
after the episode, so a normal run pays nothing extra). Only when that finds no path is the
verdict confirmed, conservatively: obstacles grown by half the robot's width minus the polygon
tolerance (so the polygons lie inside the true grown shapes) and every waypoint and the goal
counted as reached anywhere within its tolerance; on terrain, the barriers of a more capable body
than the robot's (``traversable.lenient``). If any way remains, the scenario runs.
"""
from __future__ import annotations

import math

from dataclasses import dataclass

import numpy as np

from ..scenario.model import Scenario
from .gaps import static_obstacles
from .grown import INFLATION_TOLERANCE, inflated_polygon, inflation_radius
from .paths import path_through_discs, reference_path, shortest_path


def trivially_passed(scenario: Scenario) -> str | None:
    """Why the start already completes the mission (every waypoint and the goal within their
    tolerances, the heading too if checked), or None."""
    m = scenario.mission
    s = m.start
    if any(math.hypot(w.x - s.x, w.y - s.y) > m.waypoint_tolerance for w in m.waypoints):
        return None
    if math.hypot(m.goal.x - s.x, m.goal.y - s.y) > m.goal_tolerance.position:
        return None
    yaw_tol = m.goal_tolerance.yaw
    if yaw_tol is not None and abs((s.yaw - m.goal.yaw + 180.0) % 360.0 - 180.0) > yaw_tol:
        return None
    return (f"the start ({s.x:g}, {s.y:g}) already satisfies the goal ({m.goal.x:g}, {m.goal.y:g}) "
            f"within its tolerance of {m.goal_tolerance.position:g} m"
            + ("" if not m.waypoints else " and every waypoint")
            + ": the scenario passes at t=0 whatever the planner does, so it tests nothing; "
              "move the goal away from the start or tighten mission.goal_tolerance")


@dataclass(frozen=True)
class Infeasible:
    """Why a scenario is not a test: ``code`` (for counting: trivial, no-path, too-slow,
    mover-through), the dotted ``field`` to fix (None when no one field is to blame) and the words."""
    code: str
    field: str | None
    message: str

    def __str__(self) -> str:
        return f"{self.field}: {self.message}" if self.field else self.message


def infeasible(scenario: Scenario) -> Infeasible | None:
    """Why no planner can pass ``scenario``, or why it passes without one, or why it simulates the
    impossible; None for an ordinary scenario."""
    trivial = trivially_passed(scenario)
    if trivial is not None:
        return Infeasible("trivial", None, trivial)
    blocked = _no_way(scenario)
    if blocked is not None:
        return Infeasible("no-path", None, blocked)
    slow = too_slow(scenario)
    if slow is not None:
        return Infeasible("too-slow", "mission.timeout", slow)
    from .movers import describe, mover_through
    crossing = mover_through(scenario)
    if crossing is not None:
        field, message = describe(crossing)
        return Infeasible("mover-through", field, message)
    return None


def impassable_reason(scenario: Scenario) -> str | None:
    """Why no planner can pass ``scenario`` (or why it passes without one, or simulates the
    impossible), in words with the field to fix, or None."""
    found = infeasible(scenario)
    return None if found is None else str(found)


def top_speed(scenario: Scenario) -> float:
    """The fastest the robot can drive (m/s): forward and, on an omnidirectional drive, sideways at
    once (the drive clips each command component to its own limit)."""
    limits = scenario.robot.limits
    return math.hypot(limits.max_speed, limits.max_lateral_speed if scenario.robot.drive == "omni" else 0.0)


def too_slow(scenario: Scenario, known_length: float | None = None) -> str | None:
    """Why the shortest way cannot be driven within the timeout even at the robot's top speed, or
    None. The way is a lower bound of any planner's: the shortest collision-free path of the
    footprint's centre (obstacles grown by half its width), each waypoint counted as passed anywhere
    within its tolerance, the goal reached at its tolerance's edge; acceleration is left out.
    ``known_length``: the length of some collision-free way (open_way.py), an upper bound of the
    shortest's: when it is short enough, no path search is needed."""
    m = scenario.mission
    speed = top_speed(scenario)
    slack = 2 * m.waypoint_tolerance * len(m.waypoints) + m.goal_tolerance.position
    if known_length is not None and (known_length - slack) <= speed * m.timeout:
        return None
    path = shortest_path(scenario)
    if path is None:
        return None
    if (path.length - slack) <= speed * m.timeout:     # the common case: one cached path, no more
        return None
    ref = reference_path(scenario)                    # through the waypoints' tolerance discs
    length = max((ref.length if ref is not None else path.length) - m.goal_tolerance.position, 0.0)
    needed = length / speed
    if needed <= m.timeout:
        return None
    suggest = math.ceil(2 * needed + 10)
    return (f"the timeout of {m.timeout:g} s is too short: the shortest way the robot can take is {length:.1f} m "
            f"(to the edge of the goal's tolerance), which takes at least {needed:.1f} s at its top speed of "
            f"{speed:g} m/s, so every planner would time out; raise mission.timeout (e.g. to {suggest:g} s) or "
            f"robot.limits.max_speed")


def _no_way(scenario: Scenario) -> str | None:
    """Why there is no collision-free way for the footprint at all, or None."""
    if shortest_path(scenario) is not None:
        return None
    m = scenario.mission
    fp = scenario.robot.footprint
    r = inflation_radius(fp)
    stops = [(m.start.x, m.start.y, 0.0), *((w.x, w.y, m.waypoint_tolerance) for w in m.waypoints),
             (m.goal.x, m.goal.y, m.goal_tolerance.position)]
    inflation = max(r - INFLATION_TOLERANCE, 0.0)
    path, reached = path_through_discs(scenario, stops, inflation=inflation,
                                       obstacles=static_obstacles(scenario) + _terrain(scenario, stops, inflation))
    if path is not None:
        return None   # only the exact points are closed off: a planner may still pass
    names = ["the start", *(f"waypoint {i} ({w.x:g}, {w.y:g})" for i, w in enumerate(m.waypoints)),
             f"the goal ({m.goal.x:g}, {m.goal.y:g})"]
    width = f"{2 * r:g} m wide" if fp.shape != "circle" else f"{2 * r:g} m across"
    blocked = _closest_obstacle(scenario, stops[reached], r)
    where = f"{names[reached - 1]} to {names[reached]}" if reached > 0 else names[0]
    if blocked is not None:
        why = (f"{names[reached]} lies within {blocked[1]:.2f} m of obstacle {blocked[0]!r}, closer than "
               f"half the robot's width ({r:g} m), with all of its {stops[reached][2]:g} m tolerance")
    else:
        why = _terrain_words(scenario, stops[reached - 1] if reached > 0 else stops[0], stops[reached]) or \
            "obstacles close every way between them"
    return (f"no planner can pass this scenario: there is no collision-free way for the robot "
            f"({width}) from {where}: {why}; move the obstacles or the mission points, or, if the "
            f"scenario is meant to be impassable, mark it xfail")


def _terrain(scenario: Scenario, stops, inflation: float) -> tuple:
    """The terrain barriers for the confirmation: a more capable body's (traversable.lenient),
    leaving out those the footprint already overlaps at a mission point (the loader accepted it
    standing there)."""
    if not scenario.terrain:
        return ()
    from ..scenario.bodies import body_capability
    from ..scenario.ground.traversable import barriers, lenient

    cap = body_capability(scenario)
    if cap is None:
        return ()
    points = np.array([(x, y) for x, y, _ in stops])
    keep = []
    for wall in barriers(scenario, lenient(cap)):
        poly = inflated_polygon(wall, inflation)
        edges = np.roll(poly, -1, axis=0) - poly
        cross = edges[None, :, 0] * (points[:, None, 1] - poly[None, :, 1]) - \
            edges[None, :, 1] * (points[:, None, 0] - poly[None, :, 0])
        if not (cross > 0).all(axis=1).any():
            keep.append(wall)
    return tuple(keep)


def _terrain_words(scenario: Scenario, a, b) -> str | None:
    """"the terrain the body cannot cross closes every way between them (in the way: ...)", naming
    the barriers the obstacle-free way from a to b crosses; None without terrain barriers."""
    if not scenario.terrain:
        return None
    from ..scenario.bodies import body_capability
    from ..scenario.ground.traversable import barriers

    cap = body_capability(scenario)
    walls = barriers(scenario) if cap is not None else ()
    if not walls:
        return None
    way, _ = path_through_discs(scenario, [(a[0], a[1], 0.0), (b[0], b[1], b[2])], inflation=0.0,
                                obstacles=static_obstacles(scenario))
    from shapely.geometry import LineString, Polygon
    line = LineString(way.points) if way is not None and len(way.points) > 1 else None
    crossed = []
    for wall in walls:
        if line is None or line.intersects(Polygon(inflated_polygon(wall, 0.0))):
            if wall.name not in crossed:
                crossed.append(wall.name)
    kind = scenario.robot.body.kind
    limits = (f"{'its estimated' if kind == 'wheeled' else 'its'} limits: a {cap.max_step:.2g} m step, a "
              f"{cap.max_slope:.3g} deg slope, a {cap.max_gap:.2g} m gap")
    named = ", ".join(crossed[:3]) + (f" and {len(crossed) - 3} more" if len(crossed) > 3 else "")
    return (f"the terrain the {kind} body cannot cross closes every way between them"
            + (f": in the way, {named}" if named else "") + f"; {limits}")


def _closest_obstacle(scenario: Scenario, stop: tuple[float, float, float],
                      r: float) -> tuple[str, float] | None:
    """(name, distance) of an obstacle closer to the stop than r minus its tolerance, if any."""
    from shapely.geometry import Point

    from ..scenario.geometry import obstacle_polygon

    x, y, tol = stop
    best = None
    for obs in scenario.obstacles:
        if getattr(obs, "motion", None) is not None:
            continue
        d = obstacle_polygon(obs).distance(Point(x, y))
        if d + tol < r - INFLATION_TOLERANCE and (best is None or d < best[1]):
            best = (obs.name, d)
    return best
