"""Reading a bag: pick the odometry and laser topics (by type, or as named) and read them,
with the static transforms, into plain arrays (:class:`BagData`).

Reads ROS 1 bags, rosbag2 sqlite3 and MCAP (also old ROS 2 bags with no embedded message
definitions) with ``rosbags``."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ...core.errors import NavScenarioError

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
    col = _Collector(odom_name)
    for conn, bag_ns, raw in reader.messages(connections=wanted):
        col.take(conn.topic, reader.deserialize(raw, conn.msgtype), bag_ns)
    if not col.odom:
        raise BagImportError(f"{path}: topic {odom_name} has no messages; record odometry or choose "
                             f"another topic with --odom-topic")
    data, origin = _odometry(path, col, odom_name, start, end)
    if scan_name is None:
        data.notes.append(f"no laser scan topic in {path.name}: the seed has the trajectory only, no obstacles")
        return data
    _attach_scans(data, col, scan_name, origin)
    return data


class _Collector:
    """What one pass over the bag's messages keeps: odometry poses, scans of the first scan's
    beam layout, the static transforms and the first /tf transform of each frame."""

    def __init__(self, odom_name: str):
        self.odom_name = odom_name
        self.odom: list[tuple[int, float, float, float]] = []
        self.scans: list[tuple[int, np.ndarray]] = []
        self.static_tf: dict[str, tuple[str, float, float, float]] = {}
        self.first_tf: dict[str, tuple[str, float, float, float]] = {}
        self.tf_seen = 0
        self.odom_frame = self.base_frame = self.scan_frame = ""
        self.scan_meta: tuple | None = None
        self.odd_scans = 0

    def take(self, topic: str, msg: Any, bag_ns: int) -> None:
        if topic == "/tf":
            # older bags publish the laser mount on /tf: keep the first transform of each frame
            self.tf_seen += 1
            if self.tf_seen <= TF_SCAN_LIMIT:
                for tf in msg.transforms:
                    self.first_tf.setdefault(tf.child_frame_id.lstrip("/"), _planar(tf))
        elif topic == "/tf_static":
            for tf in msg.transforms:
                self.static_tf[tf.child_frame_id.lstrip("/")] = _planar(tf)
        elif topic == self.odom_name:
            p = msg.pose.pose
            self.odom.append((_stamp(msg.header, bag_ns), p.position.x, p.position.y, _yaw(p.orientation)))
            self.odom_frame = self.odom_frame or msg.header.frame_id.lstrip("/")
            self.base_frame = self.base_frame or msg.child_frame_id.lstrip("/")
        else:
            self._scan(msg, bag_ns)

    def _scan(self, msg: Any, bag_ns: int) -> None:
        ranges = np.asarray(msg.ranges, dtype=np.float32)
        meta = (len(ranges), float(msg.angle_min), float(msg.angle_increment))
        if self.scan_meta is None:
            self.scan_meta = meta + (float(msg.range_min), float(msg.range_max))
            self.scan_frame = msg.header.frame_id.lstrip("/")
        elif meta != self.scan_meta[:3]:
            self.odd_scans += 1  # another beam layout than the first scan's: skipped, reported later
            return
        self.scans.append((_stamp(msg.header, bag_ns), ranges))


def _planar(tf: Any) -> tuple[str, float, float, float]:
    """(parent frame, x, y, yaw) of a geometry_msgs/TransformStamped."""
    tr, rot = tf.transform.translation, tf.transform.rotation
    return (tf.header.frame_id.lstrip("/"), tr.x, tr.y, _yaw(rot))


def _odometry(path: Path, col: _Collector, odom_name: str, start, end) -> tuple[BagData, float]:
    """The odometry sorted by time, t = 0 at its first message, cut to ``start``..``end``;
    and the first message's stamp (ns), the origin of every other time."""
    odom_arr = np.array(col.odom, dtype=float)
    odom_arr = odom_arr[np.argsort(odom_arr[:, 0], kind="stable")]
    origin = float(odom_arr[0, 0])
    odom_arr[:, 0] = (odom_arr[:, 0] - origin) * 1e-9
    data = BagData(path=path, odom_topic=odom_name, odom_frame=col.odom_frame or "odom",
                   base_frame=col.base_frame or "base_link", odom=odom_arr, static_tf=col.static_tf,
                   first_tf=col.first_tf)
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
