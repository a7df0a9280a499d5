"""Pictures engineers debug with: one episode's trajectory, the same scenario under A and B,
and the two-sided bar chart of a comparison.

matplotlib is imported only inside these functions (this module imports cheaply), and only its
object-oriented API with the Agg canvas is used (no pyplot, no global state, no display): safe on
headless CI machines and when called repeatedly from a pytest session.

Trajectory plot contents: obstacles (grey, named), the shortest collision-free path (dashed),
the area the robot's footprint swept (light band, the "thick line") and its outline to scale
every ``outline_every`` seconds, the centre path coloured by speed with a colour bar and time
labels, start / waypoints / goal (with its tolerance circle), the point of minimum clearance
and the narrowest obstacle gap with their values, the collision or safety stop, a grid in
metres, equal aspect and the outcome in the title. ``draw_episode`` draws these in named steps
(``draw_obstacles`` first: the one place where obstacles are drawn, to extend for new kinds).
On terrain (``terrain_plot.py``) the map is shaded by the ground's height with contour lines, the
elements outlined and named, falls and tip-overs marked, and a side profile of the route (the
ground under it, the base's height and pitch against the distance driven) is drawn under the map.
"""
from __future__ import annotations

import functools
import io
import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

from ..scenario.geometry import footprint_polygon, footprint_polygons, obstacle_polygon
from .labels import LabelPlacer, ring
from ..scenario.motion import Track, displacement, is_moving
from ..verdict.result import EpisodeResult

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .compare import Comparison

OUTCOME_COLOURS = {"success": "#2e7d32", "collision": "#c62828", "safety-stop": "#ef6c00",
                   "timeout": "#6a1b9a", "subject-error": "#37474f", "fall": "#8d1b1b"}
A_COLOUR, B_COLOUR = "#7f9fbf", "#1f4e79"
SPEED_CMAP = "viridis"
MAX_NAMED_OBSTACLES = 40   # more obstacles than this: only the ones involved are named
MAX_GAP_SEARCH = 200       # touching obstacles: look for the narrowest real gap among at most this many


def as_written(build: Callable[..., "Figure"]) -> Callable[..., "Figure"]:
    """Build the figure with matplotlib's mathtext off: the names it shows are the user's, drawn as
    written ('$' in an obstacle's name started mathtext: 'x$\\frac{$y' made the plot fail, 'cost $5
    and $x' lost its dollars). matplotlib's rcParams are left as they were."""
    @functools.wraps(build)
    def wrapper(*args: Any, **kwargs: Any) -> "Figure":
        import matplotlib

        with matplotlib.rc_context({"text.parse_math": False}):
            return build(*args, **kwargs)
    return wrapper


def _figure(width: float, height: float, constrained: bool = True) -> "Figure":
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=100, layout="constrained" if constrained else None)
    FigureCanvasAgg(fig)
    return fig


def png_bytes(fig: "Figure", dpi: int = 100) -> bytes:
    """The figure as PNG bytes (for embedding in HTML)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def save_figure(fig: "Figure", path: str | os.PathLike, dpi: int = 100) -> Path:
    """Write the figure as PNG atomically (a temporary file, then a rename); return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_bytes(png_bytes(fig, dpi))
    os.replace(tmp, path)
    return path


