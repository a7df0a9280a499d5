"""The picture at the end of ``navscenario from-bag``: does the seed resemble the run? Left, the
seed as the search sees it (searchable obstacles grey, the fixed background hatched, start,
waypoints, goal); right, the same obstacles with the path the robot drove in the bag, coloured by
time. Both panels share the axes, so a wall that should not cross the path is plain to see."""
from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..scenario.geometry import obstacle_polygon
from .plots import _draw_mission, _figure, as_written, draw_obstacles, save_figure

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def _background(ax: "Axes", scenario: Any) -> None:
    """Hatch the obstacles the search does not move (``search: frozen``)."""
    from matplotlib.collections import PolyCollection

    frozen = set((scenario.search or {}).get("frozen", ()) or ())
    polys = [np.asarray(obstacle_polygon(o).exterior.coords) for o in scenario.obstacles if o.name in frozen]
    if polys:
        ax.add_collection(PolyCollection(polys, closed=True, facecolors="#eeeeee", edgecolors="#757575",
                                         hatch="..", linewidths=0.8, zorder=3,
                                         label="fixed background (search: frozen)"), autolim=False)


def _extent(scenario: Any, recorded: np.ndarray, margin: float = 0.5) -> tuple[float, float, float, float]:
    xs = [recorded[:, 1]] + [np.asarray(obstacle_polygon(o).bounds)[[0, 2]] for o in scenario.obstacles]
    ys = [recorded[:, 2]] + [np.asarray(obstacle_polygon(o).bounds)[[1, 3]] for o in scenario.obstacles]
    m = scenario.mission
    xs.append(np.array([m.start.x, m.goal.x]))
    ys.append(np.array([m.start.y, m.goal.y]))
    x, y = np.concatenate(xs), np.concatenate(ys)
    return float(x.min() - margin), float(x.max() + margin), float(y.min() - margin), float(y.max() + margin)


@as_written
def seed_figure(scenario: Any, recorded: np.ndarray, title: str = "") -> "Figure":
    """Seed (left) beside the recorded path (right); ``recorded``: (n, 3) rows t, x, y."""
    x0, x1, y0, y1 = _extent(scenario, recorded)
    aspect = (y1 - y0) / max(x1 - x0, 1e-6)
    width = 6.0
    fig = _figure(2 * width + 1.0, min(max(width * aspect, 3.0), 10.0) + 0.8)
    axes = fig.subplots(1, 2, sharex=True, sharey=True)
    for ax in axes:
        draw_obstacles(ax, scenario)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.set_xlabel("x (m)")
    _background(axes[0], scenario)
    _draw_mission(axes[0], scenario.mission)
    n_frozen = len((scenario.search or {}).get("frozen", ()) or ())
    axes[0].set_title(f"seed: {len(scenario.obstacles) - n_frozen} searchable, {n_frozen} fixed obstacles",
                      fontsize=10)
    axes[0].set_ylabel("y (m)")
    axes[0].legend(loc="best", fontsize=7)
    line = axes[1].scatter(recorded[:, 1], recorded[:, 2], c=recorded[:, 0], s=3, cmap="viridis", zorder=6)
    axes[1].plot(recorded[0, 1], recorded[0, 2], marker="o", ms=8, color="#2e7d32", ls="none", zorder=9)
    axes[1].set_title(f"recorded path: {len(recorded)} poses in {recorded[-1, 0] - recorded[0, 0]:.1f} s",
                      fontsize=10)
    fig.colorbar(line, ax=axes[1], label="t (s)", shrink=0.8)
    fig.suptitle(title or scenario.name or "seed from a bag", fontsize=11)
    return fig


def save_seed_figure(scenario: Any, recorded: np.ndarray, path: str | os.PathLike) -> Path:
    """Write ``seed_figure`` as PNG (atomically); return the path."""
    return save_figure(seed_figure(scenario, recorded, title=Path(path).stem), path)
