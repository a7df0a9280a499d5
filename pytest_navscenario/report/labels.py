"""Placing the text labels of a map so that none covers another, or a marker.

The steps of a trajectory plot ask for labels (``add``: an anchor in data coordinates and the
offsets it may be written at, nearest first) and say where markers are (``avoid``: a point, or a
drawn area such as a moving obstacle's final outline). Nothing is written until ``place``, which
runs once the axes limits are set: it measures each label's box in display pixels and keeps,
label by label in the order asked, the first offset whose box stays inside the axes and clear of
every marker and every label placed before; a required label with no clear offset takes the one
that overlaps least, an optional one (the time stamps along a path) is left out. Fixed labels
(obstacle names, written on the obstacle) are placed first and avoided by the rest.

A greedy placer, as map labelling tools use for point features: good enough for the ~10-40
labels of one episode; each candidate costs one text measurement (~0.1 ms).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

PAD = 2.0   # px kept free around a label's text (its halo)
LEADER_MIN = 14.0   # px: a label set off further than this from its anchor gets a leader line


def ring(distances: Sequence[float] = (6.0, 14.0, 26.0), *, first: tuple[float, float] | None = None) -> list[tuple[float, float]]:
    """Offsets (points) around an anchor: right, left, above, below, then the diagonals, at each
    distance in turn; ``first`` (a direction, e.g. (0, -1) for below) is tried first at each."""
    dirs = [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, 1), (1, -1), (-1, -1)]
    if first is not None:
        f = (int(np.sign(first[0])), int(np.sign(first[1])))
        if f in dirs:
            dirs.remove(f)
        dirs.insert(0, f)
    return [(d * dx, d * dy) for d in distances for dx, dy in dirs]


def _alignment(offset: tuple[float, float]) -> tuple[str, str]:
    """Text alignment that puts the text on the offset's side of the anchor."""
    dx, dy = offset
    ha = "left" if dx > 0 else "right" if dx < 0 else "center"
    va = "bottom" if dy > 0 else "top" if dy < 0 else "center"
    return ha, va


@dataclass
class _Request:
    text: str
    xy: tuple[float, float]
    offsets: list[tuple[float, float]]
    style: dict[str, Any]
    optional: bool = False
    leader: dict[str, Any] | None = None
    fixed: bool = False
    priority: int = 5
    companions: tuple = ()


