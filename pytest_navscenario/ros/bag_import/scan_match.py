"""Odometry drift corrected by scan matching, when the bag has no ``map -> odom`` (issue 37).

Wheel odometry on a real floor drifts: a heading off by a few degrees puts a wall seen at the end of
a drive decimetres from where it was seen at the start, and the seed gets two walls (or none, once
the beams carve one another's). So each key scan (the robot moved ``KEY_MOVE`` or turned
``KEY_TURN`` since the last) is aligned to the map built from the key scans before it, and every
pose is corrected by the alignment (``map -> odom``, interpolated between key scans), when that
makes the map of the scans sharper (``SHARPER``; else the odometry had no drift worth correcting, and
a matcher on a sparse world only adds its own error):

* ``own``: a correlative scan matcher (Olson, "Real-time correlative scan matching", 2009): the
  map is a likelihood grid of the returns so far (each blurred over a few cells); every rotation
  and translation in a window around the last correction is scored by the likelihood of the scan's
  returns, coarse on the grid's cells, then fine with interpolation. Exhaustive, so it does not
  fall into a local minimum as ICP can when the drift is large against the spacing of the walls;
* ``kiss-icp``: KISS-ICP's point-to-point ICP with a robust kernel against its voxel map (the
  ``drift`` extra: ``pip install pytest-navscenario[drift]``), for comparison.

Asked for (``--scan-match``; off by default: a long corridor gives the matching nothing along it, and
on a generated corridor with exact odometry KISS-ICP slid the poses 10 cm along it), ``auto`` uses
KISS-ICP when it is installed, else the own matcher (and says so): on
generated bags with known drifts (2, 6 and 15 degrees) both gave the seed the same fit to its scans,
and KISS-ICP's poses were closer to the truth (largest error 6-8 mm against 20-35 mm, headings
within 0.30 deg against 0.43) in up to twice the own matcher's time (docs/benchmarks.md, #37).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

METHODS = ("auto", "own", "kiss-icp", "off")
KEY_MOVE = 0.2          # m the robot moves between key scans
KEY_TURN = math.radians(6.0)
POINTS = 240            # returns of a key scan the own matcher uses (evenly picked)
KISS_POINTS = 100_000   # KISS-ICP takes them all (fewer made it less exact: 37 mm against 13 mm with 240)
RES = 0.05              # m, the likelihood grid's cells
BLUR = 2                # cells: each return spreads its likelihood this far (a Gaussian of sigma 1 cell)
WINDOW = 0.25           # m either way the coarse search moves a scan from the last correction
TURN = math.radians(4.0)  # either way it turns it
PRIOR = 0.05            # score lost per (window)^2 of move: ties go to the smaller correction


@dataclass
class Matched:
    """Corrections (k, 4) t, x, y, yaw (map -> odom at each key scan) and what to tell the user."""
    corr: np.ndarray
    method: str
    keys: int


def _se2(x: float, y: float, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]])


def _apply(m: np.ndarray, pts: np.ndarray) -> np.ndarray:
    return pts @ m[:2, :2].T + m[:2, 2]


def _yaw(m: np.ndarray) -> float:
    return math.atan2(m[1, 0], m[0, 0])


class LikelihoodGrid:
    """The returns aligned so far as a likelihood field: each cell holds exp(-d^2 / 2) of its
    distance d (in cells) to the nearest cell a return fell in, up to BLUR cells away (a distance
    field, so a wall seen a hundred times counts as much as one seen twice, and its peak stays sharp)."""

    def __init__(self, lo, hi, res: float = RES):
        self.res = res
        self.lo = np.asarray(lo, float)
        self.nx = int(math.ceil((hi[0] - lo[0]) / res)) + 1
        self.ny = int(math.ceil((hi[1] - lo[1]) / res)) + 1
        self.value = np.zeros((self.ny, self.nx), np.float32)
        self.hit = np.zeros((self.ny, self.nx), bool)
        k = np.arange(-BLUR, BLUR + 1)
        kx, ky = np.meshgrid(k, k)
        self.stamp = (kx.ravel(), ky.ravel(), np.exp(-0.5 * (kx ** 2 + ky ** 2)).ravel().astype(np.float32))

    def add(self, pts: np.ndarray) -> None:
        c = np.floor((pts - self.lo) / self.res).astype(np.int64)
        ok = (c[:, 0] >= 0) & (c[:, 0] < self.nx) & (c[:, 1] >= 0) & (c[:, 1] < self.ny)
        c = np.unique(c[ok], axis=0)
        c = c[~self.hit[c[:, 1], c[:, 0]]]
        if not len(c):
            return
        self.hit[c[:, 1], c[:, 0]] = True
        kx, ky, w = self.stamp
        cx = (c[:, 0:1] + kx[None, :]).ravel()
        cy = (c[:, 1:2] + ky[None, :]).ravel()
        ok = (cx >= 0) & (cx < self.nx) & (cy >= 0) & (cy < self.ny)
        np.maximum.at(self.value, (cy[ok], cx[ok]), np.tile(w, len(c))[ok])

    def nearest(self, x: np.ndarray, y: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        """The mean likelihood at points ``x``, ``y`` (turns, points; m) moved by every pair of whole
        cell ``offsets`` (columns x rows, in meshgrid order), each read in its cell: (turns, moves)."""
        pad = int(np.abs(offsets).max()) if len(offsets) else 0
        cx = np.clip(np.floor((x - self.lo[0]) / self.res).astype(np.int64), pad, self.nx - 1 - pad)
        cy = np.clip(np.floor((y - self.lo[1]) / self.res).astype(np.int64), pad, self.ny - 1 - pad)
        ox, oy = np.meshgrid(offsets, offsets)
        shift = (oy * self.nx + ox).ravel()
        flat = self.value.reshape(-1)
        return flat[(cy * self.nx + cx)[:, None, :] + shift[None, :, None]].mean(axis=-1)

    def score(self, fx: np.ndarray, fy: np.ndarray) -> np.ndarray:
        """The mean likelihood at points given in (fractional) cells, bilinear; (..., points) -> (...)."""
        x0, y0 = np.floor(fx).astype(np.int64), np.floor(fy).astype(np.int64)
        ax, ay = (fx - x0).astype(np.float32), (fy - y0).astype(np.float32)
        ok = (x0 >= 0) & (x0 < self.nx - 1) & (y0 >= 0) & (y0 < self.ny - 1)
        x0, y0 = np.where(ok, x0, 0), np.where(ok, y0, 0)
        v = self.value
        val = ((1 - ax) * (1 - ay) * v[y0, x0] + ax * (1 - ay) * v[y0, x0 + 1]
               + (1 - ax) * ay * v[y0 + 1, x0] + ax * ay * v[y0 + 1, x0 + 1])
        return np.where(ok, val, 0.0).mean(axis=-1)


STAGES = (  # turn span, turns, moves (in cells either way, step), points used, bilinear
    (TURN, 9, (WINDOW / RES, 1.0), 120, False),
    (math.radians(0.5), 5, (1.0, 0.5), POINTS, True),
    (math.radians(0.125), 3, (0.5, 0.25), POINTS, True),
)


def correlative_match(grid: LikelihoodGrid, pts: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """The rigid motion (3x3) that best lays ``pts`` (map frame, under the last correction) on the
    grid: turns about ``centre`` (the robot) and moves within WINDOW / TURN, coarse on the cells
    with a few returns, then finer with all of them, interpolated."""
    best = (0.0, 0.0, 0.0)
    rel_all = pts - centre
    for span, steps, (reach, step), count, smooth in STAGES:
        rel = rel_all[np.linspace(0, len(rel_all) - 1, min(count, len(rel_all))).round().astype(int)]
        turns = best[2] + np.linspace(-span, span, steps)
        moves = np.arange(-reach, reach + 1e-9, step) * grid.res
        dx, dy = np.meshgrid(best[0] + moves, best[1] + moves)
        dx, dy = dx.ravel(), dy.ravel()
        c, s = np.cos(turns), np.sin(turns)
        rx = c[:, None] * rel[None, :, 0] - s[:, None] * rel[None, :, 1] + centre[0]   # (turns, points)
        ry = s[:, None] * rel[None, :, 0] + c[:, None] * rel[None, :, 1] + centre[1]
        if smooth:
            fx = (rx[:, None, :] + dx[None, :, None] - grid.lo[0]) / grid.res - 0.5    # (turns, moves, points)
            fy = (ry[:, None, :] + dy[None, :, None] - grid.lo[1]) / grid.res - 0.5
            fit = grid.score(fx, fy)
        else:   # whole cells: each turn's cells once, the moves as offsets into the flat grid
            fit = grid.nearest(rx + best[0], ry + best[1], np.round(moves / grid.res).astype(np.int64))
        score = fit - PRIOR * ((dx ** 2 + dy ** 2)[None, :] / WINDOW ** 2 + (turns ** 2)[:, None] / TURN ** 2)
        i, j = np.unravel_index(int(np.argmax(score)), score.shape)
        best = (float(dx[j]), float(dy[j]), float(turns[i]))
    dx, dy, turn = best
    c, s = math.cos(turn), math.sin(turn)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return _se2(centre[0] + dx, centre[1] + dy, 0.0) @ rot @ _se2(-centre[0], -centre[1], 0.0)


def key_scans(data, mount, points: int = POINTS):
    """(t, robot pose (3,) in the odometry frame, returns (k, 2) in the robot's frame) of each key
    scan, streamed (each beam placed with the odometry at its own time, then expressed in the
    robot's frame at the scan's stamp)."""
    from .occupancy import reach_of
    from .projection import beam_rays, poses_at
    from .streaming import stream_scans

    reach = reach_of(data.scan_layout.range_max)
    last = None
    for batch in stream_scans(data):
        rays = beam_rays(data, batch, mount)
        base = poses_at(data, batch.t + data.scan_timing.offset)
        for i in range(len(batch.t)):
            pose = base[i]
            if last is not None and math.hypot(*(pose[:2] - last[:2])) < KEY_MOVE \
                    and abs(math.remainder(pose[2] - last[2], 2 * math.pi)) < KEY_TURN:
                continue
            ok = rays.valid[i] & (rays.range[i] <= reach)
            if ok.sum() < 20:
                continue
            rng = rays.range[i][ok].astype(float)
            ang = np.broadcast_to(rays.angle, rays.range.shape)[i][ok]
            ox = np.broadcast_to(rays.ox, rays.range.shape)[i][ok]
            oy = np.broadcast_to(rays.oy, rays.range.shape)[i][ok]
            world = np.stack([ox + rng * np.cos(ang), oy + rng * np.sin(ang)], 1)
            pick = np.linspace(0, len(world) - 1, min(points, len(world))).round().astype(int)
            local = _apply(np.linalg.inv(_se2(*pose)), world[pick])
            last = pose
            yield float(batch.t[i]), pose, local


def match_own(data, mount) -> Matched:
    """Corrections by the correlative matcher against the map of the key scans before each."""
    from .occupancy import reach_of

    od = data.odom
    pad = reach_of(data.scan_layout.range_max) + 3.0
    grid = LikelihoodGrid(od[:, 1:3].min(axis=0) - pad, od[:, 1:3].max(axis=0) + pad)
    corr = np.eye(3)
    rows = []
    for t, pose, local in key_scans(data, mount):
        robot = _se2(*pose)
        pts = _apply(corr @ robot, local)
        if rows:
            step = correlative_match(grid, pts, _apply(corr @ robot, np.zeros((1, 2)))[0])
            corr = step @ corr
            pts = _apply(step, pts)
        grid.add(pts)
        rows.append((t, corr[0, 2], corr[1, 2], _yaw(corr)))
    return Matched(np.array(rows, float).reshape(-1, 4), "own correlative matcher", len(rows))


def match_kiss(data, mount) -> Matched:
    """Corrections by KISS-ICP's registration against its voxel map of the key scans before each
    (its compiled core only: the package's Python front end imports a configuration stack that
    costs more than the matching on a small bag)."""
    from kiss_icp.pybind import kiss_icp_pybind as kiss

    from .occupancy import reach_of

    reach = reach_of(data.scan_layout.range_max)
    voxels = kiss._VoxelHashMap(voxel_size=0.05, max_distance=reach + 5.0, max_points_per_voxel=20)
    reg = kiss._Registration(max_num_iterations=500, convergence_criterion=1e-4, max_num_threads=1)
    corr = np.eye(3)
    rows = []
    for t, pose, local in key_scans(data, mount, KISS_POINTS):
        pts = kiss._Vector3dVector(np.c_[local, np.zeros(len(local))])
        robot = _se2(*pose)
        guess = _to4(corr @ robot)
        if rows:
            guess = reg._align_points_to_map(points=pts, voxel_map=voxels, initial_guess=guess,
                                             max_correspondance_distance=0.5, kernel=0.1)
            corr = _to3(guess) @ np.linalg.inv(robot)
        voxels._update(pts, _to4(corr @ robot))
        rows.append((t, corr[0, 2], corr[1, 2], _yaw(corr)))
    return Matched(np.array(rows, float).reshape(-1, 4), "KISS-ICP", len(rows))


def _to4(m: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:2, :2], out[:2, 3] = m[:2, :2], m[:2, 2]
    return out


def _to3(m: np.ndarray) -> np.ndarray:
    return _se2(float(m[0, 3]), float(m[1, 3]), math.atan2(m[1, 0], m[0, 0]))


SHARPER = 0.10    # the corrected poses must make the map of a sample of scans this much sharper to be kept


def _sharpness(data, mount, corrected: np.ndarray) -> tuple[int, int]:
    """Cells of 2 cm that a sample of the window's scans falls in, with the odometry's poses and
    with ``corrected`` (fewer: a sharper map; the measure projection.settle_timing uses)."""
    from .projection import cell_count, project_scans
    from .streaming import sample_scans

    part = sample_scans(data)
    before = cell_count(project_scans(data, part, mount)[0], 0.02)
    kept = data.odom
    try:
        data.odom = corrected
        after = cell_count(project_scans(data, part, mount)[0], 0.02)
    finally:
        data.odom = kept
    return before, after


def correct_drift(data, mount, method: str = "auto") -> str | None:
    """Scan-match the window's key scans (``method``: auto, own, kiss-icp, off) and move
    ``data.odom`` by the corrections (interpolated between key scans); return what to tell the
    user (None when off). Only for poses in the odometry frame: a bag's own ``map -> odom`` or
    localisation is kept as it is."""
    from .frames import compose
    from .reading import BagImportError

    if method not in METHODS:
        raise BagImportError(f"--scan-match must be one of {', '.join(METHODS)}, got {method!r}")
    if method == "off":
        return None
    fallback = ""
    if method in ("auto", "kiss-icp"):
        try:
            from kiss_icp.pybind import kiss_icp_pybind  # noqa: F401
        except ImportError:
            if method == "kiss-icp":
                raise BagImportError("--scan-match kiss-icp needs KISS-ICP: pip install 'pytest-navscenario[drift]' "
                                     "(or pip install kiss-icp); --scan-match own needs nothing") from None
            method, fallback = "own", ("; KISS-ICP is not installed, so the own matcher was used (a little less "
                                       "exact: pip install 'pytest-navscenario[drift]')")
    found = match_kiss(data, mount) if method in ("auto", "kiss-icp") else match_own(data, mount)
    corr = found.corr
    if len(corr) < 2:
        return f"scan matching: {found.keys} key scan(s) in the window, nothing to align (poses as the odometry has them)"
    od = data.odom
    at = np.stack([np.interp(od[:, 0], corr[:, 0], corr[:, j]) for j in (1, 2)] +
                  [np.interp(od[:, 0], corr[:, 0], np.unwrap(corr[:, 3]))], axis=1)
    moved = compose(at, od[:, 1:4])
    shift = np.hypot(*(moved[:, :2] - od[:, 1:3]).T)
    turn = np.degrees(np.abs(np.unwrap(moved[:, 2]) - np.unwrap(od[:, 3])))
    before, after = _sharpness(data, mount, np.c_[od[:, 0], moved])
    if after > (1 - SHARPER) * before:
        return (f"scan matching ({found.method}, {found.keys} key scans) would move the poses by up to "
                f"{shift.max():.2f} m and {turn.max():.1f} deg but the map of the scans is no sharper for it ({after} "
                f"cells of 2 cm against {before}): no drift worth correcting, the odometry is kept{fallback}")
    data.odom = np.c_[od[:, 0], moved]
    return (f"odometry drift corrected by scan matching ({found.method}, {found.keys} key scans, each aligned to the "
            f"map of those before it): poses moved by up to {shift.max():.2f} m "
            f"and {turn.max():.1f} deg, {shift[-1]:.2f} m and {turn[-1]:.1f} deg at the window's end{fallback}")
