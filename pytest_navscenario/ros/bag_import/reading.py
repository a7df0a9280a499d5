"""Reading a bag: pick the odometry and laser topics (by type, or as named) and read them,
with the static transforms, into plain arrays (:class:`BagData`).

Reads ROS 1 bags, rosbag2 sqlite3 and MCAP (also old ROS 2 bags with no embedded message
definitions) with ``rosbags``."""
from __future__ import annotations

import array
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
    # scans are not held: their layout and timing are read in the first pass, the scans themselves
    # streamed in a second (scans.stream_scans); ``scan_received`` are the bag's receive times (ns)
    # of every scan, for picking a sample without reading them
    scan_layout: Any = None                              # scans.ScanLayout
    scan_timing: Any = None                              # scans.ScanTiming
    scan_stats: Any = None                               # scans.StreamStats of the last streamed pass
    scan_received: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    scan_probe: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # s: stamp, receive time (a sample)
    scan_probe_ranges: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.float32))  # its ranges
    static_tf: dict[str, tuple[str, float, float, float]] = field(default_factory=dict)  # child -> (parent, x, y, yaw)
    first_tf: dict[str, tuple[str, float, float, float]] = field(default_factory=dict)   # the same, first seen on /tf
    notes: list[str] = field(default_factory=list)
    # beyond odometry and laser (times in s on the same clock as ``odom``; whole bag, not only the window)
    origin_ns: int = 0                                   # bag stamp of t = 0
    full_odom: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))  # the whole odometry, odometry frame
    # the odometry's third dimension, row for row with ``odom``: t, z (m), roll, pitch (rad); all 0
    # when the odometry is planar (the robot then counts as level at z = 0)
    odom_up: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    duration: float = 0.0                                # s, the odometry's whole span
    static_tf3: dict[str, tuple[str, tuple[float, ...]]] = field(default_factory=dict)  # child -> (parent, x,y,z,q)
    frame_tf: list[tuple[float, str, str, float, float, float]] = field(default_factory=list)  # t, parent, child, x, y, yaw
    poses: dict[str, list[tuple[float, str, float, float, float]]] = field(default_factory=dict)  # topic -> t, frame, x, y, yaw
    goals: list[tuple[float, str, float, float, float, str]] = field(default_factory=list)  # t, frame, x, y, yaw, topic
    cmd: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))    # t, forward speed, yaw rate
    description: str | None = None                       # URDF text from /robot_description
    recorded: str | None = None                          # the scenario YAML on /navscenario/scenario (our bags)
    footprints: list[tuple[str, str, Any]] = field(default_factory=list)  # (source, "polygon"|"radius", value)
    cloud_topic: str | None = None
    cloud_frame: str = ""
    cloud_count: int = 0
    frame: str = ""                                      # the seed's world frame (odometry or map)
    known_map: Any = None                                # the last OccupancyGrid on /map (known_map.KnownMap)
    reader: Any = field(default=None, repr=False)        # the open bag the later passes reuse (or None)

    @property
    def scan_angles(self) -> np.ndarray:
        return self.scan_layout.angles if self.scan_layout is not None else np.zeros(0)

    @property
    def range_min(self) -> float:
        return self.scan_layout.range_min if self.scan_layout is not None else 0.0

    @property
    def range_max(self) -> float:
        return self.scan_layout.range_max if self.scan_layout is not None else math.inf


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
             at: float | None = None, window: float = 30.0, scan_stamp: str = "auto",
             scan_offset: float = 0.0, reader: Any = None) -> BagData:
    """Read odometry, the laser's layout and timing, and static transforms; ``start``/``end`` are
    seconds after the first odometry message (message header stamps; the bag's receive time where a
    stamp is zero); ``at`` with ``window``: the ``window`` seconds before the moment ``at`` instead
    (to the end of a turn in place or reversing under way at ``at``). The scans themselves are
    streamed later (``scans.stream_scans``); ``scan_stamp`` ("auto", "start", "end") and
    ``scan_offset`` (s) say when they were taken (``scans.choose_timing``). ``reader``: an open
    bag (``open_bag``) that the later passes reuse; the caller closes it.
    Raises BagImportError naming the file and what is missing."""
    path = Path(path)
    if scan_topic and cloud_topic:
        raise BagImportError("--scan-topic and --cloud-topic: give one (obstacles come from a laser or a 3D lidar)")
    from .scans import STAMPS
    if scan_stamp not in STAMPS:
        raise BagImportError(f"--scan-stamp must be one of {', '.join(STAMPS)}, got {scan_stamp!r}")
    if not (math.isfinite(scan_offset) and abs(scan_offset) <= 10.0):
        raise BagImportError(f"--scan-time-offset must be a number of seconds in [-10, 10], got {scan_offset}")
    if reader is not None:
        data = _read(reader, path, odom_topic, scan_topic, (start, end, at, window), cloud_topic,
                     (scan_stamp, scan_offset))
        data.reader = reader
        return data
    opened = open_bag(path)
    try:
        return _read(opened, path, odom_topic, scan_topic, (start, end, at, window), cloud_topic,
                     (scan_stamp, scan_offset))
    finally:
        close_bag(opened)