@dataclass
class LabelPlacer:
    """Collects the labels and markers of one axes, then places the labels (``place``)."""
    ax: "Axes"
    requests: list[_Request] = field(default_factory=list)
    points: list[tuple[float, float, float]] = field(default_factory=list)    # x, y (data), radius (px)
    areas: list[np.ndarray] = field(default_factory=list)                     # polygons (data)
    placed: list[Any] = field(default_factory=list)                           # the Annotations written

    def fixed(self, text: str, xy: tuple[float, float], **style: Any) -> None:
        """A label written centred on ``xy`` whatever is there (an obstacle's name)."""
        self.requests.append(_Request(text, (float(xy[0]), float(xy[1])), [(0.0, 0.0)], style, fixed=True))

    def add(self, text: str, xy: tuple[float, float], *, offsets: Sequence[tuple[float, float]] | None = None,
            optional: bool = False, leader: dict[str, Any] | None = None, priority: int = 5,
            companions: Sequence[Any] = (), **style: Any) -> None:
        """A label for the point ``xy``, written at the first of ``offsets`` (points from ``xy``;
        default ``ring()``) that is clear. ``optional``: left out when no offset is clear.
        ``leader``: line properties of a line from ``xy`` to the text (for labels set off far).
        Labels are placed by ``priority`` (lower first), then in the order asked. ``companions``:
        artists that go with the label (its dot), removed with an optional label left out."""
        self.requests.append(_Request(text, (float(xy[0]), float(xy[1])), list(offsets or ring()), style,
                                      optional, leader, priority=priority, companions=tuple(companions)))

    def avoid(self, xy: tuple[float, float], radius: float = 6.0) -> None:
        """A marker at ``xy`` (data) that labels must not cover, ``radius`` pixels around it."""
        self.points.append((float(xy[0]), float(xy[1]), float(radius)))

    def avoid_area(self, coords: Any) -> None:
        """A drawn area (an outline's coordinates, data) that labels must not cover."""
        self.areas.append(np.asarray(coords, dtype=float).reshape(-1, 2))

    # -- placing ------------------------------------------------------------------------------
    def place(self) -> list[Any]:
        """Write every label (call once the axes limits and aspect are final); returns them."""
        ax = self.ax
        if not self.requests:
            return []
        fig = ax.figure
        renderer = fig.canvas.get_renderer()
        ax.apply_aspect()
        to_px = ax.transData.transform
        frame = ax.get_window_extent(renderer)
        taken: list[tuple[float, float, float, float]] = []
        for x, y, r in self.points:
            px, py = to_px((x, y))
            taken.append((px - r, py - r, px + r, py + r))
        for poly in self.areas:
            pts = to_px(poly)
            taken.append((pts[:, 0].min(), pts[:, 1].min(), pts[:, 0].max(), pts[:, 1].max()))
        order = sorted(self.requests, key=lambda r: (not r.fixed, r.priority))   # stable: asked order
        for req in order:
            ann = self._write(req, taken, frame, renderer)
            if ann is not None:
                self.placed.append(ann)
        return self.placed

    def _write(self, req: _Request, taken: list, frame: Any, renderer: Any) -> Any:
        ax = self.ax
        style = dict(req.style)
        ann = ax.annotate(req.text, req.xy, xytext=req.offsets[0], textcoords="offset points",
                          annotation_clip=False, **style)
        best, best_score = None, np.inf
        for offset in req.offsets:
            if not req.fixed:
                ha, va = _alignment(offset)
                ann.xyann = offset
                ann.set_horizontalalignment(ha)
                ann.set_verticalalignment(va)
            box = _box(ann, renderer)
            score = _overlap(box, taken) + 4.0 * _outside(box, frame)
            if score < best_score:
                best, best_score = (offset, box), score
            if score <= 0.0 or req.fixed:
                break
        if best is None or (req.optional and best_score > 0.0):
            ann.remove()
            for artist in req.companions:
                artist.remove()
            return None
        offset, box = best
        if not req.fixed:
            ha, va = _alignment(offset)
            ann.xyann = offset
            ann.set_horizontalalignment(ha)
            ann.set_verticalalignment(va)
        taken.append(box)
        if req.leader is not None and offset != (0.0, 0.0):
            self._leader(req, box)
        return ann

    def _leader(self, req: _Request, box: tuple[float, float, float, float]) -> None:
        """A thin line from the anchor to the nearest point of the text's box, when the text
        stands off far enough (LEADER_MIN pixels) for the eye to need it."""
        ax = self.ax
        px, py = ax.transData.transform(req.xy)
        nx = min(max(px, box[0]), box[2])
        ny = min(max(py, box[1]), box[3])
        if (nx - px) ** 2 + (ny - py) ** 2 < LEADER_MIN ** 2:
            return
        end = ax.transData.inverted().transform((nx, ny))
        ax.plot([req.xy[0], end[0]], [req.xy[1], end[1]], scalex=False, scaley=False, **req.leader)


def _box(ann: Any, renderer: Any) -> tuple[float, float, float, float]:
    from matplotlib.text import Text

    ann.update_positions(renderer)               # where its offset puts the text now
    bb = Text.get_window_extent(ann, renderer)   # the text alone (no arrow)
    return (bb.x0 - PAD, bb.y0 - PAD, bb.x1 + PAD, bb.y1 + PAD)


def _overlap(box: tuple[float, float, float, float], taken: Sequence[tuple[float, float, float, float]]) -> float:
    """Total area (px^2) ``box`` shares with the boxes ``taken``."""
    total = 0.0
    for t in taken:
        w = min(box[2], t[2]) - max(box[0], t[0])
        h = min(box[3], t[3]) - max(box[1], t[1])
        if w > 0 and h > 0:
            total += w * h
    return total


def _outside(box: tuple[float, float, float, float], frame: Any) -> float:
    """Area (px^2) of ``box`` outside the axes."""
    w, h = box[2] - box[0], box[3] - box[1]
    iw = max(0.0, min(box[2], frame.x1) - max(box[0], frame.x0))
    ih = max(0.0, min(box[3], frame.y1) - max(box[1], frame.y0))
    return w * h - iw * ih


def text_boxes(ax: "Axes") -> list[tuple[str, tuple[float, float, float, float]]]:
    """(text, display box of the text alone) of every non-empty annotation on ``ax``: what a test
    of a picture checks for overlaps."""
    from matplotlib.text import Annotation, Text

    renderer = ax.figure.canvas.get_renderer()
    ax.apply_aspect()
    out = []
    for child in ax.get_children():
        if isinstance(child, Annotation) and child.get_text() and child.get_visible():
            child.update_positions(renderer)
            bb = Text.get_window_extent(child, renderer)
            out.append((child.get_text(), (bb.x0, bb.y0, bb.x1, bb.y1)))
    return out
