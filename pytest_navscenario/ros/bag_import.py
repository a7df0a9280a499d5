"""``navscenario from-bag``: a seed scenario from a real robot's bag.

Reads ROS 1 bags, rosbag2 sqlite3 and MCAP (also old ROS 2 bags with no embedded message
definitions) with ``rosbags``. Odometry and laser topics are found by type (override with
``--odom-topic`` / ``--scan-topic``). The scenario's world frame is the odometry frame:

* start and goal: the first and last odometry pose in the time window;
* the driven path: decimated waypoints, or a reference trajectory (CSV ``t,x,y`` beside the
  seed, ``reference.file`` relative to it);
* obstacles: every scan projected with the laser's mount transform (``--laser-pose``, else
  ``/tf_static``, else the first ``/tf`` transforms, else estimated from the scans), accumulated in the odometry
  frame on a grid, clustered, and fitted as cylinders (round clusters) and oriented boxes
  (straight segments). Box walls are placed behind the observed surface, away from the
  viewpoints that saw it, so the free space the robot drove through stays free.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..core.errors import NavScenarioError
from ..scenario.model import (
    BoxObstacle,
    CylinderObstacle,
    Footprint,
    GoalTolerance,
    Lidar,
    Limits,
    Mission,
    Obstacle,
    Pose,
    Reference,
    Robot,
    Scenario,
)

ODOM_TYPES = ("nav_msgs/msg/Odometry",)
SCAN_TYPES = ("sensor_msgs/msg/LaserScan",)
TF_STATIC_TYPES = ("tf2_msgs/msg/TFMessage",)
PATH_AS = ("waypoints", "reference", "both")
TF_SCAN_LIMIT = 500  # /tf messages read for the laser mount (the mount is fixed; /tf can be long)


class BagImportError(NavScenarioError):
    """A bag cannot be turned into a seed: not a bag, damaged, missing odometry, bad option."""


# ------------------------------------------------------------------ reading

@dataclass
class BagData:
    """What the importer needs from a bag, as plain arrays (times in s after the first odometry message)."""
    path: Path
    odom_topic: str
    odom_frame: str
    base_frame: str
    odom: np.ndarray                  # (n, 4) t, x, y, yaw (rad)
    scan_topic: str | None = None
    scan_frame: str = ""
    scan_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    scan_ranges: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.float32))
    scan_angles: np.ndarray = field(default_factory=lambda: np.zeros(0))
    range_min: float = 0.0
    range_max: float = math.inf
    static_tf: dict[str, tuple[str, float, float, float]] = field(default_factory=dict)  # child -> (parent, x, y, yaw)
    first_tf: dict[str, tuple[str, float, float, float]] = field(default_factory=dict)   # the same, first seen on /tf
    notes: list[str] = field(default_factory=list)


def _yaw(q: Any) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _stamp(header: Any, bag_ns: int) -> int:
    ns = int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)
    return ns if ns > 0 else bag_ns


def _pick(path: Path, connections: list, wanted: str | None, types: Sequence[str], what: str,
          option: str, preferred: Sequence[str], required: bool):
    """The topic to read: the one named by the user, else the one of the right type."""
    topics = sorted({(c.topic, c.msgtype) for c in connections})
    listing = ", ".join(f"{t} ({m})" for t, m in topics) or "none"
    if wanted:
        match = [c for c in connections if c.topic == wanted]
        if not match:
            raise BagImportError(f"{path}: no topic {wanted!r} in the bag (topics: {listing}); "
                                 f"fix {option}")
        if match[0].msgtype not in types:
            raise BagImportError(f"{path}: topic {wanted} is {match[0].msgtype}, not {' or '.join(types)}; "
                                 f"fix {option}")
        return wanted
    candidates = sorted({c.topic for c in connections if c.msgtype in types})
    if not candidates:
        if required:
            raise BagImportError(f"{path}: no {what} ({' or '.join(types)}) in the bag (topics: {listing}); "
                                 f"record odometry, or name a topic with {option}")
        return None
    for name in preferred:
        if name in candidates:
            return name
    if len(candidates) > 1:
        raise BagImportError(f"{path}: several {what} topics ({', '.join(candidates)}); choose one with {option}")
    return candidates[0]


def read_bag(path: str | Path, *, odom_topic: str | None = None, scan_topic: str | None = None,
             start: float | None = None, end: float | None = None) -> BagData:
    """Read odometry, laser scans and static transforms; ``start``/``end`` are seconds after
    the first odometry message (message header stamps; the bag's receive time where a stamp is
    zero). Raises BagImportError naming the file and what is missing."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    path = Path(path)
    if not path.exists():
        raise BagImportError(f"{path}: no such bag file or folder")
    try:
        reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
        reader.open()
    except Exception as exc:  # rosbags raises several unrelated types for a bad file
        what = "a damaged or truncated bag" if _has_bag_magic(path) else "not a readable ROS 1 / rosbag2 bag"
        raise BagImportError(f"{path}: {what} ({_reason(exc)})") from None
    try:
        return _read(reader, path, odom_topic, scan_topic, start, end)
    except NavScenarioError:
        raise
    except Exception as exc:
        raise BagImportError(f"{path}: bag is damaged or truncated ({_reason(exc)})") from None
    finally:
        try:
            reader.close()
        except Exception:
            pass