def open_bag(path: Path) -> Any:
    """An opened rosbags AnyReader on ``path`` (close it when done); a bad file is a BagImportError."""
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
    return reader


def close_bag(reader: Any) -> None:
    try:
        reader.close()
    except Exception:
        pass


@contextlib.contextmanager
def read_errors(path: Path):
    """Errors while reading messages (rosbags raises many kinds) as one BagImportError naming the bag."""
    try:
        yield
    except NavScenarioError:
        raise
    except Exception as exc:
        raise BagImportError(f"{path}: bag is damaged or truncated ({_reason(exc)})") from None


@contextlib.contextmanager
def open_reader(path: Path):
    """An open rosbags AnyReader on ``path``; a bad or damaged bag is a BagImportError naming it."""
    reader = open_bag(path)
    try:
        with read_errors(path):
            yield reader
    finally:
        close_bag(reader)


@contextlib.contextmanager
def bag_pass(data: "BagData"):
    """A reader for another pass over ``data``'s bag: the one its caller keeps open
    (``data.reader``: the bag's index and message types are read once), else a new one."""
    if data.reader is not None:
        with read_errors(data.path):
            yield data.reader
    else:
        with open_reader(data.path) as reader:
            yield reader


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


def stamp_ns(header: Any, bag_ns: int) -> int:
    """A message's header stamp in ns; the bag's receive time where the stamp is zero."""
    ns = int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)
    return ns if ns > 0 else bag_ns


_stamp = stamp_ns
PROBE = 150           # scans read in the first pass: the driver's timing, the laser mount's guess


