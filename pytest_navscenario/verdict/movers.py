"""Moving obstacles must not walk through what stands still: a person whose path crosses a wall
simulates the impossible (MuJoCo moves a mocap body through anything), so a frozen failure of it is
no planner's fault. ``mover_through`` sweeps each moving obstacle's outline along its whole motion
during the episode and says which static obstacle it crosses first, and where.

What counts as standing still is ``blockers(scenario)``: the static obstacles, and whatever else is
registered in ``BLOCKERS`` (the terrain helpers add terrain faces there: a function of the scenario
returning (label, field, shapely polygon) triples).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterable

import numpy as np

from ..scenario.model import Obstacle, Scenario

AREA = 1e-6     # m^2: a sweep that overlaps a blocker by less only touches it (a path along a wall)


@dataclass(frozen=True)
class Crossing:
    mover: str            # the moving obstacle's name
    index: int            # its index in scenario.obstacles
    blocker: str          # what it walks through ("static obstacle 'wall'", a terrain face, ...)
    leg: tuple[tuple[float, float], tuple[float, float]]   # its centre's leg that crosses it: from, to
    mode: str             # "path" or "velocity"


def _static_obstacles(scenario: Scenario) -> Iterable[tuple[str, str, object]]:
    from ..scenario.geometry import obstacle_polygon

    for i, o in enumerate(scenario.obstacles):
        if getattr(o, "motion", None) is None:
            yield f"static obstacle {o.name!r}", f"obstacles[{i}]", obstacle_polygon(o)


# what a moving obstacle may not cross: each a function of the scenario giving (label, field, polygon)
BLOCKERS: list[Callable[[Scenario], Iterable[tuple[str, str, object]]]] = [_static_obstacles]


def blockers(scenario: Scenario) -> list[tuple[str, str, object]]:
    return [b for source in BLOCKERS for b in source(scenario)]


def legs(obs: Obstacle, timeout: float) -> tuple[np.ndarray, str]:
    """(k, 2) the successive positions of the obstacle's centre during an episode of ``timeout``
    seconds: where it stands before it starts, then its path's corners (over and back or round as
    its mode says, one cycle at most: the rest repeats it) up to where the timeout stops it, or its
    straight run at constant velocity; and the kind of motion."""
    from ..scenario.motion import Track

    track = Track(obs)
    run = max(timeout - track.start, 0.0)
    if track.constant:
        end = (track.origin[0] + track.vel[0] * run, track.origin[1] + track.vel[1] * run)
        return np.array([track.origin, end]), "velocity"
    until = min(run, track.period) if track.period > 0 else 0.0
    tau = np.concatenate([track.knots[track.knots < until], [until]])
    return track.positions(track.start + tau), "path"


def swept(obs: Obstacle, a: tuple[float, float], b: tuple[float, float]):
    """The area the obstacle's outline covers while its centre moves from ``a`` to ``b`` (it keeps
    its orientation): the union over its convex parts of the hull of the part at both ends."""
    import shapely
    from shapely.geometry import MultiPoint

    from ..scenario.geometry import convex_parts, obstacle_polygon
    from ..scenario.model import MeshObstacle, PolygonObstacle

    base = (obs.x, obs.y)
    parts = convex_parts(obs) if isinstance(obs, (PolygonObstacle, MeshObstacle)) else \
        [np.asarray(obstacle_polygon(obs).exterior.coords)[:-1]]
    hulls = []
    for part in parts:
        pa = part + (a[0] - base[0], a[1] - base[1])
        pb = part + (b[0] - base[0], b[1] - base[1])
        hulls.append(MultiPoint(np.concatenate([pa, pb])).convex_hull)
    return shapely.union_all(hulls)


def mover_through(scenario: Scenario) -> Crossing | None:
    """The first moving obstacle whose motion during the episode crosses something that stands
    still (``blockers``), or None."""
    import shapely

    movers = [(i, o) for i, o in enumerate(scenario.obstacles) if getattr(o, "motion", None) is not None]
    if not movers:
        return None
    still = blockers(scenario)
    if not still:
        return None
    shapes = np.array([s for _, _, s in still], dtype=object)
    tree = shapely.STRtree(shapes)
    for i, obs in movers:
        pts, mode = legs(obs, scenario.mission.timeout)
        for a, b in zip(pts[:-1], pts[1:]) if len(pts) > 1 else [(pts[0], pts[0])]:
            area = swept(obs, (float(a[0]), float(a[1])), (float(b[0]), float(b[1])))
            for j in sorted(tree.query(area, predicate="intersects")):
                if area.intersection(shapes[j]).area > AREA:
                    return Crossing(mover=obs.name, index=i, blocker=still[j][0],
                                    leg=((float(a[0]), float(a[1])), (float(b[0]), float(b[1]))), mode=mode)
    return None


def describe(c: Crossing) -> tuple[str, str]:
    """(field, message) of a crossing, for a scenario error."""
    (x0, y0), (x1, y1) = c.leg
    field = f"obstacles[{c.index}].motion." + ("path" if c.mode == "path" else "velocity")
    what = (f"moving obstacle {c.mover!r} walks through {c.blocker} on its way from ({x0:g}, {y0:g}) to "
            f"({x1:g}, {y1:g})" if c.mode == "path" else
            f"moving obstacle {c.mover!r}, at constant velocity from ({x0:g}, {y0:g}), walks through {c.blocker} "
            f"before the timeout (it would reach ({x1:.3g}, {y1:.3g}))")
    return field, (f"{what}: the simulation would move it through as if that were not there; route the motion "
                   f"around it, or move the one that stands")


def movers_inside(obstacles) -> list[tuple[str, str]]:
    """(field, message) for each moving obstacle whose path starts or ends inside a static obstacle
    (DynaBARN's paths start and end inside the arena's walls, where Gazebo hides its obstacles): not
    an error (a scenario may mean it), a warning, since MuJoCo moves it through the wall."""
    from shapely import affinity

    from ..scenario.geometry import obstacle_polygon

    still = [(o.name, obstacle_polygon(o)) for o in obstacles if getattr(o, "motion", None) is None]
    out = []
    for i, o in enumerate(obstacles):
        m = getattr(o, "motion", None)
        if m is None or not m.path:
            continue
        base = obstacle_polygon(o)
        for which, (x, y) in (("starts", m.path[0]), ("ends", m.path[-1])):
            at = affinity.translate(base, x - o.x, y - o.y)
            inside = [n for n, p in still if at.intersection(p).area > AREA]
            if inside:
                out.append((f"obstacles[{i}].motion.path",
                            f"moving obstacle {o.name!r} {which} inside static obstacle {inside[0]!r} at ({x:g}, {y:g}) "
                            f"(as DynaBARN's obstacles come out of the arena's walls in Gazebo): the simulation moves "
                            f"it through the wall as if it were not there, and the pytest plugin reports the scenario "
                            f"as infeasible (a mover through a static obstacle); start and end its path outside"))
    return out