_MAGICS = (b"#ROSBAG V2.0", b"\x89MCAP", b"SQLite format 3")


def _has_bag_magic(path: Path) -> bool:
    """Whether the file (or the storage file in a rosbag2 folder) starts like a bag."""
    files = [path] if path.is_file() else sorted(path.glob("*.mcap")) + sorted(path.glob("*.db3"))
    for f in files[:1]:
        try:
            with open(f, "rb") as fh:
                head = fh.read(16)
        except OSError:
            return False
        return head.startswith(_MAGICS)
    return False


def _reason(exc: Exception) -> str:
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _read(reader: Any, path: Path, odom_topic, scan_topic, start, end) -> BagData:
    conns = list(reader.connections)
    odom_name = _pick(path, conns, odom_topic, ODOM_TYPES, "odometry", "--odom-topic", ("/odom",), True)
    scan_name = _pick(path, conns, scan_topic, SCAN_TYPES, "laser scan", "--scan-topic", ("/scan",), False)
    wanted = [c for c in conns if c.topic in (odom_name, scan_name) or
              (c.topic in ("/tf_static", "/tf") and c.msgtype in TF_STATIC_TYPES)]
    odom, scans, static_tf, first_tf = [], [], {}, {}
    tf_seen = 0
    odom_frame = base_frame = scan_frame = ""
    scan_meta = None
    odd_scans = 0
    for conn, bag_ns, raw in reader.messages(connections=wanted):
        msg = reader.deserialize(raw, conn.msgtype)
        if conn.topic == "/tf":
            # older bags publish the laser mount on /tf: keep the first transform of each frame
            tf_seen += 1
            if tf_seen > TF_SCAN_LIMIT:
                continue
            for tf in msg.transforms:
                child = tf.child_frame_id.lstrip("/")
                if child not in first_tf:
                    tr, rot = tf.transform.translation, tf.transform.rotation
                    first_tf[child] = (tf.header.frame_id.lstrip("/"), tr.x, tr.y, _yaw(rot))
            continue
        if conn.topic == "/tf_static":
            for tf in msg.transforms:
                tr, rot = tf.transform.translation, tf.transform.rotation
                static_tf[tf.child_frame_id.lstrip("/")] = (tf.header.frame_id.lstrip("/"), tr.x, tr.y, _yaw(rot))
            continue
        stamp = _stamp(msg.header, bag_ns)
        if conn.topic == odom_name:
            p = msg.pose.pose
            odom.append((stamp, p.position.x, p.position.y, _yaw(p.orientation)))
            odom_frame = odom_frame or msg.header.frame_id.lstrip("/")
            base_frame = base_frame or msg.child_frame_id.lstrip("/")
        else:
            ranges = np.asarray(msg.ranges, dtype=np.float32)
            meta = (len(ranges), float(msg.angle_min), float(msg.angle_increment))
            if scan_meta is None:
                scan_meta = meta + (float(msg.range_min), float(msg.range_max))
                scan_frame = msg.header.frame_id.lstrip("/")
            elif meta != scan_meta[:3]:
                odd_scans += 1  # another beam layout than the first scan's: skipped, reported below
                continue
            scans.append((stamp, ranges))
    if not odom:
        raise BagImportError(f"{path}: topic {odom_name} has no messages; record odometry or choose "
                             f"another topic with --odom-topic")
    odom_arr = np.array(odom, dtype=float)
    order = np.argsort(odom_arr[:, 0], kind="stable")
    odom_arr = odom_arr[order]
    origin = float(odom_arr[0, 0])  # t = 0 at the first odometry message
    odom_arr[:, 0] = (odom_arr[:, 0] - origin) * 1e-9
    data = BagData(path=path, odom_topic=odom_name, odom_frame=odom_frame or "odom",
                   base_frame=base_frame or "base_link", odom=odom_arr, static_tf=static_tf,
                   first_tf=first_tf)
    if start is not None or end is not None:
        keep = np.ones(len(odom_arr), bool)
        if start is not None:
            keep &= odom_arr[:, 0] >= start
        if end is not None:
            keep &= odom_arr[:, 0] <= end
        if keep.sum() < 2:
            raise BagImportError(f"{path}: fewer than 2 odometry messages between --start {start} and "
                                 f"--end {end} (the odometry covers 0..{odom_arr[-1, 0]:.1f} s)")
        data.odom = odom_arr[keep]
    if scan_name is None:
        data.notes.append(f"no laser scan topic in {path.name}: the seed has the trajectory only, no obstacles")
        return data
    if scans:
        st = (np.array([s[0] for s in scans], dtype=float) - origin) * 1e-9
        inside = (st >= data.odom[0, 0]) & (st <= data.odom[-1, 0])
        n, amin, ainc, rmin, rmax = scan_meta
        if odd_scans:
            data.notes.append(f"{odd_scans} scan(s) on {scan_name} with another beam count or angles than "
                              f"the first ({n} beams from {math.degrees(amin):.1f} deg) were skipped")
        data.scan_topic = scan_name
        data.scan_frame = scan_frame
        data.scan_t = st[inside]
        data.scan_ranges = np.stack([s[1] for s, k in zip(scans, inside) if k]) if inside.any() \
            else np.zeros((0, n), np.float32)
        data.scan_angles = amin + ainc * np.arange(n)
        data.range_min, data.range_max = rmin, rmax
    if len(data.scan_t) == 0:
        data.notes.append(f"topic {scan_name} has no scans within the odometry's time window: "
                          f"the seed has the trajectory only, no obstacles")
        data.scan_topic = None
    return data


