"""The key moments of a trajectory map: the minimum clearance (and, for a stop or a collision,
the clearance to the obstacle the outcome is about), the narrowest gap, the collision, safety stop,
fall or tip-over, and where the robot ended. Each marks its place for the label placer
(labels.py) so that no label covers it.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..scenario.geometry import footprint_polygon, obstacle_polygon
from ..verdict.result import EpisodeResult
from .labels import LabelPlacer, ring
from .map_parts import _HALO, _gap, _pose_at, obstacle_polygon_at

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

OUTCOME_COLOURS = {"success": "#2e7d32", "collision": "#c62828", "safety-stop": "#ef6c00",
                   "timeout": "#6a1b9a", "subject-error": "#37474f", "fall": "#8d1b1b", "requirement": "#ad1457"}


def _draw_min_clearance(ax: "Axes", result: EpisodeResult, labels: LabelPlacer | None = None) -> None:
    """The moment of minimum clearance: the footprint then (red outline) and the segment from it
    to the nearest obstacle, labelled on the free side."""
    from matplotlib.patches import Polygon as MplPolygon
    from shapely.ops import nearest_points

    s, m = result.scenario, result.metrics
    if not (math.isfinite(m.min_clearance) and m.min_clearance_obstacle):
        return
    p = _pose_at(result, m.min_clearance_time)
    if p is None:
        p = np.array([m.min_clearance_x, m.min_clearance_y, math.radians(s.mission.start.yaw)])
    obstacle = clearance_shape(s, m.min_clearance_obstacle, m.min_clearance_time)
    if obstacle is None:
        return
    footprint = footprint_polygon(s.robot.footprint, *p)
    a, b = nearest_points(footprint, obstacle)
    ax.plot([a.x, b.x], [a.y, b.y], color="#d50000", lw=2, zorder=10)
    ax.plot([a.x], [a.y], marker="o", ms=5, color="#d50000", zorder=10)
    ax.add_patch(MplPolygon(np.asarray(footprint.exterior.coords), closed=True,
                            fill=False, ec="#d50000", lw=1.2, zorder=10))
    # label on the free side: from the obstacle towards the robot
    d = np.array([a.x - b.x, a.y - b.y])
    d = d / np.linalg.norm(d) if np.linalg.norm(d) > 1e-9 else np.array([-0.7, 0.7])
    text = f"min clearance {m.min_clearance:.2f} m\n(t={m.min_clearance_time:.1f} s)"
    style = dict(fontsize=7, color="#d50000", zorder=11, bbox=_HALO)
    if labels is None:
        ax.annotate(text, (a.x, a.y), xytext=tuple(28 * d), textcoords="offset points",
                    ha="right" if d[0] < 0 else "left", va="top" if d[1] < 0 else "bottom",
                    arrowprops=dict(arrowstyle="-", color="#d50000", lw=0.6), **style)
        return
    labels.avoid((a.x, a.y), 5)
    labels.avoid_area(np.asarray(footprint.exterior.coords))   # no label over the red footprint
    free = [tuple(r * d) for r in (28.0, 44.0)]     # on the free side first, then anywhere near
    labels.add(text, (a.x, a.y), priority=1, offsets=free + ring((28.0, 44.0, 64.0)),
               leader=dict(color="#d50000", lw=0.6, zorder=10), **style)


def clearance_shape(scenario: Any, name: str, t: float) -> Any:
    """The shapely shape a clearance was measured to: the obstacle ``name`` where it was at ``t``,
    or the terrain's faces of that name (lines) and steep areas (``gaps.clearance_obstacles``);
    None if there is none."""
    try:
        return obstacle_polygon_at(scenario.obstacle(name), t)
    except KeyError:
        pass
    import shapely

    from ..verdict.gaps import clearance_obstacles

    parts = []
    for o in clearance_obstacles(scenario):
        if o.name != name:
            continue
        if getattr(o, "width", None) == 0.0:     # a face: the line it stands on
            c, sn = math.cos(math.radians(o.yaw)) * o.length / 2, math.sin(math.radians(o.yaw)) * o.length / 2
            parts.append(shapely.LineString([(o.x - c, o.y - sn), (o.x + c, o.y + sn)]))
        else:
            parts.append(obstacle_polygon(o))
    return shapely.union_all(parts) if parts else None


def _draw_culprit_clearance(ax: "Axes", result: EpisodeResult, labels: LabelPlacer | None = None) -> None:
    """For a stop or a collision about another obstacle than the minimum clearance's (a person
    beside a corridor's walls): the robot's closest approach to that obstacle, labelled with its
    name, in the outcome's colour."""
    from shapely.ops import nearest_points

    from ..verdict.metrics import culprit_clearance

    found = culprit_clearance(result) if len(result.trajectory.t) else None
    if found is None:
        return
    name, dist, time = found
    p = _pose_at(result, time)
    if p is None:
        return
    colour = OUTCOME_COLOURS.get(result.outcome.value, "#ef6c00")
    a, b = nearest_points(footprint_polygon(result.scenario.robot.footprint, *p),
                          obstacle_polygon_at(result.scenario.obstacle(name), time))
    ax.plot([a.x, b.x], [a.y, b.y], color=colour, lw=2, zorder=10)
    ax.plot([a.x], [a.y], marker="o", ms=5, color=colour, zorder=10)
    text = f"clearance to {name} {dist:.2f} m\n(t={time:.1f} s, the {result.outcome.value}'s)"
    style = dict(fontsize=7, color=colour, zorder=11, bbox=_HALO)
    if labels is None:
        ax.annotate(text, (a.x, a.y), xytext=(20, -20), textcoords="offset points", **style)
        return
    labels.avoid((a.x, a.y), 5)
    labels.add(text, (a.x, a.y), priority=1, offsets=ring((28.0, 44.0, 64.0)),
               leader=dict(color=colour, lw=0.6, zorder=10), **style)


