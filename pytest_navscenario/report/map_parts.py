"""The layers of a trajectory map, back to front: the obstacles (static and moving, named), the
shortest path, where the footprint went (swept area, outlines, the centre line coloured by speed,
time stamps), the believed path under localisation drift and the mission's marks; with the map's
extent and the helpers they share. ``plots.draw_episode`` calls them in order; the key moments
(minimum clearance, gap, events, end) are in ``map_moments.py``.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ..scenario.geometry import footprint_polygons, obstacle_polygon
from ..scenario.motion import Track, displacement, is_moving
from ..verdict.result import EpisodeResult
from .labels import LabelPlacer, ring

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

SPEED_CMAP = "viridis"
MAX_NAMED_OBSTACLES = 40   # more obstacles than this: only the ones involved are named
MAX_GAP_SEARCH = 200       # touching obstacles: look for the narrowest real gap among at most this many


def _speed(result: EpisodeResult) -> np.ndarray:
    vel = np.asarray(result.trajectory.velocity, dtype=float).reshape(-1, 3)
    return np.hypot(vel[:, 0], vel[:, 1])


def _pose_at(result: EpisodeResult, time: float) -> np.ndarray | None:
    traj = result.trajectory
    if not len(traj.t) or not math.isfinite(time):
        return None
    i = int(np.clip(np.searchsorted(traj.t, time), 0, len(traj.t) - 1))
    return np.asarray(traj.pose[i], dtype=float)


def _gap(scenario: Any, metrics: Any) -> tuple[float, str, str]:
    """The narrowest obstacle gap to mark: the metric's (paths.min_obstacle_gap), unless obstacles
    touch (gap 0, e.g. walls meeting at a corner), then the narrowest real passage between two
    obstacles that do not touch."""
    names = (metrics.min_gap_obstacles or "").split("|")
    if len(names) == 2 and math.isfinite(metrics.min_obstacle_gap):
        gap = (float(metrics.min_obstacle_gap), names[0], names[1])
    else:
        from ..verdict.gaps import min_obstacle_gap
        gap = min_obstacle_gap(scenario)
    still = [o for o in scenario.obstacles if not is_moving(o)]
    if gap[0] > 1e-6 or not 3 <= len(still) <= MAX_GAP_SEARCH:
        return gap
    polys = [obstacle_polygon(o) for o in still]
    best = (math.inf, "", "")
    for i in range(len(polys)):
        for j in range(i + 1, len(polys)):
            d = polys[i].distance(polys[j])
            if 1e-6 < d < best[0]:
                best = (d, still[i].name, still[j].name)
    return best


def speed_norm(results: Sequence[EpisodeResult]):
    """One colour scale for several plots (side by side plots must share it)."""
    from matplotlib.colors import Normalize

    top = max([float(_speed(r).max()) for r in results if len(r.trajectory.t)] + [0.0])
    limit = max([r.scenario.robot.limits.max_speed for r in results] + [top, 0.1])
    return Normalize(0.0, limit)


def _extent(result: EpisodeResult, margin: float = 0.8) -> tuple[float, float, float, float]:
    s = result.scenario
    xs = [s.mission.start.x, s.mission.goal.x] + [w.x for w in s.mission.waypoints]
    ys = [s.mission.start.y, s.mission.goal.y] + [w.y for w in s.mission.waypoints]
    end = float(result.trajectory.t[-1]) if len(result.trajectory.t) else 0.0
    for obs in s.obstacles:
        x0, y0, x1, y1 = obstacle_polygon(obs).bounds
        xs += [x0, x1]
        ys += [y0, y1]
        if is_moving(obs):     # where it went during the episode
            x0, y0, x1, y1 = obstacle_polygon_at(obs, end).bounds
            xs += [x0, x1]
            ys += [y0, y1]
    if len(result.trajectory.t):
        pose = np.asarray(result.trajectory.pose)
        xs += [float(pose[:, 0].min()), float(pose[:, 0].max())]
        ys += [float(pose[:, 1].min()), float(pose[:, 1].max())]
    believed = getattr(result.trajectory, "believed", None)
    if believed is not None and len(believed):
        xs += [float(np.min(believed[:, 0])), float(np.max(believed[:, 0]))]
        ys += [float(np.min(believed[:, 1])), float(np.max(believed[:, 1]))]
    if getattr(s, "terrain", ()):
        from .terrain_plot import terrain_extent
        tx, ty = terrain_extent(s)
        xs += tx
        ys += ty
    return min(xs) - margin, max(xs) + margin, min(ys) - margin, max(ys) + margin


_HALO = dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8)   # behind labels on the map


def draw_obstacles(ax: "Axes", scenario: Any, *, involved: set[str] = frozenset(),  # type: ignore[assignment]
                   labels: LabelPlacer | None = None) -> None:
    """The obstacles as grey polygons, with their names (on maps of more than
    MAX_NAMED_OBSTACLES obstacles, only the ``involved`` ones are named); with ``labels``, the
    names are fixed labels the other labels keep clear of.

    This is the one place that draws the static obstacles; moving ones are drawn by
    ``draw_moving_obstacles`` (they need the episode's times), the step after this one.
    """
    from matplotlib.collections import PolyCollection

    # Collections, not one patch each: patches re-run autoscaling per patch (slow).
    polys = [obstacle_polygon(obs) for obs in scenario.obstacles]
    plane = float(scenario.robot.lidar.mount_height)    # the 2D lidar's plane above the floor

    still = [(obs, p) for obs, p in zip(scenario.obstacles, polys) if not is_moving(obs)]
    glass = [p for obs, p in still if not getattr(obs, "visible_to_lidar", True)]
    seen = [p for obs, p in still if getattr(obs, "visible_to_lidar", True) and obs.height > plane]
    low = [p for obs, p in still if getattr(obs, "visible_to_lidar", True) and obs.height <= plane]
    if glass:   # visible_to_lidar: false (glass): see-through, dashed
        ax.add_collection(PolyCollection([np.asarray(p.exterior.coords) for p in glass], closed=True,
                                         facecolors="#b3e5fc", edgecolors="#0277bd", linewidths=1.0,
                                         linestyles="--", alpha=0.8, zorder=2,
                                         label="unseen by the lidar (glass)"), autolim=False)
    ax.add_collection(PolyCollection([np.asarray(p.exterior.coords) for p in seen], closed=True,
                                     facecolors="#9e9e9e", edgecolors="#424242", linewidths=1.0,
                                     zorder=2), autolim=False)
    if low:     # the lidar cannot see them (they still collide): hatched, in the legend
        ax.add_collection(PolyCollection([np.asarray(p.exterior.coords) for p in low], closed=True,
                                         facecolors="#e0e0e0", edgecolors="#424242", linewidths=1.0,
                                         hatch="////", zorder=2,
                                         label=f"below the lidar ({plane:g} m): unseen"),
                          autolim=False)
    for obs, poly in zip(scenario.obstacles, polys):
        if len(polys) > MAX_NAMED_OBSTACLES and obs.name not in involved:
            continue
        if is_moving(obs):
            continue    # named at its key moments (draw_moving_obstacles)
        at = poly.centroid if poly.contains(poly.centroid) else poly.representative_point()  # a U's notch
        if labels is not None:
            labels.fixed(obs.name, (at.x, at.y), ha="center", va="center", fontsize=7, zorder=8, bbox=_HALO)
        else:
            ax.annotate(obs.name, (at.x, at.y), ha="center", va="center", fontsize=7, zorder=8, bbox=_HALO)


MOVING_COLOUR = "#e65100"


def obstacle_polygon_at(obs: Any, time: float) -> Any:
    """The obstacle's outline where it was at ``time`` (moving obstacles translate)."""
    poly = obstacle_polygon(obs)
    if not is_moving(obs):
        return poly
    from shapely.affinity import translate

    dx, dy = displacement(Track(obs), np.array([time]))[0]
    return translate(poly, float(dx), float(dy))


def moving_key_moments(result: EpisodeResult, obs: Any) -> list[tuple[float, str]]:
    """(time, label) of the moments to draw a moving obstacle at: the start, its closest approach
    to the robot, and the end (labelled with the collision or safety stop that ended it)."""
    traj = result.trajectory
    end = float(traj.t[-1]) if len(traj.t) else 0.0
    moments = [(0.0, "t=0")]
    if len(traj.t) > 1:
        t = np.asarray(traj.t, dtype=float)
        centre = Track(obs).positions(t)
        pose = np.asarray(traj.pose, dtype=float)
        k = int(np.argmin(np.hypot(centre[:, 0] - pose[:, 0], centre[:, 1] - pose[:, 1])))
        if 0 < k < len(t) - 1:
            moments.append((float(t[k]), f"closest t={t[k]:.1f}s"))
    why = ("collision" if result.collision is not None else
           "stop" if result.safety_stop is not None else "end")
    moments.append((end, f"{why} t={end:.1f}s"))
    return moments


def draw_moving_obstacles(ax: "Axes", result: EpisodeResult, labels: LabelPlacer | None = None) -> None:
    """Each moving obstacle: the way it went during the episode (dotted, from where it stood
    to where it was at the end) and its outline at the key moments (moving_key_moments), the
    last one filled, each labelled with its name and time (placed by ``labels`` when given, which
    other labels then keep off the outlines)."""
    from matplotlib.collections import PolyCollection

    traj = result.trajectory
    end = float(traj.t[-1]) if len(traj.t) else 0.0
    for obs in result.scenario.obstacles:
        if not is_moving(obs):
            continue
        times = np.linspace(0.0, end, max(2, int(end / 0.05) + 1))
        way = Track(obs).positions(times)
        ax.plot(way[:, 0], way[:, 1], ls=":", lw=1.4, color=MOVING_COLOUR, zorder=3,
                label="moving obstacle's way" if not ax.get_legend_handles_labels()[1].count(
                    "moving obstacle's way") else None)
        moments = moving_key_moments(result, obs)
        polys = [obstacle_polygon_at(obs, t) for t, _ in moments]
        rings = [np.asarray(p.exterior.coords) for p in polys]
        ax.add_collection(PolyCollection(rings[:-1], closed=True, facecolors="none",
                                         edgecolors=MOVING_COLOUR, linewidths=0.9, linestyles="--",
                                         zorder=5), autolim=False)
        ax.add_collection(PolyCollection(rings[-1:], closed=True, facecolors="#ffcc80",
                                         edgecolors=MOVING_COLOUR, linewidths=1.2, zorder=5),
                          autolim=False)
        for k, ((t, label), poly) in enumerate(zip(moments, polys)):
            text = f"{obs.name} {label}" if k == 0 else label
            style = dict(fontsize=6, color=MOVING_COLOUR, zorder=8, bbox=_HALO)
            if labels is None:
                ax.annotate(text, (poly.centroid.x, poly.centroid.y), xytext=(0, (9, -15, 20)[k % 3]),
                            textcoords="offset points", ha="center", **style)
                continue
            labels.avoid_area(np.asarray(poly.exterior.coords))
            labels.add(text, (poly.centroid.x, poly.centroid.y), priority=4,
                       offsets=ring((10.0, 18.0, 30.0), first=(0, 1)),
                       leader=dict(color=MOVING_COLOUR, lw=0.5, zorder=7), **style)


def _draw_shortest_path(ax: "Axes", scenario: Any) -> None:
    """The shortest collision-free path from start to goal through the waypoints (dashed)."""
    try:
        from ..verdict.paths import shortest_path
        best = shortest_path(scenario)
    except ImportError:  # pragma: no cover
        best = None
    if best is not None:
        pts = np.asarray(best.points)
        ax.plot(pts[:, 0], pts[:, 1], ls="--", lw=1.0, color="#616161", zorder=3,
                label=f"shortest path {best.length:.1f} m")


def _draw_footprint_path(ax: "Axes", result: EpisodeResult, *, norm: Any,
                         outline_every: float | None, labels: LabelPlacer | None = None) -> Any:
    """Where the robot went: the area its footprint swept (the "thick line"), its outline to
    scale every ``outline_every`` seconds, the centre path coloured by speed, and time labels.
    Returns the speed colour mapping, or None without a trajectory."""
    traj = result.trajectory
    if len(traj.t) < 2:
        return None
    fp = result.scenario.robot.footprint
    pose = np.asarray(traj.pose, dtype=float)
    t = np.asarray(traj.t, dtype=float)
    duration = float(t[-1] - t[0])
    _draw_swept_area(ax, fp, pose)
    _draw_outlines(ax, fp, pose, t, outline_every or _nice_step(max(0.5, duration / 25.0)))
    mapping = _draw_speed_path(ax, pose, _speed(result), norm)
    _draw_time_labels(ax, pose, t, duration, labels)
    return mapping


def _draw_believed(ax: "Axes", result: EpisodeResult, labels: LabelPlacer | None = None) -> None:
    """With localisation drift: the path the planner believed it drove (dashed purple, per tick)
    beside the true one, and at the end a line from where it believed it was to where it was."""
    believed = getattr(result.trajectory, "believed", None)
    if believed is None or not len(believed):
        return
    b = np.asarray(believed, dtype=float)
    ax.plot(b[:, 0], b[:, 1], ls="--", lw=1.4, color="#7b1fa2", zorder=6,
            label="believed pose (localisation drift)")
    pose = np.asarray(result.trajectory.pose, dtype=float)
    ax.plot([b[-1, 0], pose[-1, 0]], [b[-1, 1], pose[-1, 1]], ls=":", lw=1.0, color="#7b1fa2", zorder=6)
    ax.plot(b[-1, 0], b[-1, 1], marker="o", ms=5, mfc="white", mec="#7b1fa2", zorder=9, ls="none")
    err = math.hypot(b[-1, 0] - pose[-1, 0], b[-1, 1] - pose[-1, 1])
    _label(ax, labels, f"believed: {err:.2f} m off", (b[-1, 0], b[-1, 1]), (6, -10),
           fontsize=6, color="#7b1fa2", zorder=11, bbox=_HALO)
    if labels is not None:
        labels.avoid((b[-1, 0], b[-1, 1]), 4)


def _draw_swept_area(ax: "Axes", fp: Any, pose: np.ndarray) -> None:
    import shapely
    from matplotlib.collections import PolyCollection

    # a footprint every 5 cm of travel or 10 degrees of turn is enough for the union (fast)
    step = max(1, len(pose) // 1000)
    swept = shapely.union_all(footprint_polygons(fp, pose[_thin(pose, step, 0.05, 10.0)]))
    rings = [np.asarray(g.exterior.coords) for g in getattr(swept, "geoms", [swept]) if not g.is_empty]
    ax.add_collection(PolyCollection(rings, closed=True, facecolors="#90caf9", edgecolors="none",
                                     alpha=0.35, zorder=1, label="swept by the footprint"),
                      autolim=False)


def _draw_outlines(ax: "Axes", fp: Any, pose: np.ndarray, t: np.ndarray, every: float) -> None:
    """The footprint to scale every ``every`` seconds (one outline where the robot stood still)."""
    from matplotlib.collections import PolyCollection

    marks = np.searchsorted(t, np.arange(t[0], t[-1] + 1e-9, every))
    marks = _spread(pose, np.unique(np.append(np.clip(marks, 0, len(t) - 1), len(t) - 1)), 0.25)
    outlines = [np.asarray(p.exterior.coords) for p in footprint_polygons(fp, pose[marks])]
    ax.add_collection(PolyCollection(outlines, closed=True, facecolors="none", edgecolors="#1565c0",
                                     linewidths=0.6, alpha=0.55, zorder=4,
                                     label=f"footprint every {every:g} s"), autolim=False)


def _draw_speed_path(ax: "Axes", pose: np.ndarray, speed: np.ndarray, norm: Any) -> Any:
    """The centre path coloured by speed; returns its colour mapping (for the colour bar)."""
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize

    stride = max(1, len(pose) // 2000)
    xy = pose[::stride, :2]
    segs = np.stack([xy[:-1], xy[1:]], axis=1)
    lc = LineCollection(segs, cmap=SPEED_CMAP, norm=norm or Normalize(0, max(0.1, speed.max())),
                        lw=2.5, zorder=6)
    lc.set_array(speed[::stride][:-1])
    ax.add_collection(lc, autolim=False)
    return lc


def _draw_time_labels(ax: "Axes", pose: np.ndarray, t: np.ndarray, duration: float,
                      labels: LabelPlacer | None = None) -> None:
    """Dots with the time ("2s") at about six nice instants along the path. Where the robot
    dwells (stands, dithers, circles) one stamp is kept per place: a stamp at least 0.4 m of
    travel and 0.75 m in a straight line from every stamp kept before; with ``labels`` a stamp
    whose text would cover another label or a marker is left out."""
    tick = _nice_step(duration / 6.0)
    ticks = np.arange(tick, t[-1], tick)
    idx = np.clip(np.searchsorted(t, ticks), 0, len(t) - 1)
    keep = set(_spread(pose, idx, 0.4).tolist())
    kept: list[np.ndarray] = []
    for tt, i in zip(ticks, idx):
        if i not in keep:  # the robot stood still: one label is enough
            continue
        if any(math.hypot(*(pose[i, :2] - k)) < 0.75 for k in kept):   # back where a stamp is
            continue
        kept.append(pose[i, :2])
        dot = ax.plot(*pose[i, :2], "o", ms=2.5, color="black", zorder=7)
        if labels is None:
            ax.annotate(f"{tt:g}s", pose[i, :2], xytext=(4, -8), textcoords="offset points",
                        fontsize=6, color="#212121", zorder=8)
            continue
        labels.avoid(tuple(pose[i, :2]), 3)
        labels.add(f"{tt:g}s", tuple(pose[i, :2]), optional=True, priority=9, companions=dot,
                   offsets=ring((4.0, 9.0, 16.0), first=(1, -1)), fontsize=6, color="#212121", zorder=8)


def _draw_mission(ax: "Axes", mission: Any, labels: LabelPlacer | None = None) -> None:
    """Start, numbered waypoints, and the goal with its tolerance circle."""
    from matplotlib.patches import Circle

    ax.plot(mission.start.x, mission.start.y, marker="o", ms=8, color="#2e7d32", zorder=9, ls="none",
            label="start")
    for k, w in enumerate(mission.waypoints, 1):
        ax.plot(w.x, w.y, marker="D", ms=6, color="#f9a825", zorder=9, ls="none",
                label="waypoints" if k == 1 else None)
        _label(ax, labels, str(k), (w.x, w.y), (5, 5), fontsize=7)
        if labels is not None:
            labels.avoid((w.x, w.y), 5)
    ax.add_patch(Circle((mission.goal.x, mission.goal.y), mission.goal_tolerance.position,
                        fill=False, ls=":", ec="#2e7d32", zorder=5))
    ax.plot(mission.goal.x, mission.goal.y, marker="*", ms=13, color="#2e7d32", zorder=9, ls="none",
            label="goal")
    if labels is not None:
        labels.avoid((mission.start.x, mission.start.y), 6)
        labels.avoid((mission.goal.x, mission.goal.y), 10)   # the star (13 pt) and a little room


def _label(ax: "Axes", labels: LabelPlacer | None, text: str, xy: tuple[float, float],
           offset: tuple[float, float], **style: Any) -> None:
    """A label at ``offset`` points from ``xy``: through the placer when there is one (the offset
    tried first, then the ring around ``xy``), else written there."""
    if labels is not None:
        labels.add(text, xy, offsets=[offset, *ring()], **style)
    else:
        ax.annotate(text, xy, xytext=offset, textcoords="offset points", **style)


def _nice_step(raw: float) -> float:
    """1, 2 or 5 times a power of ten, at least raw."""
    if not raw > 0 or not math.isfinite(raw):
        return 1.0
    exp = math.floor(math.log10(raw))
    for f in (1, 2, 5, 10):
        if f * 10 ** exp >= raw:
            return f * 10 ** exp
    return 10 ** (exp + 1)


def _thin(pose: np.ndarray, step: int, min_move: float, min_turn_deg: float) -> np.ndarray:
    """Indices (every ``step``-th pose, first and last kept) at least ``min_move`` m or
    ``min_turn_deg`` degrees apart from the previous kept one."""
    idx = np.arange(0, len(pose), step)
    if idx[-1] != len(pose) - 1:
        idx = np.append(idx, len(pose) - 1)
    kept = [0]
    px, py, pyaw = pose[0]
    turn = math.radians(min_turn_deg)
    for i in idx[1:]:
        x, y, yaw = pose[i]
        if (x - px) ** 2 + (y - py) ** 2 >= min_move ** 2 or abs((yaw - pyaw + math.pi) % (2 * math.pi) - math.pi) >= turn:
            kept.append(int(i))
            px, py, pyaw = x, y, yaw
    if kept[-1] != len(pose) - 1:
        kept.append(len(pose) - 1)
    return np.asarray(kept)


def _spread(pose: np.ndarray, idx: np.ndarray, min_move: float) -> np.ndarray:
    """Keep the indices whose pose moved at least ``min_move`` m (or turned 30 degrees) since the
    last kept one, and the last: a robot that stands still gets one outline, not a pile."""
    if len(idx) == 0:
        return idx
    kept = [int(idx[0])]
    for i in idx[1:]:
        last = pose[kept[-1]]
        turn = abs((pose[i, 2] - last[2] + math.pi) % (2 * math.pi) - math.pi)
        if math.hypot(pose[i, 0] - last[0], pose[i, 1] - last[1]) >= min_move or turn >= math.radians(30):
            kept.append(int(i))
    if kept[-1] != int(idx[-1]) and len(idx) > 1:
        kept.append(int(idx[-1]))
    return np.asarray(kept)