# ------------------------------------------------------------------ geometry

def laser_mount(data: BagData, source: str = "/tf_static") -> tuple[float, float, float] | None:
    """The laser's pose (x, y, yaw rad) in the odometry child frame from ``source`` ("/tf_static",
    or "/tf": the first transform of each frame there, with /tf_static filling gaps), or None."""
    tree = data.static_tf if source == "/tf_static" else {**data.static_tf, **data.first_tf}
    frame, x, y, yaw = data.scan_frame, 0.0, 0.0, 0.0
    for _ in range(32):
        if frame == data.base_frame:
            return (x, y, yaw)
        if frame not in tree:
            break
        parent, px, py, pyaw = tree[frame]
        c, s = math.cos(pyaw), math.sin(pyaw)
        x, y, yaw = px + c * x - s * y, py + s * x + c * y, pyaw + yaw
        frame = parent
    if frame == data.base_frame:
        return (x, y, yaw)
    return None


def _poses_at(data: BagData, t: np.ndarray) -> np.ndarray:
    od = data.odom
    yaw = np.unwrap(od[:, 3])
    return np.stack([np.interp(t, od[:, 0], od[:, 1]), np.interp(t, od[:, 0], od[:, 2]),
                     np.interp(t, od[:, 0], yaw)], axis=1)