def _draw_narrowest_gap(ax: "Axes", scenario: Any, metrics: Any, labels: LabelPlacer | None = None) -> None:
    """The narrowest gap between two obstacles: a double arrow with its width."""
    from shapely.ops import nearest_points

    gap, na, nb = _gap(scenario, metrics)
    if not (math.isfinite(gap) and na and nb):
        return
    try:
        a, b = nearest_points(obstacle_polygon(scenario.obstacle(na)), obstacle_polygon(scenario.obstacle(nb)))
    except KeyError:
        return
    ax.annotate("", (a.x, a.y), (b.x, b.y), zorder=10,
                arrowprops=dict(arrowstyle="<->", color="#ff6f00", lw=1.3, shrinkA=0, shrinkB=0))
    mid = ((a.x + b.x) / 2, (a.y + b.y) / 2)
    style = dict(fontsize=7, color="#e65100", zorder=11, bbox=_HALO)
    if labels is None:
        ax.annotate(f"gap {gap:.2f} m", mid, xytext=(0, -7), textcoords="offset points",
                    ha="center", va="top", **style)
        return
    labels.add(f"gap {gap:.2f} m", mid, priority=2, offsets=ring((7.0, 16.0, 30.0), first=(0, -1)),
               leader=dict(color="#e65100", lw=0.5, zorder=10), **style)


def _draw_events(ax: "Axes", result: EpisodeResult, labels: LabelPlacer | None = None) -> None:
    """Where the episode ended badly: the collision's contact point, the safety stop's pose, where
    the robot fell, tipped over or got stuck on terrain."""
    event = getattr(result, "terrain_event", None)
    if event is not None:
        from .terrain_plot import draw_terrain_event
        draw_terrain_event(ax, result)
        if labels is not None:
            labels.avoid((event.x, event.y), 9)
    if result.collision is not None:
        c = result.collision
        who = "" if getattr(c, "robot_moving", True) else ", robot standing"
        ax.plot(c.x, c.y, marker="X", ms=12, color="#b71c1c", mec="white", zorder=12, ls="none",
                label=f"collision t={c.time:.1f} s{who}")
        if labels is not None:
            labels.avoid((c.x, c.y), 9)
    if result.safety_stop is not None:
        p = _pose_at(result, result.safety_stop.time)
        if p is not None:
            ax.plot(p[0], p[1], marker="8", ms=11, color="#ef6c00", mec="white", zorder=12, ls="none",
                    label=f"safety stop t={result.safety_stop.time:.1f} s")
            if labels is not None:
                labels.avoid((p[0], p[1]), 9)


def _draw_end(ax: "Axes", result: EpisodeResult, labels: LabelPlacer | None = None) -> None:
    """Where the robot ended when neither a collision nor a safety stop marks it and it is not at
    the goal (a timeout, a planner error): its footprint then, outlined in the outcome's colour,
    and a square at its centre, in the legend with the outcome and the time."""
    from matplotlib.patches import Polygon as MplPolygon

    if result.passed or result.collision is not None or result.safety_stop is not None:
        return
    traj = result.trajectory
    if not len(traj.t):
        return
    x, y, yaw = (float(v) for v in np.asarray(traj.pose[-1], dtype=float))
    colour = OUTCOME_COLOURS.get(result.outcome.value, "black")
    outline = footprint_polygon(result.scenario.robot.footprint, x, y, yaw)
    ax.add_patch(MplPolygon(np.asarray(outline.exterior.coords), closed=True, fill=False, ec=colour,
                            lw=1.6, zorder=11))
    if labels is not None:
        labels.avoid_area(np.asarray(outline.exterior.coords))
    event = getattr(result, "terrain_event", None)
    if event is not None and math.hypot(event.x - x, event.y - y) < 0.5:
        return   # the fall, tip-over or stuck marker says where and when it ended: no square over it
    ax.plot(x, y, marker="s", ms=8, color=colour, mec="white", zorder=12, ls="none",
            label=f"end: {result.outcome.value} at t={float(traj.t[-1]):.1f} s")
    if labels is not None:
        labels.avoid((x, y), 7)
