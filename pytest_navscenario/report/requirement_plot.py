"""Requirements in the pictures (issue 34): on the map, the regions a scenario's signals declare
(dashed outlines, named) and where each violated requirement was first violated (a marker at the
robot's position then, in the legend with the requirement and the time); and a figure of each
requirement's signals over time with the thresholds its formula compares them to and the time of
its first violation, for the HTML report and the artifacts."""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..verdict.result import EpisodeResult

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

COLOUR = "#ad1457"          # the requirement outcome's colour (plots.OUTCOME_COLOURS)
REGION_COLOUR = "#00695c"


def _pose_at(result: EpisodeResult, time: float) -> np.ndarray | None:
    traj = result.trajectory
    if not len(traj.t):
        return None
    i = min(int(np.searchsorted(traj.t, time - 1e-9)), len(traj.t) - 1)
    return np.asarray(traj.pose[i], dtype=float)


def draw_requirements(ax: "Axes", result: EpisodeResult, labels: Any = None) -> None:
    """The declared regions and the first violation of each violated requirement, on the map."""
    from matplotlib.patches import Circle, Polygon

    for signal in result.scenario.signals:
        region = signal.inside
        if region is None:
            continue
        if region.radius is not None:
            patch = Circle((region.x, region.y), region.radius, fill=False, ls="--", lw=1.2, ec=REGION_COLOUR,
                           zorder=6)
            at = (region.x, region.y + region.radius)
        else:
            pts = np.asarray(region.points, dtype=float)
            patch = Polygon(pts, closed=True, fill=False, ls="--", lw=1.2, ec=REGION_COLOUR, zorder=6)
            at = (float(pts[:, 0].mean()), float(pts[:, 1].max()))
        ax.add_patch(patch)
        if labels is not None:
            labels.add(signal.name, at, color=REGION_COLOUR, fontsize=7)
    for req in result.requirements:
        if not req.violated or req.first_violation is None:
            continue
        p = _pose_at(result, req.first_violation)
        if p is None:
            continue
        ax.plot(p[0], p[1], marker="D", ms=9, color=COLOUR, mec="white", zorder=13, ls="none",
                label=f"violated {_short(req.name)} t={req.first_violation:.1f} s")
        if labels is not None:
            labels.avoid((p[0], p[1]), 8)


def _short(name: str, width: int = 16) -> str:
    return name if len(name) <= width else name[: width - 1] + "…"


def _thresholds(spec: str) -> dict[str, list[tuple[str, float]]]:
    """signal -> [(comparison, constant)] for every comparison of a signal with a number."""
    from ..stl import parse

    out: dict[str, list[tuple[str, float]]] = {}
    flip = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "==": "==", "!==": "!=="}
    for node in parse(spec).root.walk():
        if len(node.args) == 2 and node.op in flip:
            a, b = node.args
            if a.op == "var" and b.op == "const":
                out.setdefault(a.name, []).append((node.op, b.value))
            elif a.op == "const" and b.op == "var":
                out.setdefault(b.name, []).append((flip[node.op], a.value))
    return out


def requirements_figure(result: EpisodeResult) -> "Figure | None":
    """One panel per requirement: its signals over the episode, its thresholds (dashed) and the
    time it was first violated (a vertical line); None without requirements or a trajectory."""
    if not result.requirements or not len(result.trajectory.t):
        return None
    from matplotlib.figure import Figure

    from ..stl import parse
    from ..verdict.signals import episode_signals, samples, signal_unit

    scenario = result.scenario
    at = samples(scenario, result.trajectory)
    known = {r.name: r for r in scenario.requirements}
    rows = [r for r in result.requirements if r.name in known]
    names = sorted(set().union(*(parse(known[r.name].spec).signals for r in rows)) - {"time"})
    values = episode_signals(scenario, result.trajectory, names, at)
    fig = Figure(figsize=(7.5, 1.9 * len(rows) + 0.3), layout="constrained")
    for k, req in enumerate(rows):
        ax = fig.add_subplot(len(rows), 1, k + 1)
        spec = known[req.name].spec
        used = sorted(parse(spec).signals - {"time"})
        limits = _thresholds(spec)
        for j, name in enumerate(used):
            colour = f"C{j}"
            unit = signal_unit(scenario, name)
            shown = np.where(np.isfinite(values[name]), values[name], np.nan)
            ax.plot(at.times, shown, color=colour, lw=1.4, label=f"{name}" + (f" ({unit})" if unit else ""))
            for op, value in limits.get(name, ()):
                ax.axhline(value, color=colour, ls="--", lw=1.0, label=f"{name} {op} {value:g}")
        if req.violated and req.first_violation is not None:
            ax.axvline(req.first_violation, color=COLOUR, lw=1.6, label=f"first violated t={req.first_violation:.1f} s")
        state = "violated" if req.violated else "kept"
        unit = f" {req.unit}" if req.unit else ""
        ax.set_title(f"{req.name}: {spec}  ({state}, robustness {req.robustness:.3g}{unit})", fontsize=8,
                     color=COLOUR if req.violated else "#2e7d32", loc="left")
        ax.grid(True, color="#dddddd", lw=0.6)
        ax.legend(loc="upper right", fontsize=6, framealpha=0.85)
        ax.tick_params(labelsize=7)
        if k == len(rows) - 1:
            ax.set_xlabel("time (s)", fontsize=8)
    return fig
