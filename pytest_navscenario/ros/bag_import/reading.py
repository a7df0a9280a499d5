"""Reading a bag: pick the odometry and laser topics (by type, or as named) and read them,
with the static transforms, into plain arrays (:class:`BagData`).

Reads ROS 1 bags, rosbag2 sqlite3 and MCAP (also old ROS 2 bags with no embedded message
definitions) with ``rosbags``."""
from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ...core.errors import NavScenarioError

from .topics import (CLOUD_TYPES, ODOM_TYPES, SCAN_TYPES, command, footprint_from_params, goal_pose, planar,
                     pose_of, role, spatial, yaw_of)

CLOUD_TOPICS = ("/points", "/velodyne_points", "/ouster/points", "/lidar_points", "/hesai/pandar")
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
    odom: np.ndarray                  # (n, 4) t, x, y, yaw (rad) in the time window, in the world frame
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
    # beyond odometry and laser (times in s on the same clock as ``odom``; whole bag, not only the window)
    origin_ns: int = 0                                   # bag stamp of t = 0
    full_odom: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))  # the whole odometry, odometry frame
    duration: float = 0.0                                # s, the odometry's whole span
    static_tf3: dict[str, tuple[str, tuple[float, ...]]] = field(default_factory=dict)  # child -> (parent, x,y,z,q)
    frame_tf: list[tuple[float, str, str, float, float, float]] = field(default_factory=list)  # t, parent, child, x, y, yaw
    poses: dict[str, list[tuple[float, str, float, float, float]]] = field(default_factory=dict)  # topic -> t, frame, x, y, yaw
    goals: list[tuple[float, str, float, float, float, str]] = field(default_factory=list)  # t, frame, x, y, yaw, topic
    cmd: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))    # t, forward speed, yaw rate
    description: str | None = None                       # URDF text from /robot_description
    footprints: list[tuple[str, str, Any]] = field(default_factory=list)  # (source, "polygon"|"radius", value)
    cloud_topic: str | None = None
    cloud_frame: str = ""
    cloud_count: int = 0
    frame: str = ""                                      # the seed's world frame (odometry or map)
    known_map: Any = None                                # the last OccupancyGrid on /map (known_map.KnownMap)


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
             start: float | None = None, end: float | None = None, cloud_topic: str | None = None,
             at: float | None = None, window: float = 30.0) -> BagData:
    """Read odometry, laser scans and static transforms; ``start``/``end`` are seconds after
    the first odometry message (message header stamps; the bag's receive time where a stamp is
    zero); ``at`` with ``window``: the ``window`` seconds before the moment ``at`` instead.
    Raises BagImportError naming the file and what is missing."""
    path = Path(path)
    if scan_topic and cloud_topic:
        raise BagImportError("--scan-topic and --cloud-topic: give one (obstacles come from a laser or a 3D lidar)")
    with open_reader(path) as reader:
        return _read(reader, path, odom_topic, scan_topic, (start, end, at, window), cloud_topic)


