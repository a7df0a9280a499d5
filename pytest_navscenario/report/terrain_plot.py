"""Terrain in the pictures: the map shaded by the ground's height with contour lines and the
elements' outlines and names, where the robot fell, tipped over or got stuck, and a side profile of
the route (the ground under it, the base's height, its pitch and roll along the distance driven).

Called by ``plots.py`` (maps, side-by-side) and ``html.py`` (the time-slider's shading) only for
scenarios with terrain: a flat scenario's pictures are unchanged. matplotlib is imported inside the
functions, as in ``plots.py``.
"""
from __future__ import annotations

import base64
import io
import math
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ..scenario.ground import surface as ground

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

MAX_SAMPLES = 320            # ground samples along the longer side of the map's shading
# below the floor blue (pits, stairwells), the floor itself near white, above it green to brown
TERRAIN_COLOURS = ((0.0, "#0d47a1"), (0.35, "#64b5f6"), (0.5, "#fafafa"), (0.62, "#c5e1a5"),
                   (0.8, "#bcaaa4"), (1.0, "#5d4037"))
EVENT_MARKERS = {"fell": ("v", "#8d1b1b", "fell"), "tipped": ("*", "#8d1b1b", "tipped over"),
                 "stuck": ("s", "#6a1b9a", "stuck"), "still": ("o", "#6a1b9a", "did not move")}
PROFILE_HEIGHT = 2.1         # inches added under the map for the side profile


def has_terrain(scenario: Any) -> bool:
    return bool(getattr(scenario, "terrain", ()))