# ------------------------------------------------------------------------------ trajectory plot

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
    """The narrowest obstacle gap to mark: the metric's (gaps.min_obstacle_gap), unless obstacles
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


def draw_episode(ax: "Axes", result: EpisodeResult, *, norm: Any = None,
                 outline_every: float | None = None, title: str | None = None,
                 legend: bool = False, labels: LabelPlacer | None = None, ground_scale: bool = True) -> Any:
    """Draw one episode on ``ax``; return the speed colour mapping (for a colour bar) or None.

    The picture is made in named steps, back to front: the obstacles, the shortest path, the
    footprint's path (swept area, outlines, centre line coloured by speed, time labels), the
    mission (start, waypoints, goal), the key moments (minimum clearance, narrowest gap,
    collision, safety stop, or where the robot ended when it did neither and missed the goal),
    then the axes (limits, grid, labels, legend, title). Artists are added as collections with
    ``autolim=False``: the limits are set once, at the end. The steps ask for their text labels
    and say where their markers are; the labels are placed last, clear of each other and of the
    markers (labels.py). Pass ``labels`` to place them yourself later (``labels.place()``, once
    the limits are final: side-by-side panels share theirs).
    """
    s = result.scenario
    placer = labels if labels is not None else LabelPlacer(ax)
    if getattr(s, "terrain", ()):     # the ground's height under everything (terrain_plot.py)
        from .terrain_plot import draw_terrain
        draw_terrain(ax, s, _extent(result), colorbar=ground_scale)
    draw_obstacles(ax, s, involved=_involved_obstacles(result), labels=placer)
    draw_moving_obstacles(ax, result, labels=placer)
    _draw_shortest_path(ax, s)
    mapping = _draw_footprint_path(ax, result, norm=norm, outline_every=outline_every, labels=placer)
    _draw_believed(ax, result, placer)
    _draw_mission(ax, s.mission, placer)
    _draw_min_clearance(ax, result, placer)
    _draw_narrowest_gap(ax, s, result.metrics, placer)
    _draw_events(ax, result, placer)
    _draw_end(ax, result, placer)
    _finish_axes(ax, result, title=title, legend=legend)
    if labels is None:
        placer.place()
    return mapping


def _involved_obstacles(result: EpisodeResult) -> set[str]:
    """The obstacles the episode's story is about (closest, the narrowest gap's, the one hit)."""
    m = result.metrics
    return {m.min_clearance_obstacle, *(m.min_gap_obstacles or "").split("|"),
            result.collision.obstacle if result.collision else "",
            result.safety_stop.obstacle if result.safety_stop else ""}


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
        labels.avoid((mission.goal.x, mission.goal.y), 8)


def _label(ax: "Axes", labels: LabelPlacer | None, text: str, xy: tuple[float, float],
           offset: tuple[float, float], **style: Any) -> None:
    """A label at ``offset`` points from ``xy``: through the placer when there is one (the offset
    tried first, then the ring around ``xy``), else written there."""
    if labels is not None:
        labels.add(text, xy, offsets=[offset, *ring()], **style)
    else:
        ax.annotate(text, xy, xytext=offset, textcoords="offset points", **style)


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
    try:
        obstacle = obstacle_polygon_at(s.obstacle(m.min_clearance_obstacle), m.min_clearance_time)
    except KeyError:
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
    free = [tuple(r * d) for r in (28.0, 44.0)]     # on the free side first, then anywhere near
    labels.add(text, (a.x, a.y), priority=1, offsets=free + ring((28.0, 44.0, 64.0)),
               leader=dict(color="#d50000", lw=0.6, zorder=10), **style)


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
    ax.plot(x, y, marker="s", ms=8, color=colour, mec="white", zorder=12, ls="none",
            label=f"end: {result.outcome.value} at t={float(traj.t[-1]):.1f} s")
    if labels is not None:
        labels.avoid((x, y), 7)


def _finish_axes(ax: "Axes", result: EpisodeResult, *, title: str | None, legend: bool) -> None:
    """Limits around everything drawn, equal aspect, a grid in metres, labels, legend, title."""
    from matplotlib.ticker import MultipleLocator

    x0, x1, y0, y1 = _extent(result)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box")
    major = _nice_step(max(x1 - x0, y1 - y0) / 8.0)
    ax.xaxis.set_major_locator(MultipleLocator(major))
    ax.yaxis.set_major_locator(MultipleLocator(major))
    ax.grid(True, which="major", color="#bdbdbd", lw=0.6, zorder=0)
    ax.set_axisbelow(True)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if legend:
        ax.legend(loc="best", fontsize=7, framealpha=0.85)
    outcome = result.outcome.value
    ax.set_title(title if title is not None else episode_title(result), fontsize=9,
                 color=OUTCOME_COLOURS.get(outcome, "black"))


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


def episode_title(result: EpisodeResult, prefix: str = "", width: int = 60) -> str:
    """Name, outcome and subject, then the outcome's message wrapped to ``width`` characters."""
    import textwrap

    s = result.scenario
    name = s.name + (f" [{s.family}]" if s.family and s.family != s.name else "")
    subject = result.subject + (f" {result.subject_version}" if result.subject_version else "")
    message = textwrap.shorten(result.message, 2 * width, placeholder="...")
    wrapped = textwrap.fill(message, width, break_on_hyphens=False) if message else ""
    head = textwrap.fill(f"{prefix}{name}: {result.outcome.value.upper()} ({subject})", width,
                         break_on_hyphens=False)
    return head + (f"\n{wrapped}" if wrapped else "")