@contextlib.contextmanager
def open_reader(path: Path):
    """An open rosbags AnyReader on ``path``; a bad or damaged bag is a BagImportError naming it."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    if not path.exists():
        raise BagImportError(f"{path}: no such bag file or folder")
    try:
        reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
        reader.open()
    except Exception as exc:  # rosbags raises several unrelated types for a bad file
        what = "a damaged or truncated bag" if _has_bag_magic(path) else "not a readable ROS 1 / rosbag2 bag"
        raise BagImportError(f"{path}: {what} ({_reason(exc)})") from None
    try:
        yield reader
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


def _stamp(header: Any, bag_ns: int) -> int:
    ns = int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)
    return ns if ns > 0 else bag_ns


def _read(reader: Any, path: Path, odom_topic, scan_topic, cut: tuple, cloud_topic=None) -> BagData:
    conns = list(reader.connections)
    odom_name = _pick(path, conns, odom_topic, ODOM_TYPES, "odometry", "--odom-topic", ("/odom",), True)
    scan_name = None if cloud_topic else \
        _pick(path, conns, scan_topic, SCAN_TYPES, "laser scan", "--scan-topic", ("/scan",), False)
    cloud_name = None if scan_name else \
        _pick(path, conns, cloud_topic, CLOUD_TYPES, "point cloud", "--cloud-topic", CLOUD_TOPICS, False)
    roles = {c.topic: role(c.topic, c.msgtype) for c in conns}
    # the clouds are big: they are read in a second pass, one at a time (clouds.py), not here
    wanted = [c for c in conns if c.topic in (odom_name, scan_name) or roles[c.topic]]
    col = _Collector(odom_name, scan_name, roles, _scan_window(*cut))
    for conn, bag_ns, raw in reader.messages(connections=wanted):
        col.take(conn.topic, reader.deserialize(raw, conn.msgtype), bag_ns)
    if not col.odom:
        raise BagImportError(f"{path}: topic {odom_name} has no messages; record odometry or choose "
                             f"another topic with --odom-topic")
    data, origin = _odometry(path, col, odom_name, *cut)
    _attach_extras(data, col, origin)
    if cloud_name is not None:
        data.cloud_topic = cloud_name
        data.cloud_count = sum(int(getattr(c, "msgcount", 0) or 0) for c in conns if c.topic == cloud_name)
        return data
    if scan_name is None:
        data.notes.append(f"no laser scan topic (and no point cloud) in {path.name}: the seed has the "
                          f"trajectory only, no obstacles")
        return data
    _attach_scans(data, col, scan_name, origin)
    return data


class _Collector:
    """What the first pass over the bag's messages keeps: odometry poses, scans of the first scan's
    beam layout, transforms, localisation poses, goals, velocity commands, the robot's description
    and footprint."""

    def __init__(self, odom_name: str, scan_name: str | None, roles: dict,
                 window: tuple[float, float] = (-math.inf, math.inf)):
        self.odom_name, self.scan_name, self.roles = odom_name, scan_name, roles
        self.window = window   # s after the first odometry message: scans outside it are not kept
        self.odom: list[tuple[int, float, float, float]] = []
        self.scans: list[tuple[int, np.ndarray]] = []
        self.static_tf: dict[str, tuple[str, float, float, float]] = {}
        self.static_tf3: dict[str, tuple[str, tuple[float, ...]]] = {}
        self.first_tf: dict[str, tuple[str, float, float, float]] = {}
        self.frame_tf: list[tuple[int, str, str, float, float, float]] = []
        self.poses: dict[str, list[tuple[int, str, float, float, float]]] = {}
        self.goals: list[tuple[int, str, float, float, float, str]] = []
        self.cmd: list[tuple[int, float, float]] = []
        self.description: str | None = None
        self.footprints: list[tuple[str, str, Any]] = []
        self.known_map: Any = None
        self.tf_seen = 0
        self.odom_frame = self.base_frame = self.scan_frame = ""
        self.scan_meta: tuple | None = None
        self.odd_scans = 0

    def take(self, topic: str, msg: Any, bag_ns: int) -> None:
        if topic == self.odom_name:
            p = msg.pose.pose
            self.odom.append((_stamp(msg.header, bag_ns), p.position.x, p.position.y, yaw_of(p.orientation)))
            self.odom_frame = self.odom_frame or msg.header.frame_id.lstrip("/")
            self.base_frame = self.base_frame or msg.child_frame_id.lstrip("/")
        elif topic == self.scan_name:
            self._scan(msg, bag_ns)
        else:
            getattr(self, f"_{self.roles[topic].replace('tf_static', 'static')}")(topic, msg, bag_ns)

    def _tf(self, topic: str, msg: Any, bag_ns: int) -> None:
        self.tf_seen += 1
        for tf in msg.transforms:
            child = tf.child_frame_id.lstrip("/")
            parent, x, y, yaw = planar(tf)
            if self.tf_seen <= TF_SCAN_LIMIT:  # older bags publish the laser mount on /tf
                self.first_tf.setdefault(child, (parent, x, y, yaw))
                if child not in self.static_tf:
                    self.static_tf3.setdefault(child, spatial(tf))
            if child != self.base_frame and ("odom" in child or "map" in parent):
                self.frame_tf.append((_stamp(tf.header, bag_ns), parent, child, x, y, yaw))

    def _static(self, topic: str, msg: Any, bag_ns: int) -> None:
        for tf in msg.transforms:
            self.static_tf[tf.child_frame_id.lstrip("/")] = planar(tf)
            self.static_tf3[tf.child_frame_id.lstrip("/")] = spatial(tf)

    def _pose(self, topic: str, msg: Any, bag_ns: int) -> None:
        p = pose_of(msg)
        self.poses.setdefault(topic, []).append((_stamp(msg.header, bag_ns), msg.header.frame_id.lstrip("/"),
                                                 p.position.x, p.position.y, yaw_of(p.orientation)))

    def _goal(self, topic: str, msg: Any, bag_ns: int) -> None:
        found = goal_pose(msg)
        if found is not None:
            header, p = found
            self.goals.append((_stamp(header, bag_ns), header.frame_id.lstrip("/"), p.position.x, p.position.y,
                               yaw_of(p.orientation), topic))

    def _cmd(self, topic: str, msg: Any, bag_ns: int) -> None:
        stamp = _stamp(msg.header, bag_ns) if hasattr(msg, "header") else bag_ns
        self.cmd.append((stamp, *command(msg)))

    def _description(self, topic: str, msg: Any, bag_ns: int) -> None:
        self.description = self.description or msg.data

    def _footprint(self, topic: str, msg: Any, bag_ns: int) -> None:
        pts = [(float(p.x), float(p.y)) for p in msg.polygon.points]
        if len(pts) >= 3 and not self.footprints:
            self.footprints.append((topic, "polygon", pts))

    def _params(self, topic: str, msg: Any, bag_ns: int) -> None:
        found = footprint_from_params(msg)
        if found is not None:
            self.footprints.append((f"parameter of {msg.node}", *found))

    def _map(self, topic: str, msg: Any, bag_ns: int) -> None:
        from .known_map import from_message
        self.known_map = from_message(msg, topic)

    def _scan(self, msg: Any, bag_ns: int) -> None:
        ranges = np.asarray(msg.ranges, dtype=np.float32)
        meta = (len(ranges), float(msg.angle_min), float(msg.angle_increment))
        if self.scan_meta is None:
            self.scan_meta = meta + (float(msg.range_min), float(msg.range_max))
            self.scan_frame = msg.header.frame_id.lstrip("/")
        elif meta != self.scan_meta[:3]:
            self.odd_scans += 1  # another beam layout than the first scan's: skipped, reported later
            return
        stamp = _stamp(msg.header, bag_ns)
        if self.odom:  # a time window is known once odometry started: hold only the scans in it
            t = (stamp - self.odom[0][0]) * 1e-9
            if not self.window[0] <= t <= self.window[1]:
                return
        self.scans.append((stamp, ranges))


def _scan_window(start, end, at=None, window: float = 30.0) -> tuple[float, float]:
    """The span (s after the first odometry message, 2 s wider each side for odometry stamps out
    of order) whose scans the first pass keeps: a cut of a long bag holds only its own scans."""
    if at is not None:
        start, end = at - window, at
    lo = -math.inf if start is None else start - 2.0
    hi = math.inf if end is None else end + 2.0
    return lo, hi


def _attach_extras(data: BagData, col: _Collector, origin: float) -> None:
    """Transforms, poses, goals, commands, description and footprints, on the odometry's clock."""
    def sec(ns: int) -> float:
        return (ns - origin) * 1e-9

    data.origin_ns = int(origin)
    data.static_tf3 = col.static_tf3
    data.frame_tf = sorted((sec(t), *rest) for t, *rest in col.frame_tf)
    data.poses = {k: sorted((sec(t), *rest) for t, *rest in v) for k, v in col.poses.items()}
    data.goals = sorted((sec(t), *rest) for t, *rest in col.goals)
    if col.cmd:
        cmd = np.array(col.cmd, dtype=float)
        cmd[:, 0] = (cmd[:, 0] - origin) * 1e-9
        data.cmd = cmd[np.argsort(cmd[:, 0], kind="stable")]
    data.description = col.description
    data.footprints = col.footprints
    data.known_map = col.known_map
    data.frame = data.odom_frame