def project_scans(data: BagData, mount: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Every valid return as a point in the odometry frame, and the laser position it was seen from."""
    poses = _poses_at(data, data.scan_t)
    rng = data.scan_ranges.astype(float)
    valid = np.isfinite(rng) & (rng > data.range_min) & (rng < data.range_max * 0.99)
    rng = np.where(valid, rng, 0.0)
    mx, my, myaw = mount
    ang = data.scan_angles[None, :] + myaw
    lx = mx + rng * np.cos(ang)
    ly = my + rng * np.sin(ang)
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    wx = poses[:, 0:1] + c * lx - s * ly
    wy = poses[:, 1:2] + s * lx + c * ly
    ox = poses[:, 0] + np.cos(poses[:, 2]) * mx - np.sin(poses[:, 2]) * my
    oy = poses[:, 1] + np.sin(poses[:, 2]) * mx + np.cos(poses[:, 2]) * my
    origin = np.broadcast_to(np.stack([ox, oy], 1)[:, None, :], wx.shape + (2,))
    return np.stack([wx[valid], wy[valid]], 1), origin[valid]


def _sharpness(points: np.ndarray, res: float) -> int:
    cells = np.floor(points / res).astype(np.int64)
    return len(np.unique(cells[:, 0] * 1_000_003 + cells[:, 1]))


def estimate_mount(data: BagData, res: float = 0.02) -> tuple[float, float, float]:
    """The laser's forward offset that makes the accumulated map sharpest (fewest occupied cells).

    Used when the bag has no /tf_static and no --laser-pose is given: a laser mounted behind the
    base frame (TurtleBot3 Waffle: -0.064 m) otherwise smears round obstacles into rings.
    """
    best = None
    sub = slice(None, None, max(1, len(data.scan_t) // 150))  # 150 scans suffice to compare
    part = BagData(path=data.path, odom_topic=data.odom_topic, odom_frame=data.odom_frame,
                   base_frame=data.base_frame, odom=data.odom, scan_t=data.scan_t[sub],
                   scan_ranges=data.scan_ranges[sub], scan_angles=data.scan_angles,
                   range_min=data.range_min, range_max=data.range_max)
    for dx in np.round(np.arange(-0.16, 0.1601, 0.016), 3):
        pts, _ = project_scans(part, (float(dx), 0.0, 0.0))
        score = _sharpness(pts, res)
        if best is None or score < best[0]:
            best = (score, float(dx))
    return (best[1], 0.0, 0.0)


@dataclass
class Cluster:
    points: np.ndarray    # (k, 2) per-cell mean of the returns
    viewpoint: np.ndarray  # (2,) mean laser position that saw them


@dataclass
class Grid:
    """Returns accumulated per grid cell: the cell's mean return and mean viewpoint, and hits."""
    means: np.ndarray    # (k, 4) x, y of the returns, x, y of the laser that saw them
    counts: np.ndarray   # (k,) returns per cell
    returns: int         # returns in total


def _cells(points: np.ndarray, origins: np.ndarray, res: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(cell keys (k, 2), sums of [point, origin] (k, 4), counts (k,)) of a batch of returns."""
    cells = np.floor(points / res).astype(np.int64)
    keys, inverse, counts = np.unique(cells, axis=0, return_inverse=True, return_counts=True)
    sums = np.zeros((len(keys), 4))
    np.add.at(sums, inverse.reshape(-1), np.concatenate([points, origins], axis=1))
    return keys, sums, counts


def grid_returns(data: BagData, mount: tuple[float, float, float], res: float = 0.05,
                 chunk: int = 1000) -> Grid:
    """Project the scans ``chunk`` at a time and sum them per cell, so an hour-long bag needs
    memory for its grid, not for every return at once."""
    parts = []
    total = 0
    for i in range(0, len(data.scan_t), chunk):
        sub = dataclasses.replace(data, scan_t=data.scan_t[i:i + chunk], scan_ranges=data.scan_ranges[i:i + chunk])
        pts, origins = project_scans(sub, mount)
        total += len(pts)
        if len(pts):
            parts.append(_cells(pts, origins, res))
    if not parts:
        return Grid(np.zeros((0, 4)), np.zeros(0, np.int64), 0)
    keys = np.concatenate([p[0] for p in parts])
    sums = np.concatenate([p[1] for p in parts])
    counts = np.concatenate([p[2] for p in parts])
    if len(parts) > 1:  # merge the cells that several chunks share
        keys, inverse = np.unique(keys, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        merged = np.zeros((len(keys), 4))
        np.add.at(merged, inverse, sums)
        sums, counts = merged, np.bincount(inverse, weights=counts, minlength=len(keys)).astype(np.int64)
    return Grid(means=sums / counts[:, None], counts=counts, returns=total)


def occupied_clusters(grid: Grid, *, min_hits: int = 2, link: float = 0.3,
                      min_cells: int = 3) -> tuple[list[Cluster], int]:
    """Keep cells hit ``min_hits`` times, group cells closer than ``link`` (sparse beams leave
    gaps along a far face; a robot does not fit through ``link`` anyway).

    Returns the clusters and the number of small clusters (< ``min_cells``) dropped as noise.
    """
    means = grid.means[grid.counts >= min_hits]
    clusters, dropped = [], 0
    for members in _groups(means[:, :2], link):
        if len(members) < min_cells:
            dropped += 1
            continue
        m = means[members]
        clusters.append(Cluster(points=m[:, :2], viewpoint=m[:, 2:].mean(axis=0)))
    return clusters, dropped


def _groups(points: np.ndarray, radius: float) -> list[np.ndarray]:
    """Index arrays of the groups of points chained by neighbours closer than ``radius``."""
    if len(points) == 0:
        return []
    cells = np.floor(points / radius).astype(np.int64)
    buckets: dict[tuple[int, int], list[int]] = {}
    for i, (a, b) in enumerate(cells):
        buckets.setdefault((int(a), int(b)), []).append(i)
    label = -np.ones(len(points), dtype=np.int64)
    groups = []
    for seed in range(len(points)):
        if label[seed] >= 0:
            continue
        label[seed] = seed
        stack, members = [seed], []
        while stack:
            i = stack.pop()
            members.append(i)
            a, b = cells[i]
            for da in (-1, 0, 1):
                for db in (-1, 0, 1):
                    for j in buckets.get((int(a + da), int(b + db)), ()):
                        if label[j] < 0 and np.hypot(*(points[j] - points[i])) <= radius:
                            label[j] = seed
                            stack.append(j)
        groups.append(np.sort(np.array(members)))
    return groups


def fit_circle(points: np.ndarray) -> tuple[float, float, float, float]:
    """Least-squares (Kasa) circle: centre x, y, radius and the RMS radial residual."""
    a = np.c_[2.0 * points, np.ones(len(points))]
    b = (points ** 2).sum(axis=1)
    (cx, cy, c), *_ = np.linalg.lstsq(a, b, rcond=None)
    r = math.sqrt(max(c + cx * cx + cy * cy, 0.0))
    resid = np.hypot(points[:, 0] - cx, points[:, 1] - cy) - r
    return float(cx), float(cy), r, float(np.sqrt(np.mean(resid ** 2)))


@dataclass(frozen=True)
class FitSettings:
    res: float = 0.05             # m, grid cell
    max_radius: float = 0.6       # m, largest round obstacle fitted as a cylinder
    circle_rms: float = 0.025     # m, max RMS residual of a cylinder fit
    line_tol: float = 0.06        # m, max distance of a point from a wall line
    gap: float = 0.3              # m, a wall line breaks at gaps wider than this
    min_segment: float = 0.2      # m, shorter wall pieces are left to the box fallback
    wall_width: float = 0.15      # m, thickness of a wall box (only its near face is seen)
    max_block: float = 2.5        # m, longest side of a cluster fitted as one solid box
    link: float = 0.3             # m, returns closer than this belong to one obstacle


def _round(points: np.ndarray, s: FitSettings) -> tuple[float, float, float] | None:
    if len(points) < 5:
        return None
    cx, cy, r, rms = fit_circle(points)
    if not (0.02 <= r <= s.max_radius) or rms > max(s.circle_rms, 0.1 * r):
        return None
    # the returns must wrap around the centre, not be a nearly straight piece of wall
    cov = np.cov((points - points.mean(axis=0)).T)
    ev = np.linalg.eigvalsh(cov)
    if ev[0] < 0.05 * ev[1]:
        return None
    return cx, cy, r


def _box_from_points(name: str, points: np.ndarray, viewpoint: np.ndarray, s: FitSettings,
                     direction: np.ndarray | None = None) -> BoxObstacle:
    """An oriented box around ``points``; a thin piece is thickened away from ``viewpoint``."""
    centre = points.mean(axis=0)
    if direction is None:
        if len(points) >= 2:
            _, vecs = np.linalg.eigh(np.cov((points - centre).T))
            direction = vecs[:, 1]
        else:
            direction = np.array([1.0, 0.0])
    d = direction / np.linalg.norm(direction)
    n = np.array([-d[1], d[0]])
    along = (points - centre) @ d
    across = (points - centre) @ n
    lo_a, hi_a = along.min() - s.res / 2, along.max() + s.res / 2
    lo_n, hi_n = across.min() - s.res / 2, across.max() + s.res / 2
    if hi_n - lo_n < s.wall_width:
        side = float((viewpoint - centre) @ n)   # the viewer's side stays where it was
        if side >= 0:
            lo_n = hi_n - s.wall_width
        else:
            hi_n = lo_n + s.wall_width
    mid = centre + d * (lo_a + hi_a) / 2 + n * (lo_n + hi_n) / 2
    yaw = math.degrees(math.atan2(d[1], d[0]))
    yaw = (yaw + 90.0) % 180.0 - 90.0  # a box is symmetric: keep yaw in [-90, 90)
    return BoxObstacle(name=name, x=_r(mid[0]), y=_r(mid[1]), length=_r(hi_a - lo_a),
                       width=_r(hi_n - lo_n), yaw=_r(yaw, 2))


def _r(v: float, nd: int = 3) -> float:
    return float(round(float(v), nd)) + 0.0


def _lines(points: np.ndarray, s: FitSettings) -> list[tuple[np.ndarray, np.ndarray]]:
    """Split points into straight runs (Hough peak, PCA refine, split at gaps): (points, direction)."""
    out = []
    rest = points
    thetas = np.radians(np.arange(0.0, 180.0, 1.0))
    cs, sn = np.cos(thetas), np.sin(thetas)
    for _ in range(64):
        if len(rest) < 4:
            break
        rho = rest[:, 0:1] * cs + rest[:, 1:2] * sn           # (k, 180)
        bins = np.round(rho / s.line_tol).astype(np.int64)
        best = (0, 0, 0)
        for j in range(len(thetas)):
            vals, cnt = np.unique(bins[:, j], return_counts=True)
            k = int(cnt.argmax())
            if cnt[k] > best[0]:
                best = (int(cnt[k]), j, int(vals[k]))
        count, j, b = best
        if count < 4:
            break
        inl = np.abs(rho[:, j] - b * s.line_tol) <= s.line_tol
        pts = rest[inl]
        centre = pts.mean(axis=0)
        _, vecs = np.linalg.eigh(np.cov((pts - centre).T))
        d = vecs[:, 1]
        nrm = np.array([-d[1], d[0]])
        inl = np.abs((rest - centre) @ nrm) <= s.line_tol
        pts = rest[inl]
        along = (pts - centre) @ d
        order = np.argsort(along)
        pts, along = pts[order], along[order]
        breaks = np.nonzero(np.diff(along) > s.gap)[0] + 1
        used = np.zeros(len(pts), bool)
        for run_idx in np.split(np.arange(len(pts)), breaks):
            run = pts[run_idx]
            if len(run) >= 4 and along[run_idx[-1]] - along[run_idx[0]] >= s.min_segment:
                out.append((run, d))
                used[run_idx] = True
        if not used.any():
            break
        keep = np.ones(len(rest), bool)
        keep[np.nonzero(inl)[0][order[used]]] = False
        rest = rest[keep]
    out.append((rest, None))  # leftovers, possibly empty
    return out


def _compact_box(points: np.ndarray, free_xy: np.ndarray | None, s: FitSettings) -> BoxObstacle | None:
    """One oriented box for a cluster that outlines a solid block seen from two or more sides:
    its minimum rotated rectangle is small, thick, hugged by the returns and holds no pose the
    robot drove through (so a corner of walls around the robot is not filled in)."""
    import shapely
    from shapely.geometry import MultiPoint

    if len(points) < 6:
        return None
    rect = MultiPoint(points).minimum_rotated_rectangle
    if rect.geom_type != "Polygon":
        return None
    xy = np.asarray(rect.exterior.coords)[:4]
    e1, e2 = xy[1] - xy[0], xy[2] - xy[1]
    a, b = float(np.hypot(*e1)), float(np.hypot(*e2))
    if min(a, b) < 3 * s.res or max(a, b) > s.max_block:
        return None
    if np.mean(shapely.distance(rect.exterior, shapely.points(points))) > s.res:
        return None
    if free_xy is not None and len(free_xy) and shapely.contains_xy(rect, free_xy[:, 0], free_xy[:, 1]).any():
        return None
    d = e1 if a >= b else e2
    yaw = (math.degrees(math.atan2(d[1], d[0])) + 90.0) % 180.0 - 90.0
    c = xy.mean(axis=0)
    return BoxObstacle(name="", x=_r(c[0]), y=_r(c[1]), length=_r(max(a, b)), width=_r(min(a, b)), yaw=_r(yaw, 2))


def fit_obstacles(clusters: list[Cluster], s: FitSettings = FitSettings(),
                  free_xy: np.ndarray | None = None) -> list[Obstacle]:
    """Cylinders for round clusters, one box for a compact block, else oriented boxes for the
    straight runs and small leftovers. ``free_xy``: positions the robot drove through."""
    obstacles: list[Obstacle] = []
    n_cyl = n_box = 0
    for cl in sorted(clusters, key=lambda c: (round(float(c.points[:, 0].mean()), 3),
                                               round(float(c.points[:, 1].mean()), 3))):
        circle = _round(cl.points, s)
        if circle is not None:
            n_cyl += 1
            obstacles.append(CylinderObstacle(name=f"pillar{n_cyl}", x=_r(circle[0]), y=_r(circle[1]),
                                              radius=_r(circle[2])))
            continue
        block = _compact_box(cl.points, free_xy, s)
        if block is not None:
            n_box += 1
            obstacles.append(dataclasses.replace(block, name=f"box{n_box}"))
            continue
        for pts, direction in _lines(cl.points, s):
            # leftovers of the line search (corners, stubs) are boxed per local group
            groups = [pts] if direction is not None else [pts[g] for g in _groups(pts, 1.5 * s.res)]
            for grp in groups:
                if len(grp) < 3:
                    continue
                n_box += 1
                obstacles.append(_box_from_points(f"wall{n_box}", grp, cl.viewpoint, s, direction))
    kept = _drop_contained(obstacles)
    counts: dict[str, int] = {}
    named = []
    for o in kept:  # number each kind 1, 2, ... again after the drop
        prefix = o.name.rstrip("0123456789")
        counts[prefix] = counts.get(prefix, 0) + 1
        named.append(dataclasses.replace(o, name=f"{prefix}{counts[prefix]}"))
    return named


def _drop_contained(obstacles: list[Obstacle], share: float = 0.5) -> list[Obstacle]:
    """Leave out a piece that lies mostly (``share`` of its area or more) inside a larger obstacle: the
    stray returns at a block's corner otherwise become a sliver stuck to the block."""
    from ..scenario.geometry import obstacle_polygon

    polys = [obstacle_polygon(o) for o in obstacles]
    keep = []
    for i, (o, p) in enumerate(zip(obstacles, polys)):
        inside = any(j != i and q.area > p.area and p.intersection(q).area >= share * p.area
                     for j, q in enumerate(polys))
        if not inside:
            keep.append(o)
    return keep


# ------------------------------------------------------------------ scenario

def _peak_rates(od: np.ndarray, window: float = 0.5) -> tuple[float, float]:
    """98th-percentile speed (m/s) and yaw rate (rad/s) over ``window``-second steps (odometry
    jitter makes per-message differences useless for limits)."""
    if len(od) < 2 or od[-1, 0] - od[0, 0] <= 0:
        return 0.0, 0.0
    t = np.arange(od[0, 0], od[-1, 0], window / 5)
    if len(t) < 6:
        return 0.0, 0.0
    x, y = np.interp(t, od[:, 0], od[:, 1]), np.interp(t, od[:, 0], od[:, 2])
    yaw = np.interp(t, od[:, 0], np.unwrap(od[:, 3]))
    speed = np.hypot(x[5:] - x[:-5], y[5:] - y[:-5]) / window
    rate = np.abs(yaw[5:] - yaw[:-5]) / window
    return float(np.percentile(speed, 98)), float(np.percentile(rate, 98))


@dataclass
class BagSeed:
    """The importer's result: the scenario, the driven path (t, x, y) and what to tell the user."""
    scenario: Scenario
    path: np.ndarray
    notes: list[str]
    mount: tuple[float, float, float] | None = None


def decimate_path(xy: np.ndarray, tolerance: float = 0.15, min_spacing: float = 0.5) -> np.ndarray:
    """Waypoints that follow the driven path within ``tolerance`` (Douglas-Peucker), no two
    closer than ``min_spacing``; excludes the first and last point (start and goal)."""
    from shapely.geometry import LineString
    if len(xy) < 3:
        return np.zeros((0, 2))
    simple = np.asarray(LineString(xy).simplify(tolerance, preserve_topology=False).coords)
    pts = [simple[0]]
    for p in simple[1:-1]:
        if np.hypot(*(p - pts[-1])) >= min_spacing:
            pts.append(p)
    inner = np.asarray(pts[1:])
    if len(inner) and np.hypot(*(inner[-1] - simple[-1])) < min_spacing:
        inner = inner[:-1]
    return inner.reshape(-1, 2)


def scenario_from_bag(path: str | Path, *, odom_topic: str | None = None, scan_topic: str | None = None,
                      start: float | None = None, end: float | None = None,
                      laser_pose: tuple[float, float, float] | None = None,
                      path_as: str = "waypoints", reference_file: str | None = None,
                      name: str = "", robot_radius: float = 0.15,
                      settings: FitSettings = FitSettings()) -> BagSeed:
    """Build a seed scenario from a bag (see the module docstring). ``laser_pose`` is x, y (m),
    yaw (degrees) of the laser in the robot's base frame; ``robot_radius`` the seed's circular
    footprint (m); ``reference_file`` is the CSV name
    written into ``scenario.reference`` when ``path_as`` is ``"reference"`` or ``"both"``
    (waypoints to drive the loop and the reference to measure how closely the run replays it)."""
    if not (math.isfinite(robot_radius) and 0 < robot_radius <= 5):
        raise BagImportError(f"--robot-radius must be a length in (0, 5] m, got {robot_radius}")
    if path_as not in PATH_AS:
        raise BagImportError(f"--path-as must be one of {', '.join(PATH_AS)}, got {path_as!r}")
    data = read_bag(path, odom_topic=odom_topic, scan_topic=scan_topic, start=start, end=end)
    notes = list(data.notes)
    od = data.odom
    obstacles: list[Obstacle] = []
    mount = None
    if data.scan_topic is not None:
        if laser_pose is not None:
            mount = (laser_pose[0], laser_pose[1], math.radians(laser_pose[2]))
            how = "from --laser-pose"
        else:
            mount = laser_mount(data)
            how = "from /tf_static"
            if mount is None and data.first_tf:
                mount = laser_mount(data, "/tf")
                how = "from the first /tf transforms (no /tf_static)"
            if mount is None:
                mount = estimate_mount(data)
                how = (f"estimated from the scans (no /tf_static transform {data.base_frame} -> "
                       f"{data.scan_frame}; pass --laser-pose x,y,yaw to set it)")
        notes.append(f"laser {data.scan_frame} at x={mount[0]:.3f} y={mount[1]:.3f} "
                     f"yaw={math.degrees(mount[2]):.1f} deg in {data.base_frame}, {how}")
        grid = grid_returns(data, mount, settings.res)
        clusters, dropped = occupied_clusters(grid, link=settings.link)
        obstacles = fit_obstacles(clusters, settings, free_xy=od[:, 1:3])
        n_cyl = sum(isinstance(o, CylinderObstacle) for o in obstacles)
        notes.append(f"{len(data.scan_t)} scans, {grid.returns} returns -> {len(clusters)} clusters -> "
                     f"{n_cyl} cylinders, {len(obstacles) - n_cyl} boxes"
                     + (f" ({dropped} specks of < 3 cells ignored as noise)" if dropped else ""))
    start_pose = Pose(_r(od[0, 1]), _r(od[0, 2]), _r(math.degrees(od[0, 3]), 2))
    goal_pose = Pose(_r(od[-1, 1]), _r(od[-1, 2]), _r(math.degrees(od[-1, 3]), 2))
    seg = np.hypot(*np.diff(od[:, 1:3], axis=0).T)
    length = float(seg.sum())
    duration = float(od[-1, 0] - od[0, 0])
    speed, yaw_rate = _peak_rates(od)
    path_rows = np.stack([od[:, 0] - od[0, 0], od[:, 1], od[:, 2]], axis=1)
    waypoints: tuple[Pose, ...] = ()
    reference = None
    if path_as in ("waypoints", "both"):
        wps = decimate_path(od[:, 1:3])
        waypoints = tuple(Pose(_r(x), _r(y)) for x, y in wps)
    if path_as in ("reference", "both"):
        reference = Reference(file=reference_file or "reference.csv")
    # 20 % above the real peak speed, rounded up to 0.05 m/s: headroom for the planner
    limits = Limits(max_speed=_r(max(0.2, math.ceil(speed * 1.2 * 20) / 20), 2),
                    max_yaw_rate=_r(max(30.0, math.ceil(math.degrees(yaw_rate) * 1.2 / 5) * 5), 1))
    lidar = Lidar(beams=min(len(data.scan_angles), 360) if data.scan_topic else 72,
                  range_max=_r(data.range_max if data.scan_topic and math.isfinite(data.range_max) else 8.0, 2),
                  range_min=_r(data.range_min if data.scan_topic else 0.05, 3))
    robot = Robot(footprint=Footprint(shape="circle", radius=robot_radius), drive="diff", limits=limits, lidar=lidar)
    timeout = _r(max(30.0, math.ceil(max(duration, length / max(limits.max_speed, 0.1)) * 2.0 + 10.0)), 1)
    scenario = Scenario(
        mission=Mission(start=start_pose, goal=goal_pose, waypoints=waypoints,
                        goal_tolerance=GoalTolerance(position=0.3), timeout=timeout),
        obstacles=tuple(obstacles), robot=robot, reference=reference, name=name,
        description=(f"Seed from {Path(path).name}: {data.odom_topic} ({length:.1f} m in {duration:.1f} s)"
                     + (f", obstacles from {data.scan_topic}" if data.scan_topic else ", no obstacles (no scans)")
                     + f"; frame {data.odom_frame}."),
    )
    notes.append(f"path {length:.1f} m in {duration:.1f} s: "
                 + ", ".join(([f"{len(waypoints)} waypoints"] if path_as != "reference" else [])
                             + ([f"reference trajectory of {len(od)} poses"] if path_as != "waypoints" else [])))
    return BagSeed(scenario=scenario, path=path_rows, notes=notes, mount=mount)


# ------------------------------------------------------------------ CLI

def _triple(text: str) -> tuple[float, float, float]:
    try:
        parts = [float(v) for v in text.split(",")]
    except ValueError:
        parts = []
    if len(parts) != 3 or not all(math.isfinite(v) for v in parts):
        raise argparse.ArgumentTypeError(f"expected x,y,yaw (metres, metres, degrees), got {text!r}")
    return parts[0], parts[1], parts[2]


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("bag", metavar="PATH", help="ROS 1 .bag file, rosbag2 folder, or .mcap/.db3 file")
    p.add_argument("-o", "--output", required=True, metavar="OUT.yaml",
                   help="seed scenario YAML to write (an existing file is kept unless --force)")
    p.add_argument("--start", type=float, default=None, metavar="SECONDS", help="window start, seconds after the first odometry message")
    p.add_argument("--end", type=float, default=None, metavar="SECONDS", help="window end, seconds after the first odometry message")
    p.add_argument("--odom-topic", default=None, metavar="TOPIC", help="nav_msgs/Odometry topic (default: found by type)")
    p.add_argument("--scan-topic", default=None, metavar="TOPIC", help="sensor_msgs/LaserScan topic (default: found by type)")
    p.add_argument("--laser-pose", type=_triple, default=None, metavar="X,Y,YAW",
                   help="laser pose in the odometry child frame (m, m, degrees; e.g. --laser-pose -0.064,0,0); "
                        "default /tf_static, else estimated from the scans")
    p.add_argument("--path-as", choices=PATH_AS, default="waypoints",
                   help="driven path as decimated waypoints (default), a reference trajectory (CSV t,x,y beside "
                        "the seed, for the reference deviation metrics) or both")
    p.add_argument("--robot-radius", type=float, default=0.15, metavar="METRES",
                   help="the seed robot's circular footprint radius, m (default 0.15; edit the seed for a box)")
    p.add_argument("--name", default="", metavar="TEXT", help="scenario name (default: the output file's stem)")
    p.add_argument("--force", action="store_true", help="overwrite an existing output file")


def run(args: argparse.Namespace) -> int:
    from .world_import import write_seed
    out = Path(args.output)
    csv_name = f"{out.stem}.reference.csv"
    seed = scenario_from_bag(args.bag, odom_topic=args.odom_topic, scan_topic=args.scan_topic,
                             start=args.start, end=args.end, laser_pose=args.laser_pose,
                             path_as=args.path_as, reference_file=csv_name, name=args.name,
                             robot_radius=args.robot_radius)
    extra = {}
    if args.path_as != "waypoints":
        extra[csv_name] = reference_csv(seed.path)
    write_seed(seed.scenario, out, extra_files=extra, force=args.force)
    for note in seed.notes:
        print(f"navscenario from-bag: {note}")
    print(f"navscenario from-bag: wrote {out}" + (f" and {out.parent / csv_name}" if extra else ""))
    return 0


def reference_csv(rows: np.ndarray) -> str:
    """The reference trajectory file: a ``t,x,y`` header and one row per odometry message."""
    lines = ["t,x,y"] + [f"{t:.3f},{x:.4f},{y:.4f}" for t, x, y in rows]
    return "\n".join(lines) + "\n"