# Fixed layout in inches (no constrained layout: it re-measures every text and costs ~40 % of a plot).
_LEFT, _GAP, _RIGHT, _TOP, _BOTTOM = 0.75, 0.35, 2.1, 0.85, 1.25
_CBAR_H, _CBAR_Y = 0.14, 0.42


def _figsize(results: Sequence[EpisodeResult], panels: int) -> tuple[float, float]:
    """Figure size (inches) for ``panels`` maps side by side, each with the maps' aspect ratio
    (and the side profile under them on terrain)."""
    pw, ph = _panel_size(results)
    return _LEFT + panels * pw + (panels - 1) * _GAP + _RIGHT, _BOTTOM + ph + _TOP + _profile_height(results)


def _profile_height(results: Sequence[EpisodeResult]) -> float:
    """Inches of side profile under the maps: only where the ground is not flat."""
    if not any(getattr(r.scenario, "terrain", ()) for r in results):
        return 0.0
    from .terrain_plot import PROFILE_HEIGHT
    return PROFILE_HEIGHT


def _panel_size(results: Sequence[EpisodeResult]) -> tuple[float, float]:
    boxes = [_extent(r) for r in results]
    w = max(b[1] for b in boxes) - min(b[0] for b in boxes)
    h = max(b[3] for b in boxes) - min(b[2] for b in boxes)
    aspect = w / max(h, 1e-6)
    ph = 6.0
    pw = float(np.clip(ph * aspect, 2.6, 9.0 if len(results) == 1 else 6.5))
    ph = float(np.clip(pw / aspect, 2.6, 7.0))
    return round(pw, 2), round(ph, 2)


def _map_figure(results: Sequence[EpisodeResult]) -> tuple["Figure", list["Axes"], "Axes"]:
    """A figure with one map panel per result (shared axes), and an axes for the speed colour bar."""
    n = len(results)
    pw, ph = _panel_size(results)
    fw, fh = _figsize(results, n)
    fig = _figure(fw, fh, constrained=False)
    axes: list[Axes] = []
    up = _profile_height(results)          # the side profile goes under the maps
    for k in range(n):
        rect = ((_LEFT + k * (pw + _GAP)) / fw, (_BOTTOM + up) / fh, pw / fw, ph / fh)
        ax = fig.add_axes(rect, sharex=axes[0] if axes else None, sharey=axes[0] if axes else None)
        if k:
            ax.tick_params(labelleft=False)
        axes.append(ax)
    span = n * pw + (n - 1) * _GAP
    cw = min(span, 5.0)
    cax = fig.add_axes(((_LEFT + (span - cw) / 2) / fw, (_CBAR_Y + up) / fh, cw / fw, _CBAR_H / fh))
    return fig, axes, cax


def _draw_profile(fig: "Figure", results: Sequence[EpisodeResult], labels: Sequence[str] = (),
                  colours: Sequence[str] = ()) -> None:
    """The side profile of the routes under the maps (terrain_plot.draw_profile), when on terrain."""
    up = _profile_height(results)
    if not up:
        return
    from .terrain_plot import draw_profile
    fw, fh = fig.get_size_inches()
    ax = fig.add_axes((_LEFT / fw, 0.45 / fh, (fw - _LEFT - _RIGHT) / fw, (up - 0.75) / fh))
    draw_profile(ax, results, labels, colours)


def _figure_legend(fig: "Figure", axes: Sequence["Axes"]) -> None:
    """One legend for all panels, right of the maps so it never hides the goal or an obstacle."""
    seen: dict[str, Any] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(label, handle)
    if seen:
        fw, fh = fig.get_size_inches()
        fig.legend(list(seen.values()), list(seen), loc="upper left", fontsize=7, frameon=False,
                   bbox_to_anchor=((fw - _RIGHT + 0.1) / fw, 1 - _TOP / fh))


