"""Scenarios no planner can pass, or that pass without one: told before the episode runs.

A scenario whose goal cannot be reached at all (walled in; a waypoint or the goal, with its whole
tolerance, closer to an obstacle than half the robot's width) would run to its timeout and be
blamed on the planner; one whose start already satisfies the goal passes in 0 s and tests
nothing. ``impassable_reason`` says which, in words, or None for an ordinary scenario.

Cost: the common case is one ``paths.shortest_path`` (cached; the metrics need the same path
after the episode, so a normal run pays nothing extra). Only when that finds no path is the
verdict confirmed, conservatively: obstacles grown by half the robot's width minus the polygon
tolerance (so the polygons lie inside the true grown shapes) and every waypoint and the goal
counted as reached anywhere within its tolerance. If any way remains, the scenario runs.
"""
from __future__ import annotations

import math

from ..scenario.model import Scenario
from .paths import INFLATION_TOLERANCE, inflation_radius, path_through_discs, shortest_path


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


def impassable_reason(scenario: Scenario) -> str | None:
    """Why no planner can pass ``scenario`` (or why it passes without one), or None."""
    trivial = trivially_passed(scenario)
    if trivial is not None:
        return trivial
    if shortest_path(scenario) is not None:
        return None
    m = scenario.mission
    fp = scenario.robot.footprint
    r = inflation_radius(fp)
    stops = [(m.start.x, m.start.y, 0.0), *((w.x, w.y, m.waypoint_tolerance) for w in m.waypoints),
             (m.goal.x, m.goal.y, m.goal_tolerance.position)]
    path, reached = path_through_discs(scenario, stops, inflation=max(r - INFLATION_TOLERANCE, 0.0))
    if path is not None:
        return None   # only the exact points are closed off: a planner may still pass
    names = ["the start", *(f"waypoint {i} ({w.x:g}, {w.y:g})" for i, w in enumerate(m.waypoints)),
             f"the goal ({m.goal.x:g}, {m.goal.y:g})"]
    width = f"{2 * r:g} m wide" if fp.shape != "circle" else f"{2 * r:g} m across"
    blocked = _closest_obstacle(scenario, stops[reached], r)
    where = f"{names[reached - 1]} to {names[reached]}" if reached > 0 else names[0]
    why = (f"{names[reached]} lies within {blocked[1]:.2f} m of obstacle {blocked[0]!r}, closer than "
           f"half the robot's width ({r:g} m), with all of its {stops[reached][2]:g} m tolerance"
           if blocked is not None else "obstacles close every way between them")
    return (f"no planner can pass this scenario: there is no collision-free way for the robot "
            f"({width}) from {where}: {why}; move the obstacles or the mission points, or, if the "
            f"scenario is meant to be impassable, mark it xfail")


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