def _read(reader: Any, path: Path, odom_topic, scan_topic, cut: tuple, cloud_topic=None,
          timing: tuple[str, float] = ("auto", 0.0)) -> BagData:
    conns = list(reader.connections)
    odom_name = _pick(path, conns, odom_topic, ODOM_TYPES, "odometry", "--odom-topic", ("/odom",), True)
    scan_name = None if cloud_topic else \
        _pick(path, conns, scan_topic, SCAN_TYPES, "laser scan", "--scan-topic", ("/scan",), False)
    cloud_name = None if scan_name else \
        _pick(path, conns, cloud_topic, CLOUD_TYPES, "point cloud", "--cloud-topic", CLOUD_TOPICS, False)
    roles = {c.topic: role(c.topic, c.msgtype) for c in conns}
    # scans and clouds are big: they are streamed in a second pass (scans.py, clouds.py), not held here
    wanted = [c for c in conns if c.topic in (odom_name, scan_name) or roles[c.topic]]
    scan_count = sum(int(getattr(c, "msgcount", 0) or 0) for c in conns if c.topic == scan_name)
    col = _Collector(odom_name, scan_name, roles, probe_every=max(1, scan_count // PROBE))
    with read_errors(path):    # only the reading: a mistake of ours is not called a damaged bag
        for conn, bag_ns, raw in reader.messages(connections=wanted):
            if conn.topic == scan_name:
                col.scan_seen(reader, conn, raw, bag_ns)
            else:
                col.take(conn.topic, reader.deserialize(raw, conn.msgtype), bag_ns)
    if not len(col.odom) and not col.odom_bad:
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
    _attach_scans(data, col, scan_name, origin, *timing)
    return data


class _Collector:
    """What the first pass over the bag's messages keeps: odometry poses, the scans' layout and a
    few of them (their timing), transforms, localisation poses, goals, velocity commands, the
    robot's description and footprint. Odometry is packed into a flat array of floats (32 bytes a
    message), not a list of tuples."""

    def __init__(self, odom_name: str, scan_name: str | None, roles: dict, probe_every: int = 1):
        self.odom_name, self.scan_name, self.roles = odom_name, scan_name, roles
        self.odom = array.array("d")                    # stamp (ns, as float), x, y, yaw, ...
        self.odom_up = array.array("d")                 # z, roll, pitch of the same messages
        self.odom_bad = 0                               # odometry messages with a NaN / inf pose
        self.scan_received = array.array("q")           # every scan's receive time (ns)
        self.probe: list[tuple[int, int]] = []          # (stamp ns, receive ns) of the probed scans
        self.probe_ranges: list[np.ndarray] = []        # and their ranges
        self.probe_every = probe_every
        self.scan_layout: Any = None
        self.bad_layout: tuple[int, str] = (0, "")      # scans whose beams cannot be placed, and why
        self.static_tf: dict[str, tuple[str, float, float, float]] = {}
        self.static_tf3: dict[str, tuple[str, tuple[float, ...]]] = {}
        self.first_tf: dict[str, tuple[str, float, float, float]] = {}
        self.frame_tf: list[tuple[int, str, str, float, float, float]] = []
        self.poses: dict[str, list[tuple[int, str, float, float, float]]] = {}
        self.goals: list[tuple[int, str, float, float, float, str]] = []
        self.cmd: list[tuple[int, float, float]] = []
        self.description: str | None = None
        self.recorded: str | None = None
        self.footprints: list[tuple[str, str, Any]] = []
        self.known_map: Any = None
        self.tf_seen = 0
        self.odom_frame = self.base_frame = ""

    def take(self, topic: str, msg: Any, bag_ns: int) -> None:
        if topic == self.odom_name:
            p = msg.pose.pose
            pose = (float(p.position.x), float(p.position.y), yaw_of(p.orientation))
            if not all(math.isfinite(v) for v in pose):
                self.odom_bad += 1
                return
            self.odom.extend((float(_stamp(msg.header, bag_ns)),) + pose)
            self.odom_up.extend((float(p.position.z),) + _roll_pitch(p.orientation))
            self.odom_frame = self.odom_frame or msg.header.frame_id.lstrip("/")
            self.base_frame = self.base_frame or msg.child_frame_id.lstrip("/")
        else:
            getattr(self, f"_{self.roles[topic].replace('tf_static', 'static')}")(topic, msg, bag_ns)

    def scan_seen(self, reader: Any, conn: Any, raw: Any, bag_ns: int) -> None:
        """Every scan's receive time; the layout of the first usable scan and a probe of every
        ``probe_every``-th (their stamps), deserialised; the rest are read in the second pass."""
        index = len(self.scan_received)
        self.scan_received.append(bag_ns)
        if self.scan_layout is not None and index % self.probe_every:
            return
        from .scans import layout_of, layout_problem
        msg = reader.deserialize(raw, conn.msgtype)
        layout = layout_of(msg, conn.topic)
        problem = layout_problem(layout)
        if problem is not None:
            self.bad_layout = (self.bad_layout[0] + 1, problem)
            return
        if self.scan_layout is None:
            self.scan_layout = layout
        elif layout.key() != self.scan_layout.key():
            return
        self.probe.append((_stamp(msg.header, bag_ns), bag_ns))
        self.probe_ranges.append(np.asarray(msg.ranges, dtype=np.float32))

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

    def _recorded(self, topic: str, msg: Any, bag_ns: int) -> None:
        self.recorded = self.recorded or msg.data

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
    data.recorded = col.recorded
    data.footprints = col.footprints
    data.known_map = col.known_map
    data.frame = data.odom_frame


def _odometry(path: Path, col: _Collector, odom_name: str, start, end, at=None,
              window: float = 30.0) -> tuple[BagData, float]:
    """The odometry sorted by time, t = 0 at its first message, cut to ``start``..``end`` (or
    ``at - window``..``at``, to the end of a turn in place or reversing under way at ``at``); and
    the first message's stamp (ns), the origin of every other time."""
    from .motion import manoeuvre_at

    odom_arr = np.frombuffer(col.odom, dtype=float).reshape(-1, 4).copy()
    up_arr = np.frombuffer(col.odom_up, dtype=float).reshape(-1, 3)
    notes = []
    if col.odom_bad:
        if not len(odom_arr):
            raise BagImportError(f"{path}: every pose on {odom_name} ({col.odom_bad} messages) has a NaN or infinite "
                                 f"position or orientation: there is no pose to place the robot with")
        notes.append(f"warning: {col.odom_bad} message(s) on {odom_name} with a NaN or infinite pose were left out "
                     f"(the robot's pose there is interpolated from its neighbours)")
    if len(odom_arr) < 2:
        raise BagImportError(f"{path}: {odom_name} has {len(odom_arr)} usable message(s): a seed needs the robot's "
                             f"poses over time (a start and a goal apart); record longer, or choose another topic "
                             f"with --odom-topic")
    order = np.argsort(odom_arr[:, 0], kind="stable")
    odom_arr = odom_arr[order]
    up_arr = np.nan_to_num(up_arr[order], nan=0.0, posinf=0.0, neginf=0.0)
    origin = float(odom_arr[0, 0])
    if odom_arr[-1, 0] == origin:
        raise BagImportError(f"{path}: all {len(odom_arr)} messages on {odom_name} have the same header stamp "
                             f"({origin * 1e-9:.3f} s): their times are unknown, so the robot's speed and the moment "
                             f"of each scan cannot be told; fix the clock of the node that publishes {odom_name}")
    odom_arr[:, 0] = (odom_arr[:, 0] - origin) * 1e-9
    data = BagData(path=path, odom_topic=odom_name, odom_frame=col.odom_frame or "odom",
                   base_frame=col.base_frame or "base_link", odom=odom_arr, static_tf=col.static_tf,
                   first_tf=col.first_tf, duration=float(odom_arr[-1, 0]), full_odom=odom_arr, notes=notes,
                   odom_up=np.column_stack([odom_arr[:, 0], up_arr]))
    if at is not None:
        if not (math.isfinite(at) and 0 < at <= data.duration):
            raise BagImportError(f"{path}: --at {at:g} is outside the bag: its odometry covers 0..{data.duration:.1f} s "
                                 f"(times are seconds after the first odometry message; --list-events shows candidates)")
        if not (math.isfinite(window) and window > 0):
            raise BagImportError(f"--window must be a positive number of seconds, got {window}")
        start, end = at - window, at
        if start < 0:
            notes.append(f"the window of {window:g} s before --at {at:g} would reach before the bag's start: cut there, "
                         f"it covers 0..{at:g} s ({at:g} s)")
            start = 0.0
        moving = manoeuvre_at(odom_arr, at)
        if moving is not None and moving[2] > at:
            kind, t0, t1 = moving
            end = min(t1, data.duration)
            notes.append(f"--at {at:g} falls on a {kind} (t={t0:.1f}..{t1:.1f} s): the seed runs to its end at "
                         f"t={end:.1f} s so that it holds the {kind}")
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
        data.odom_up = data.odom_up[keep]
    return data, origin


def _attach_scans(data: BagData, col: _Collector, scan_name: str, origin: float, stamp: str = "auto",
                  offset: float = 0.0) -> None:
    """The scans' layout and timing (scans.choose_timing): the scans themselves are streamed later."""
    from .scans import choose_timing

    bad, why = col.bad_layout
    if col.scan_layout is None:
        if bad:
            raise BagImportError(f"{data.path}: every scan read on {scan_name} is unusable: {why}; fix the laser "
                                 f"driver's output, or pass --scan-topic for another laser")
        data.notes.append(f"topic {scan_name} has no scans: the seed has the trajectory only, no obstacles")
        return
    if bad:
        data.notes.append(f"warning: scans on {scan_name} are unusable ({why}): {bad} of those read in the first "
                          f"pass; every such scan is left out")
    data.scan_topic = scan_name
    data.scan_layout = col.scan_layout
    data.scan_frame = col.scan_layout.frame
    data.scan_received = np.frombuffer(col.scan_received, dtype=np.int64).copy()
    probe = np.array(col.probe, dtype=float).reshape(-1, 2)
    data.scan_probe = (probe - origin) * 1e-9
    data.scan_probe_ranges = np.stack(col.probe_ranges)
    rec = np.sort(data.scan_received)
    period = float((rec[-1] - rec[0]) / (len(rec) - 1)) * 1e-9 if len(rec) > 1 else 0.0
    data.scan_timing = choose_timing(col.scan_layout, data.scan_probe[:, 0], data.scan_probe[:, 1], period,
                                     stamp, offset)
    data.notes.extend(f"warning: {w}" for w in data.scan_timing.warnings)


def _roll_pitch(q: Any) -> tuple[float, float]:
    """Roll and pitch (rad, Z-Y-X) of a geometry_msgs quaternion."""
    w, x, y, z = float(q.w), float(q.x), float(q.y), float(q.z)
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    return roll, pitch