def _odometry(path: Path, col: _Collector, odom_name: str, start, end, at=None,
              window: float = 30.0) -> tuple[BagData, float]:
    """The odometry sorted by time, t = 0 at its first message, cut to ``start``..``end`` (or
    ``at - window``..``at``); and the first message's stamp (ns), the origin of every other time."""
    odom_arr = np.array(col.odom, dtype=float)
    odom_arr = odom_arr[np.argsort(odom_arr[:, 0], kind="stable")]
    origin = float(odom_arr[0, 0])
    odom_arr[:, 0] = (odom_arr[:, 0] - origin) * 1e-9
    data = BagData(path=path, odom_topic=odom_name, odom_frame=col.odom_frame or "odom",
                   base_frame=col.base_frame or "base_link", odom=odom_arr, static_tf=col.static_tf,
                   first_tf=col.first_tf, duration=float(odom_arr[-1, 0]), full_odom=odom_arr)
    if at is not None:
        if not (math.isfinite(at) and 0 < at <= data.duration):
            raise BagImportError(f"{path}: --at {at:g} is outside the bag: its odometry covers 0..{data.duration:.1f} s "
                                 f"(times are seconds after the first odometry message; --list-events shows candidates)")
        if not (math.isfinite(window) and window > 0):
            raise BagImportError(f"--window must be a positive number of seconds, got {window}")
        start, end = max(0.0, at - window), at
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
    return data, origin


def _attach_scans(data: BagData, col: _Collector, scan_name: str, origin: float) -> None:
    """The scans inside the odometry's window, as one (scans, beams) array, with their beam angles."""
    if col.scans:
        st = (np.array([s[0] for s in col.scans], dtype=float) - origin) * 1e-9
        inside = (st >= data.odom[0, 0]) & (st <= data.odom[-1, 0])
        n, amin, ainc, rmin, rmax = col.scan_meta
        if col.odd_scans:
            data.notes.append(f"{col.odd_scans} scan(s) on {scan_name} with another beam count or angles than "
                              f"the first ({n} beams from {math.degrees(amin):.1f} deg) were skipped")
        data.scan_topic = scan_name
        data.scan_frame = col.scan_frame
        data.scan_t = st[inside]
        data.scan_ranges = np.stack([s[1] for s, k in zip(col.scans, inside) if k]) if inside.any() \
            else np.zeros((0, n), np.float32)
        data.scan_angles = amin + ainc * np.arange(n)
        data.range_min, data.range_max = rmin, rmax
    if len(data.scan_t) == 0:
        data.notes.append(f"topic {scan_name} has no scans within the odometry's time window: "
                          f"the seed has the trajectory only, no obstacles")
        data.scan_topic = None