def _colorbar(fig: "Figure", mapping: Any, cax: "Axes") -> None:
    if mapping is None:
        cax.set_visible(False)
        return
    fig.colorbar(mapping, cax=cax, orientation="horizontal", label="speed (m/s)")


@as_written
def trajectory_figure(result: EpisodeResult, *, outline_every: float | None = None) -> "Figure":
    """One episode: the figure (see the module docstring for what it shows)."""
    fig, (ax,), cax = _map_figure([result])
    width = max(30, int((_panel_size([result])[0] + 1.0) / 0.075))  # title may overhang the map a bit
    mapping = draw_episode(ax, result, outline_every=outline_every, title=episode_title(result, width=width))
    _figure_legend(fig, [ax])
    _colorbar(fig, mapping, cax)
    _draw_profile(fig, [result])
    return fig


def save_trajectory(result: EpisodeResult, path: str | os.PathLike, **kwargs: Any) -> Path:
    """Write the trajectory plot of one episode as PNG (100 dpi, sized to the map)."""
    return save_figure(trajectory_figure(result, **kwargs), path)


@as_written
def comparison_figure(a: EpisodeResult, b: EpisodeResult, labels: tuple[str, str] = ("A", "B")) -> "Figure":
    """The same scenario under A and B side by side, same axes and the same speed colours."""
    fig, axes, cax = _map_figure([a, b])
    norm = speed_norm([a, b])
    mapping = None
    # outlines as dense as the shorter run needs (where a robot stood still they are thinned anyway)
    every = _nice_step(max(0.5, min(a.trajectory.duration or 1e9, b.trajectory.duration or 1e9, 100.0) / 25.0))
    width = max(30, int(_panel_size([a, b])[0] / 0.075))  # characters per title line, one panel
    placers = [LabelPlacer(ax) for ax in axes]
    for ax, res, label, placer in zip(axes, (a, b), labels, placers):
        mapping = draw_episode(ax, res, norm=norm, outline_every=every, labels=placer, ground_scale=ax is axes[-1],
                               title=episode_title(res, prefix=f"{label}: ", width=width)) or mapping
    boxes = [_extent(r) for r in (a, b)]  # the shared axes must show both runs whole
    axes[0].set_xlim(min(x[0] for x in boxes), max(x[1] for x in boxes))
    axes[0].set_ylim(min(x[2] for x in boxes), max(x[3] for x in boxes))
    for placer in placers:   # now that the shared limits are final
        placer.place()
    axes[1].set_ylabel("")
    _figure_legend(fig, axes)
    _colorbar(fig, mapping, cax)
    _draw_profile(fig, [a, b], labels, (A_COLOUR, B_COLOUR))
    return fig


def save_comparison(a: EpisodeResult, b: EpisodeResult, path: str | os.PathLike,
                    labels: tuple[str, str] = ("A", "B")) -> Path:
    """Write the side-by-side plot of one scenario under A and B as PNG (100 dpi)."""
    return save_figure(comparison_figure(a, b, labels), path)


# ------------------------------------------------------------------------------- bar chart

FAILURE_HATCHES = {"safety-stop": "///", "timeout": "..", "collision": "xx", "subject-error": "--"}