def ground_grid(scenario: Any, extent: tuple[float, float, float, float], samples: int = MAX_SAMPLES
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x (nx,), y (ny,), heights (ny, nx)): the ground over ``extent`` = (x0, x1, y0, y1), at most
    ``samples`` points along its longer side (cell centres)."""
    x0, x1, y0, y1 = extent
    step = max(x1 - x0, y1 - y0) / samples
    xs = np.arange(x0 + step / 2, x1, step)
    ys = np.arange(y0 + step / 2, y1, step)
    gx, gy = np.meshgrid(xs, ys)
    return xs, ys, ground.ground_height(scenario, gx, gy)


def _cmap() -> Any:
    from matplotlib.colors import LinearSegmentedColormap
    return LinearSegmentedColormap.from_list("navscenario-ground", TERRAIN_COLOURS)


def _norm(heights: np.ndarray) -> Any:
    """Colours centred on the floor: below it in blues, above it from green to brown."""
    from matplotlib.colors import TwoSlopeNorm

    low, high = float(np.nanmin(heights)), float(np.nanmax(heights))
    reach = max(abs(low), abs(high), 0.05)
    return TwoSlopeNorm(vcenter=0.0, vmin=min(low, -reach * 0.6), vmax=max(high, reach * 0.6))


def draw_terrain(ax: "Axes", scenario: Any, extent: tuple[float, float, float, float], *,
                 colorbar: bool = True, labels: Any = None) -> Any:
    """The ground's height as shading and contour lines under everything else, the elements'
    outlines with their names, and (``colorbar``) a height scale right of the map, under the
    legend; returns the shading. With ``labels`` (a labels.LabelPlacer) the names are placed
    clear of the other labels and the markers (the goal, a gap's width), on the element when
    there is room, else beside it."""
    from matplotlib.collections import PolyCollection

    xs, ys, z = ground_grid(scenario, extent)
    x0, x1, y0, y1 = extent
    shade = ax.imshow(z, origin="lower", extent=(xs[0] - (xs[1] - xs[0]) / 2, xs[-1] + (xs[1] - xs[0]) / 2,
                                                 ys[0] - (ys[1] - ys[0]) / 2, ys[-1] + (ys[1] - ys[0]) / 2),
                      cmap=_cmap(), norm=_norm(z), alpha=0.6, zorder=0.2, interpolation="nearest")
    span = float(np.nanmax(z) - np.nanmin(z))
    if span > 1e-6:
        step = _nice(span / 8.0)
        levels = np.arange(math.floor(np.nanmin(z) / step) * step, np.nanmax(z) + step, step)
        # unlabelled: on steps and walls the lines bunch up (the scale on the right reads them)
        ax.contour(xs, ys, z, levels=levels, colors="#5d4037", linewidths=0.5, alpha=0.6, zorder=0.3)
    if colorbar:
        cax = ax.inset_axes((1.03, 0.0, 0.035, 0.42))
        bar = ax.figure.colorbar(shade, cax=cax)
        bar.set_label("ground (m)", fontsize=7)
        bar.ax.tick_params(labelsize=6)
    outlines = [ground.outline(el) for el in scenario.terrain]
    ax.add_collection(PolyCollection(outlines, closed=True, facecolors="none", edgecolors="#4e342e",
                                     linewidths=0.9, zorder=1.5), autolim=False)
    style = dict(fontsize=6.5, color="#3e2723", zorder=8,
                 bbox=dict(boxstyle="round,pad=0.12", fc="#fff8e1", ec="none", alpha=0.75))
    for el, corners in zip(scenario.terrain, outlines):
        cx, cy = corners.mean(axis=0)
        if not (x0 <= cx <= x1 and y0 <= cy <= y1):
            continue
        if labels is None:
            ax.annotate(ground.describe_element(el), (cx, cy), ha="center", va="center", **style)
        else:
            from .labels import ring
            labels.add(ground.describe_element(el), (float(cx), float(cy)), priority=3,
                       offsets=[(0.0, 0.0), *ring((10.0, 22.0, 40.0, 64.0))], **style)
    return shade


def draw_terrain_event(ax: "Axes", result: Any) -> None:
    """Where the robot fell, tipped over or got stuck (a marker with the time in the legend)."""
    event = getattr(result, "terrain_event", None)
    if event is None:
        return
    marker, colour, what = EVENT_MARKERS.get(event.kind, ("X", "#8d1b1b", event.kind))
    where = f" {event.element}" if event.element else ""
    extra = f", {event.drop:.2f} m drop" if event.kind == "fell" and event.drop else ""
    ax.plot(event.x, event.y, marker=marker, ms=13, color=colour, mec="white", zorder=13, ls="none",
            label=f"{what}{where} t={event.time:.1f} s{extra}")


def route_profile(result: Any) -> dict[str, np.ndarray]:
    """Along the route: distance driven (m, horizontal), the ground under the base, the base's
    height (the ground for the planar body), its pitch (degrees, positive nose up) and its roll
    (degrees)."""
    traj = result.trajectory
    pose = np.asarray(traj.pose, dtype=float)
    if not len(pose):
        return {"s": np.zeros(0), "ground": np.zeros(0), "z": np.zeros(0), "pitch": np.zeros(0),
                "roll": np.zeros(0)}
    step = np.hypot(np.diff(pose[:, 0]), np.diff(pose[:, 1]))
    dist = np.concatenate([[0.0], np.cumsum(step)])
    under = ground.ground_height(result.scenario, pose[:, 0], pose[:, 1])
    z = np.asarray(traj.z, dtype=float) if getattr(traj, "z", None) is not None else under
    pitch = (-np.degrees(np.asarray(traj.pitch, dtype=float)) if getattr(traj, "pitch", None) is not None
             else np.zeros(len(pose)))
    roll = (np.degrees(np.asarray(traj.roll, dtype=float)) if getattr(traj, "roll", None) is not None
            else np.zeros(len(pose)))
    return {"s": dist, "ground": under, "z": z, "pitch": pitch, "roll": roll}


def draw_profile(ax: "Axes", results: Sequence[Any], labels: Sequence[str] = (), colours: Sequence[str] = ()
                 ) -> None:
    """The side profile: the ground under each route (shaded), the base's height (a line) and its
    pitch (dashed) and roll (dotted) on the right-hand axis in degrees, against the distance
    driven; so a tip-over by roll shows as plainly as one by pitch."""
    twin = ax.twinx()
    top, angles = 0.0, [0.0]
    for k, result in enumerate(results):
        prof = route_profile(result)
        if not len(prof["s"]):
            continue
        colour = colours[k] if k < len(colours) else "#1f4e79"
        label = f"{labels[k]}: " if k < len(labels) else ""
        if k == 0:
            floor = min(0.0, float(prof["ground"].min())) - 0.1
            ax.fill_between(prof["s"], floor, prof["ground"], color="#a1887f", alpha=0.55, lw=0,
                            label="ground under the route")
        ax.plot(prof["s"], prof["z"], color=colour, lw=1.4, label=f"{label}base height")
        twin.plot(prof["s"], prof["pitch"], color=colour, lw=1.0, ls="--", alpha=0.8, label=f"{label}pitch")
        twin.plot(prof["s"], prof["roll"], color="#c2185b" if len(results) == 1 else colour, lw=1.0, ls=":",
                  alpha=0.9, label=f"{label}roll")
        angles += [float(np.nanmin(prof["pitch"])), float(np.nanmax(prof["pitch"])),
                   float(np.nanmin(prof["roll"])), float(np.nanmax(prof["roll"]))]
        _profile_event(ax, result, prof, label)
        top = max(top, float(prof["s"][-1]))
    ax.set_xlim(0.0, max(top, 0.1) * 1.02)          # room for a marker at the end
    ax.set_xlabel("distance driven (m)")
    ax.set_ylabel("height (m)")
    _angle_axis(twin, angles)
    ax.grid(True, color="#e0e0e0", lw=0.5)
    handles = ax.get_legend_handles_labels()
    extra = twin.get_legend_handles_labels()
    # right of the profile, beside its angle axis, in the figure's right margin: inside the plot
    # it covered the base's height where the route starts at the top
    import textwrap

    width_in = ax.get_position().width * ax.figure.get_size_inches()[0]
    names = [textwrap.fill(n, 24, break_on_hyphens=False) for n in handles[1] + extra[1]]
    ax.legend(handles[0] + extra[0], names, loc="upper left", fontsize=6.5, frameon=False,
              bbox_to_anchor=(1.0 + 0.6 / width_in, 1.04), borderaxespad=0.0, handlelength=1.8)


def _profile_event(ax: "Axes", result: Any, prof: dict[str, np.ndarray], label: str) -> None:
    """Where the robot fell, tipped over or got stuck, on the base's height line."""
    event = getattr(result, "terrain_event", None)
    if event is None:
        return
    i = int(np.argmin(np.abs(np.asarray(result.trajectory.t) - event.time)))
    marker, c, what = EVENT_MARKERS.get(event.kind, ("X", "#8d1b1b", event.kind))
    ax.plot(prof["s"][i], prof["z"][i], marker=marker, ms=10, color=c, mec="white", ls="none",
            zorder=5, label=f"{label}{what}")


def _angle_axis(twin: "Axes", angles: list[float]) -> None:
    """The right-hand axis of pitch and roll: plain degrees (no offset text such as
    "1e-12+9.999993304e-1", which read as 9 degrees for one) over at least -5..5 degrees, so that
    noise in a flat drive is not blown up to fill the axis."""
    from matplotlib.ticker import ScalarFormatter

    lo, hi = min(min(angles), -5.0), max(max(angles), 5.0)
    pad = 0.08 * (hi - lo)
    twin.set_ylim(lo - pad, hi + pad)
    formatter = ScalarFormatter(useOffset=False)
    formatter.set_scientific(False)
    twin.yaxis.set_major_formatter(formatter)
    twin.set_ylabel("pitch (nose up), roll (deg)", fontsize=8)
    twin.tick_params(labelsize=7)


def shading_png(scenario: Any, extent: tuple[float, float, float, float], samples: int = 160) -> str:
    """The ground's shading over ``extent`` as a PNG data URI (for the HTML time-slider view)."""
    _, _, z = ground_grid(scenario, extent, samples)
    rgba = _cmap()(_norm(z)(z))
    rgba[..., 3] = 0.55
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray((rgba[::-1] * 255).astype(np.uint8), "RGBA").save(buf, format="PNG", optimize=True)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def terrain_extent(scenario: Any) -> tuple[list[float], list[float]]:
    """The xs and ys of the terrain elements' corners (to grow a map's extent by)."""
    xs: list[float] = []
    ys: list[float] = []
    for el in scenario.terrain:
        corners = ground.outline(el)
        xs += corners[:, 0].tolist()
        ys += corners[:, 1].tolist()
    return xs, ys


def _nice(raw: float) -> float:
    exp = math.floor(math.log10(raw))
    for m in (1, 2, 5, 10):
        if m * 10 ** exp >= raw:
            return m * 10 ** exp
    return 10 ** (exp + 1)
