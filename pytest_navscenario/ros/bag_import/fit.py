"""Does the seed agree with the scans it was made from? Ray-cast the seed's obstacles from the
recorded poses along the recorded beams and compare with the recorded ranges:

* ``blocked``: the share of beams along which the seed has an obstacle more than ``TOL`` in front of
  what the real lidar saw (its return, or nothing within its range): space the real robot saw free;
* ``missed``: the share of real returns the seed has nothing at (its first obstacle along the beam
  more than ``TOL`` behind the return, or none); of them ``carved``: those in cells that returns hit
  repeatedly but later beams carved free (a carving problem, not something left out on purpose);

(``TOL`` measured across the seed's surface where the beam meets it, not along the beam: a beam
that grazes a wall a centimetre off meets it decimetres from the real return);
* ``median_error``: the median difference between the seed's range and the real return;
* the start clearance: the seed's distance from the start to its nearest obstacle, against the first
  scan's nearest return from the robot's centre.

A generated bag of a known world imported faithfully gives 0 % and 0.0x m (tests/ros). The figures
are printed at the end of every import, written beside the seed (``OUT.fit.json``), and turned into
a warning when the seed disagrees with its own data.
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field

import numpy as np

TOL = 0.1              # m: a seed range within this of the real one agrees
WARN_BLOCKED = 0.05    # share of beams: above it the seed blocks what the robot saw free
WARN_MISSED = 0.10     # share of returns the seed misses
WARN_ERROR = 0.10      # m, median range error
WARN_START = 0.10      # m, start clearance off by more than this
PAIRS = 30_000_000     # ray x edge pairs the figure may cost (a huge seed uses fewer scans)


@dataclass
class FitFigure:
    scans: int                    # scans compared
    beams: int                    # beams compared (returns and beams that saw nothing)
    blocked: float                # share of beams where the seed blocks what the lidar saw free
    missed: float                 # share of real returns the seed misses
    median_error: float           # m, over the real returns
    start_seed: float             # m, the seed's clearance at the start (inf without obstacles)
    start_scan: float             # m, the first scan's nearest return from the robot's centre
    carved: float = 0.0           # share of real returns missed in cells hit repeatedly yet carved free
    tolerance: float = TOL
    warnings: list[str] = field(default_factory=list)

    def lines(self) -> list[str]:
        head = (f"fit of the seed to its own {self.scans} scans ({self.beams} beams, ray-cast from the recorded "
                f"poses): the seed blocks {self.blocked:.1%} of the beams where the lidar saw free space, misses "
                f"{self.missed:.1%} of the real returns, median range error {self.median_error:.2f} m; start "
                f"clearance {_m(self.start_seed)} in the seed, {_m(self.start_scan)} in the first scan")
        return [head] + [f"warning: {w}" for w in self.warnings]

    def to_json(self) -> str:
        body = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}
        return json.dumps(body, indent=2) + "\n"


def _m(v: float) -> str:
    return f"{v:.2f} m" if math.isfinite(v) else "none"


def _segments(obstacles) -> tuple[np.ndarray, np.ndarray]:
    """(s, 4) polygon edges x0, y0, x1, y1 and (c, 3) circles x, y, r of the static obstacles."""
    from ...scenario.geometry import obstacle_polygon
    from ...scenario.model import CylinderObstacle

    edges, circles = [], []
    for o in obstacles:
        if getattr(o, "motion", None) is not None or not getattr(o, "visible_to_lidar", True):
            continue
        if isinstance(o, CylinderObstacle):
            circles.append((o.x, o.y, o.radius))
            continue
        ring = np.asarray(obstacle_polygon(o).exterior.coords)
        edges.append(np.c_[ring[:-1], ring[1:]])
    return (np.concatenate(edges) if edges else np.zeros((0, 4))), np.array(circles, float).reshape(-1, 3)


def cast(ox, oy, dx, dy, edges: np.ndarray, circles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance along each ray (origin ox, oy; unit direction dx, dy; all (m,)) to the first
    edge or circle (inf where there is none), and |cos| of the angle between the ray and the
    surface's normal there (1 head-on, near 0 grazing)."""
    best = np.full(len(ox), np.inf)
    cosine = np.ones(len(ox))
    if len(edges):
        ex, ey = edges[:, 2] - edges[:, 0], edges[:, 3] - edges[:, 1]
        length = np.maximum(np.hypot(ex, ey), 1e-12)
        chunk = max(1, 200_000 // len(edges))      # ray x edge pairs at once: ~20 MB of temporaries
        for a in range(0, len(ox), chunk):
            px, py = ox[a:a + chunk, None], oy[a:a + chunk, None]
            rx, ry = dx[a:a + chunk, None], dy[a:a + chunk, None]
            qx, qy = edges[None, :, 0] - px, edges[None, :, 1] - py
            den = rx * ey - ry * ex
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (qx * ey - qy * ex) / den
                u = (qx * ry - qy * rx) / den
            hit = (np.abs(den) > 1e-12) & (t > 1e-9) & (u >= 0) & (u <= 1)
            t = np.where(hit, t, np.inf)
            k = t.argmin(axis=1)
            rows = np.arange(len(k))
            first = t[rows, k]
            closer = first < best[a:a + chunk]
            best[a:a + chunk] = np.where(closer, first, best[a:a + chunk])
            cos_k = np.abs(den[rows, k]) / length[k]      # |ray x edge| / |edge| = |cos(ray, normal)|
            cosine[a:a + chunk] = np.where(closer, cos_k, cosine[a:a + chunk])
    for cx, cy, r in circles:
        fx, fy = ox - cx, oy - cy
        b = dx * fx + dy * fy
        disc = b * b - (fx * fx + fy * fy - r * r)
        root = np.sqrt(np.maximum(disc, 0.0))
        near = -b - root
        t = np.where(near > 1e-9, near, -b + root)     # from inside a circle: its far side
        t = np.where((disc >= 0) & (t > 1e-9), t, np.inf)
        closer = t < best
        with np.errstate(invalid="ignore"):
            cos_c = np.abs(b + t) / r                    # |d . (hit - centre)| / r
        best = np.where(closer, t, best)
        cosine = np.where(closer, np.minimum(cos_c, 1.0), cosine)
    return best, cosine


def fit_figure(scenario, data, mount, sample, first, carved=None) -> FitFigure:
    """The seed ``scenario`` against the recorded scans ``sample`` (scans.ScanBatch) and the window's
    ``first`` scan, each beam from where the laser was when it measured it; ``carved(x, y)`` (bool
    per point): whether a return's cell was hit repeatedly and carved free all the same."""
    from shapely.geometry import Point

    from ...scenario.geometry import obstacle_polygon
    from .occupancy import reach_of
    from .projection import beam_rays, poses_at
    from .scans import ScanBatch

    edges, circles = _segments(scenario.obstacles)
    layout = data.scan_layout
    per_scan = layout.beams * max(1, len(edges))
    keep = min(len(sample.t), max(20, PAIRS // per_scan))
    if keep < len(sample.t):
        pick = np.linspace(0, len(sample.t) - 1, keep).round().astype(int)
        sample = ScanBatch(sample.t[pick], sample.ranges[pick])
    reach = reach_of(layout.range_max)
    blocked = missed = beams = returns = lost = 0
    errors = []
    if len(sample.t):
        r = beam_rays(data, sample, mount)
        use = r.valid | r.none
        ox, oy = r.ox[use].astype(float), r.oy[use].astype(float)
        ang = r.angle[use]
        seed, cosine = cast(ox, oy, np.cos(ang), np.sin(ang), edges, circles)
        real = np.where(r.valid[use], r.range[use].astype(float), np.inf)
        valid = np.isfinite(real)
        seen_to = np.where(valid, real, reach)
        # across the seed's surface, not along the beam: at a grazing angle a wall a centimetre off
        # would put the seed's hit decimetres from the real return
        with np.errstate(invalid="ignore"):
            blocked = int(np.count_nonzero((seed < seen_to) & ((seen_to - seed) * cosine > TOL)))
            miss = valid & (~np.isfinite(seed) | ((seed - real) * cosine > TOL))
        missed = int(np.count_nonzero(miss))
        if carved is not None and missed:
            px, py = ox[miss] + real[miss] * np.cos(ang[miss]), oy[miss] + real[miss] * np.sin(ang[miss])
            lost = int(np.count_nonzero(carved(px, py)))
        errors = np.abs(np.minimum(seed[valid], layout.range_max) - real[valid])
        beams, returns = int(use.sum()), int(valid.sum())
    start = scenario.mission.start
    polys = [obstacle_polygon(o) for o in scenario.obstacles if getattr(o, "motion", None) is None]
    start_seed = min((p.distance(Point(start.x, start.y)) for p in polys), default=math.inf)
    start_scan = math.inf
    if len(first.t):
        r = beam_rays(data, first, mount)
        if r.valid.any():
            rng = r.range[r.valid].astype(float)
            px = r.ox[r.valid] + rng * np.cos(r.angle[r.valid])
            py = r.oy[r.valid] + rng * np.sin(r.angle[r.valid])
            base = poses_at(data, np.broadcast_to(r.t, r.range.shape)[r.valid])
            start_scan = float(np.hypot(px - base[:, 0], py - base[:, 1]).min())
    fig = FitFigure(scans=len(sample.t), beams=beams, blocked=blocked / beams if beams else 0.0,
                    missed=missed / returns if returns else 0.0,
                    median_error=float(np.median(errors)) if len(errors) else 0.0,
                    start_seed=float(start_seed), start_scan=start_scan, carved=lost / returns if returns else 0.0)
    fig.warnings = _disagreements(fig)
    return fig


def _disagreements(fig: FitFigure) -> list[str]:
    """What makes the seed disagree with its own data, with what to check."""
    out = []
    if fig.blocked > WARN_BLOCKED:
        out.append(f"the seed disagrees with its own scans: along {fig.blocked:.0%} of the beams it has an obstacle "
                   f"more than {TOL:g} m nearer than what the lidar saw (a smear or a misplaced wall): check the "
                   f"seed's picture, the laser mounting (--laser-pose) and the scan timing (--scan-stamp, "
                   f"--scan-time-offset)")
    if fig.missed > WARN_MISSED:
        left = fig.missed - fig.carved
        if fig.carved > WARN_MISSED / 2:
            out.append(f"the seed misses {fig.missed:.0%} of the real returns, {fig.carved:.0%} of them in cells that "
                       f"returns hit again and again but later beams carved free: a carving problem (walls erased by "
                       f"beams that passed them, often because the poses drift: check the seed's picture beside the "
                       f"returns; a shorter window, --start/--end, keeps them)"
                       + (f"; the other {left:.0%} are small or moving things, left out on purpose" if left > 0.005
                          else ""))
        else:
            out.append(f"the seed misses {fig.missed:.0%} of the real returns (something the lidar saw is not in the "
                       f"seed: small or moving things are left out on purpose)")
    if fig.median_error > WARN_ERROR:
        out.append(f"the seed's ranges are {fig.median_error:.2f} m off the real ones (median)")
    if math.isfinite(fig.start_scan) and fig.start_seed < fig.start_scan - WARN_START:
        out.append(f"at the start the seed has an obstacle {fig.start_seed:.2f} m from the robot's centre where "
                   f"the first scan's nearest return is {fig.start_scan:.2f} m away")
    if math.isfinite(fig.start_scan) and fig.start_seed > fig.start_scan + WARN_START:
        seed = f"{fig.start_seed:.2f} m away" if math.isfinite(fig.start_seed) else "none at all"
        out.append(f"at the start the seed's nearest obstacle is {seed} where the first scan's nearest return is "
                   f"{fig.start_scan:.2f} m from the robot's centre: the seed lacks what the robot saw nearest (a "
                   f"wall carved away or left out as small): check the seed's picture beside the returns")
    return out