@as_written
def bars_figure(cmp: "Comparison") -> "Figure":
    """The paper's two-sided bar chart, with every way of failing: per family, the success rate
    up and the failures down, stacked by outcome (safety stop, timeout, collision, subject error;
    each hatched its own way, its share written inside when there is room), A beside B. Error
    bars: 95 % Wilson intervals of the success rate (up) and of all failures together (down);
    n and McNemar's p under each family."""
    from matplotlib.patches import Patch

    rows = list(cmp.families) + ([cmp.overall] if len(cmp.families) > 1 else [])
    fig = _figure(max(6.0, 1.5 + 1.3 * len(rows)), 5.8)
    ax = fig.add_subplot()
    x = np.arange(len(rows), dtype=float)
    width = 0.38
    failing = [o for o in FAILURE_HATCHES
               if any(getattr(r, side)[o].count for r in rows for side in ("a", "b"))] or ["safety-stop"]
    halo = dict(boxstyle="square,pad=0.1", fc="white", ec="none", alpha=0.7)
    for side, offset, colour, name, subject in (("a", -width / 2, A_COLOUR, "A", cmp.a_subject),
                                                ("b", width / 2, B_COLOUR, "B", cmp.b_subject)):
        rates = [getattr(r, side) for r in rows]
        ok = np.array([0.0 if rt["success"].n == 0 else 100 * rt["success"].rate for rt in rates])
        err = np.maximum(np.array([[100 * (rt["success"].rate - rt["success"].low) if rt["success"].n else 0 for rt in rates],
                                   [100 * (rt["success"].high - rt["success"].rate) if rt["success"].n else 0 for rt in rates]]), 0.0)
        label = f"{name}: {subject}" if len(subject) < 40 else name
        ax.bar(x + offset, ok, width, color=colour, ec=colour, label=label, yerr=err, capsize=3,
               error_kw=dict(lw=0.8, ecolor="#424242"), zorder=3)
        for xi, v in zip(x + offset, ok):
            ax.annotate(f"{v:.0f}%", (xi, v), xytext=(0, 3), textcoords="offset points", ha="center",
                        va="bottom", fontsize=7, zorder=4, bbox=halo)
        bottom = np.zeros(len(rows))
        for outcome in failing:
            vals = np.array([0.0 if rt[outcome].n == 0 else 100 * rt[outcome].rate for rt in rates])
            ax.bar(x + offset, -vals, width, bottom=-bottom, color=colour, hatch=FAILURE_HATCHES[outcome],
                   ec="white", lw=0.5, zorder=3)
            total = np.array([sum(100 * rt[o].rate for o in failing if rt[o].n) for rt in rates])
            for xi, b0, v, t in zip(x + offset, bottom, vals, total):
                if v >= 9 and v < t - 0.5:   # room for the share inside, and not the whole stack
                    ax.annotate(f"{v:.0f}%", (xi, -(b0 + v / 2)), ha="center", va="center", fontsize=6.5,
                                zorder=4, bbox=halo)
            bottom += vals
        # all failures together: the interval of 1 - success, below the stack
        low = np.array([[100 * (rt["success"].high - rt["success"].rate) if rt["success"].n else 0 for rt in rates],
                        [100 * (rt["success"].rate - rt["success"].low) if rt["success"].n else 0 for rt in rates]])
        ax.errorbar(x + offset, -bottom, yerr=np.maximum(low, 0.0), fmt="none", ecolor="#424242",
                    elinewidth=0.8, capsize=3, zorder=4)
        for xi, v in zip(x + offset, bottom):
            ax.annotate(f"{v:.0f}%", (xi, -v), xytext=(0, -3), textcoords="offset points", ha="center",
                        va="top", fontsize=7, zorder=4, bbox=halo)
    if not rows or not cmp.pairs:
        ax.text(0.5, 0.5, "no comparable scenario pairs:\nsee the 'only in A / only in B / not comparable' lists",
                transform=ax.transAxes, ha="center", va="center", fontsize=10, color="#c62828")
    ax.axhline(0, color="black", lw=0.8)
    ax.set_xticks(x, [f"{r.family}\nn={r.n}" + (f"\np={r.mcnemar_p:.2g}" if r.n else "") for r in rows],
                  fontsize=8)
    ax.set_ylim(-118, 115)
    ticks = np.arange(-100, 101, 25)
    ax.set_yticks(ticks, [f"{abs(t)}" for t in ticks])
    ax.set_ylabel("failed %   |   success %")
    ax.grid(True, axis="y", color="#e0e0e0", zorder=0)
    ax.set_title(f"Success (up) and failures by outcome (down) per family, A vs B\n"
                 f"A = {cmp.a_subject}   B = {cmp.b_subject}   (error bars: 95 % Wilson; p: McNemar)",
                 fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    handles += [Patch(facecolor="white", edgecolor="#424242", hatch=FAILURE_HATCHES[o], label=o) for o in failing]
    labels += failing
    ax.legend(handles, labels, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.18),
              ncol=2 + len(failing), frameon=False)
    return fig


def save_bars(cmp: "Comparison", path: str | os.PathLike) -> Path:
    """Write the two-sided bar chart of a comparison as PNG."""
    return save_figure(bars_figure(cmp), path)
