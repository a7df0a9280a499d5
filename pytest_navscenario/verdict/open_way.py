"""A way for the footprint known without a path search: ``paths.path_exists`` and the first margin
of ``paths.passage_room`` answered in microseconds for most of a search's layouts.

A failure search checks hundreds of layouts that differ in where a few obstacles stand: is there
still a way for the footprint (its validity), how much room does the narrowest passage leave
(evolve's ranking)? Each answer is a visibility-graph search, 0.5-1 ms. But most layouts are
open: grow every obstacle's bounding circle by the inflation, the margin and what the polygons of
``paths`` may bulge past it; if no stop is inside one and the circles touch in no cycle, their
union is a set of simply connected blobs (the nerve of convex sets that touch in no cycle is a
forest), whose outside is connected: a way exists at that margin among the polygons inside them,
and walking the straight legs, round each blob a leg meets by its shorter side (at most half its
perimeter), bounds its length from above (``feasibility.too_slow``'s common case). Otherwise
``paths`` answers. The answers are always ``paths``'.
"""
from __future__ import annotations

import math

from ..scenario.model import Scenario
from .gaps import path_obstacles
from .grown import INFLATION_TOLERANCE, inflation_radius

BULGE = 1.0 / math.cos(math.pi / 32) - 1.0   # paths' polygons bulge past tol at most this share of r


def open_way(scenario: Scenario, margin: float) -> float | None:
    """The length of a way for the footprint grown by ``margin`` (m) among ``scenario``'s path
    obstacles, known without a path search when their bounding circles, grown by the inflation,
    the margin and what the polygons of ``paths`` may bulge, leave every stop outside and touch in
    no cycle (see the module docstring; a few microseconds a layout); else None. A
    length means ``passage_room`` passes ``margin`` and ``path_exists`` is True."""
    from ..scenario.geometry import bounding_radius

    obstacles = path_obstacles(scenario)
    r = inflation_radius(scenario.robot.footprint)
    m = scenario.mission
    stops = [(m.start.x, m.start.y), *((w.x, w.y) for w in m.waypoints), (m.goal.x, m.goal.y)]
    grow = r + margin + INFLATION_TOLERANCE + 1e-6
    discs = []
    for obs in obstacles:
        rho = bounding_radius(obs)
        discs.append((obs.x, obs.y, rho + grow + BULGE * (r + margin + rho)))
    for x, y, rad in discs:
        if any(math.hypot(x - sx, y - sy) <= rad for sx, sy in stops):
            return None
    group = list(range(len(discs)))

    def find(i: int) -> int:
        while group[i] != i:
            group[i] = group[group[i]]
            i = group[i]
        return i
    for i, (xi, yi, ri) in enumerate(discs):
        for j in range(i + 1, len(discs)):
            xj, yj, rj = discs[j]
            if math.hypot(xi - xj, yi - yj) <= ri + rj:
                a, b = find(i), find(j)
                if a == b:
                    return None   # a cycle: they might enclose a stop
                group[a] = b
    length = 0.0
    for (ax, ay), (bx, by) in zip(stops, stops[1:]):
        length += math.hypot(bx - ax, by - ay)
        hit = {find(i) for i, (x, y, rad) in enumerate(discs) if _to_segment(x, y, ax, ay, bx, by) <= rad}
        length += sum(math.pi * rad for i, (_, _, rad) in enumerate(discs) if find(i) in hit)
    return length


def _to_segment(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    dx, dy = bx - ax, by - ay
    u = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / ((dx * dx + dy * dy) or 1.0)))
    return math.hypot(px - ax - u * dx, py - ay - u * dy)
