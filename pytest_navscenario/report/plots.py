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

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from .bars import FAILURE_HATCHES, bars_figure, save_bars  # noqa: F401  (the public names of this module)
from .figures import _figure, as_written, png_bytes, save_figure  # noqa: F401
from .labels import LabelPlacer
from .requirement_plot import draw_requirements
from .map_moments import (  # noqa: F401
    OUTCOME_COLOURS,
    _draw_culprit_clearance,
    _draw_end,
    _draw_events,
    _draw_min_clearance,
    _draw_narrowest_gap,
)
from .map_parts import (  # noqa: F401
    MAX_GAP_SEARCH,
    MAX_NAMED_OBSTACLES,
    MOVING_COLOUR,
    SPEED_CMAP,
    _draw_believed,
    _draw_footprint_path,
    _draw_mission,
    _draw_shortest_path,
    _extent,
    _nice_step,
    draw_moving_obstacles,
    draw_obstacles,
    moving_key_moments,
    obstacle_polygon_at,
    speed_norm,
)
from ..verdict.result import EpisodeResult

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

A_COLOUR, B_COLOUR = "#7f9fbf", "#1f4e79"


def draw_episode(ax: "Axes", result: EpisodeResult, *, norm: Any = None,
                 outline_every: float | None = None, title: str | None = None,
                 legend: bool = False, labels: LabelPlacer | None = None, ground_scale: bool = True) -> Any:
    """Draw one episode on ``ax``; return the speed colour mapping (for a colour bar) or None.

    The picture is made in named steps, back to front: the obstacles, the shortest path, the
    footprint's path (swept area, outlines, centre line coloured by speed, time labels), the
    mission (start, waypoints, goal), the key moments (minimum clearance, narrowest gap,
    collision, safety stop, a requirement's first violation and the regions it names
    (requirement_plot.py), or where the robot ended when it did neither and missed the goal),
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
        draw_terrain(ax, s, _extent(result), colorbar=ground_scale, labels=placer)
    draw_obstacles(ax, s, involved=_involved_obstacles(result), labels=placer)
    draw_moving_obstacles(ax, result, labels=placer)
    _draw_shortest_path(ax, s)
    mapping = _draw_footprint_path(ax, result, norm=norm, outline_every=outline_every, labels=placer)
    _draw_believed(ax, result, placer)
    _draw_mission(ax, s.mission, placer)
    _draw_min_clearance(ax, result, placer)
    _draw_culprit_clearance(ax, result, placer)
    _draw_narrowest_gap(ax, s, result.metrics, placer)
    _draw_events(ax, result, placer)
    draw_requirements(ax, result, placer)
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


def _finish_axes(ax: "Axes", result: EpisodeResult, *, title: str | None, legend: bool) -> None:
    """Limits around everything drawn, equal aspect, a grid in metres, labels, legend, title."""
    from matplotlib.ticker import MultipleLocator

    x0, x1, y0, y1 = _extent(result)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box")
    major = _nice_step(max(x1 - x0, y1 - y0) / 8.0)
    ax.xaxis.set_major_locator(MultipleLocator(major))
    # a wide, low map (a long ramp, a dock) keeps at least three y ticks: its own, finer step
    ax.yaxis.set_major_locator(MultipleLocator(major if (y1 - y0) / major >= 3 else _nice_step((y1 - y0) / 4.0)))
    ax.grid(True, which="major", color="#bdbdbd", lw=0.6, zorder=0)
    ax.set_axisbelow(True)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if legend:
        ax.legend(loc="best", fontsize=7, framealpha=0.85)
    outcome = result.outcome.value
    ax.set_title(title if title is not None else episode_title(result), fontsize=9,
                 color=OUTCOME_COLOURS.get(outcome, "black"))


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
        import textwrap

        fw, fh = fig.get_size_inches()
        # wrapped to the margin's width (a 7 pt character is ~0.06 in, the marker takes ~0.45 in):
        # "fell off platform 'dock' t=4.3 s, 1.2 m drop" was cut at the figure's right edge
        width = max(16, int((_RIGHT - 0.1 - 0.45) / 0.06))
        texts = [textwrap.fill(label, width, break_on_hyphens=False) for label in seen]
        fig.legend(list(seen.values()), texts, loc="upper left", fontsize=7, frameon=False,
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
