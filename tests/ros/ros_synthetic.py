"""Bags written from a known world, for checking what ``from-bag`` reconstructs against the truth.

A world is round pillars and upright boxes with heights on a flat ground; a drive is a list of
timed poses. ``laser_ranges`` and ``cloud_points`` ray-cast that world exactly (a 2D laser at a
height sees only what reaches that height; a 3D lidar sees the ground too). ``BagOut`` writes
messages in ROS 1 or rosbag2 (MCAP) format with the project's own ``build`` helper.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pytest_navscenario.ros.bag_writer import _typestore, build


@dataclass
class World:
    pillars: list[tuple[float, float, float, float]] = field(default_factory=list)        # x, y, r, height
    boxes: list[tuple[float, float, float, float, float, float]] = field(default_factory=list)  # x, y, l, w, yaw deg, h


def _hit_distances(world: World, ox: float, oy: float, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal distance along each unit direction (k, 2) to the first obstacle side, and that
    obstacle's height (inf distance where nothing is hit)."""
    best, height, _ = _hits(world, ox, oy, dirs)
    return best, height


def _hits(world: World, ox, oy, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``_hit_distances`` and |cos| of the angle between each beam and the surface's normal where
    it meets it (1 head-on, near 0 grazing)."""
    best = np.full(len(dirs), np.inf)
    height = np.zeros(len(dirs))
    cosine = np.ones(len(dirs))
    for cx, cy, r, h in world.pillars:
        fx, fy = ox - cx, oy - cy
        b = dirs[:, 0] * fx + dirs[:, 1] * fy
        c = fx * fx + fy * fy - r * r
        disc = b * b - c
        t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
        t = np.where(t > 1e-6, t, np.inf)
        closer = t < best
        with np.errstate(invalid="ignore"):
            cos_p = np.abs(b + t) / r
        best, height = np.where(closer, t, best), np.where(closer, h, height)
        cosine = np.where(closer, np.minimum(cos_p, 1.0), cosine)
    for cx, cy, ln, wd, yaw, h in world.boxes:
        c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
        # ray in the box frame, slab test
        px, py = c * (ox - cx) + s * (oy - cy), -s * (ox - cx) + c * (oy - cy)
        dx, dy = c * dirs[:, 0] + s * dirs[:, 1], -s * dirs[:, 0] + c * dirs[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            t1x, t2x = (-ln / 2 - px) / dx, (ln / 2 - px) / dx
            t1y, t2y = (-wd / 2 - py) / dy, (wd / 2 - py) / dy
        tmin = np.maximum(np.minimum(t1x, t2x), np.minimum(t1y, t2y))
        tmax = np.minimum(np.maximum(t1x, t2x), np.maximum(t1y, t2y))
        t = np.where((tmax >= tmin) & (tmin > 1e-6), tmin, np.inf)
        closer = t < best
        x_face = np.minimum(t1x, t2x) >= np.minimum(t1y, t2y)      # entered through an x face
        best, height = np.where(closer, t, best), np.where(closer, h, height)
        cosine = np.where(closer, np.where(x_face, np.abs(dx), np.abs(dy)), cosine)
    return best, height, cosine


def laser_ranges(world: World, x, y, yaw, angles: np.ndarray, z: float = 0.2,
                 range_max: float = 10.0, grazing: float = 0.0) -> np.ndarray:
    """A planar scan from a laser at (x, y, yaw) and height ``z``: inf where nothing is hit. ``x``,
    ``y``, ``yaw`` may be arrays, one pose per beam (a laser that moves while it scans).
    ``grazing`` (degrees): a beam meeting a surface at less than this from it returns nothing
    (inf), as a real lidar's too weak echo does."""
    a = np.asarray(yaw) + angles
    d, h, cosine = _hits(world, np.asarray(x), np.asarray(y), np.stack([np.cos(a), np.sin(a)], 1))
    d = np.where((h >= z) & (d <= range_max) & (cosine >= math.sin(math.radians(grazing))), d, np.inf)
    return d.astype(np.float32)


def cloud_points(world: World, x: float, y: float, yaw: float, z: float, azimuths: np.ndarray,
                 elevations: np.ndarray, range_max: float = 30.0) -> np.ndarray:
    """A 3D lidar's returns (rings x azimuths, 3) in the sensor frame, ground at z = 0 included;
    NaN where a beam hits nothing (as organised clouds have)."""
    el, az = np.meshgrid(elevations, azimuths, indexing="ij")
    a = (yaw + az).ravel()
    dh, h = _hit_distances(world, x, y, np.stack([np.cos(a), np.sin(a)], 1))
    tan = np.tan(el.ravel())
    z_hit = z + dh * tan
    side = np.isfinite(dh) & (z_hit >= 0) & (z_hit <= h)
    ground = np.where(tan < 0, z / np.maximum(-tan, 1e-9), np.inf)
    horiz = np.where(side & (dh < ground), dh, np.where(ground < np.inf, ground, np.inf))
    rng = horiz / np.cos(el.ravel())
    horiz = np.where(rng <= range_max, horiz, np.nan)
    pts = np.stack([horiz * np.cos(az.ravel()), horiz * np.sin(az.ravel()), horiz * tan], 1)
    return pts.reshape(len(elevations), len(azimuths), 3)


def stamp(t: float) -> dict[str, int]:
    ns = int(round(t * 1e9))
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def quat(yaw: float) -> dict[str, float]:
    return {"z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}


def pose_msg(x: float, y: float, yaw: float) -> dict[str, Any]:
    return {"position": {"x": x, "y": y}, "orientation": quat(yaw)}


class BagOut:
    """Write messages given as dicts: ``BagOut(path, ros1=False)``, then ``write(topic, type, t, values)``."""

    def __init__(self, path: Path, ros1: bool = False):
        self.ros1 = ros1
        self.ts = _typestore(ros1)
        if ros1:
            from rosbags.rosbag1 import Writer
            self.writer = Writer(path)
        else:
            from rosbags.rosbag2 import StoragePlugin, Writer
            self.writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
        self.conns: dict[str, Any] = {}

    def __enter__(self) -> "BagOut":
        self.writer.open()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.writer.close()

    def write(self, topic: str, msgtype: str, t: float, values: dict[str, Any]) -> None:
        if topic not in self.conns:
            self.conns[topic] = self.writer.add_connection(topic, msgtype, typestore=self.ts)
        msg = build(self.ts, msgtype, values)
        raw = self.ts.serialize_ros1(msg, msgtype) if self.ros1 else self.ts.serialize_cdr(msg, msgtype)
        self.writer.write(self.conns[topic], int(round(t * 1e9)), raw)


def loop_drive(n: int = 300, dt: float = 0.1, radius: float = 2.0) -> np.ndarray:
    """(n, 4) t, x, y, yaw of a robot driving a circle of ``radius`` counter-clockwise from (radius, 0)."""
    t = np.arange(n) * dt
    a = t * (2 * math.pi / (n * dt))
    return np.stack([t, radius * np.cos(a), radius * np.sin(a), a + math.pi / 2], 1)


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Planar poses (..., 3): ``a`` then ``b`` expressed in ``a``."""
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([a[..., 0] + c * b[..., 0] - s * b[..., 1], a[..., 1] + s * b[..., 0] + c * b[..., 1],
                     a[..., 2] + b[..., 2]], axis=-1)


def invert(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([-(c * a[..., 0] + s * a[..., 1]), s * a[..., 0] - c * a[..., 1], -a[..., 2]], axis=-1)


LASER = (0.1, 0.0, 0.2)           # x, y, z of the laser on base_link (turned 0)
SCAN_ANGLES = np.radians(np.arange(-180.0, 180.0, 1.0))


@dataclass(frozen=True)
class ScanTiming:
    """How a generated laser takes its scans, as real drivers do: beams ``increment`` seconds apart
    (the truth), the fields it writes (``time_increment``, ``scan_time``: what a driver declares,
    which may be 0 or wrong), its stamp (``stamp``: "start" = the first beam, "end" = the last),
    the stamp moved by ``stamp_error`` (a driver's clock off), and the bag receiving each scan
    ``latency`` seconds after its last beam."""
    increment: float = 0.0
    time_increment: float | None = None     # None: write ``increment``
    scan_time: float | None = None          # None: beams x increment
    stamp: str = "start"
    stamp_error: float = 0.0
    latency: float = 0.002

    def beam_times(self, t: float) -> np.ndarray:
        return t + self.increment * np.arange(len(SCAN_ANGLES))

    def fields(self) -> tuple[float, float]:
        ti = self.increment if self.time_increment is None else self.time_increment
        st = self.increment * len(SCAN_ANGLES) if self.scan_time is None else self.scan_time
        return float(ti), float(st)


def pose_at(truth: np.ndarray, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The truth's x, y, yaw interpolated at times ``t`` (yaw unwrapped)."""
    return (np.interp(t, truth[:, 0], truth[:, 1]), np.interp(t, truth[:, 0], truth[:, 2]),
            np.interp(t, truth[:, 0], np.unwrap(truth[:, 3])))


def robot_bag(path: Path, world: World, truth: np.ndarray, *, drift: np.ndarray | None = None,
              ros1: bool = False, scans: bool = True, cloud: dict | None = None, extra=None,
              tf_map: bool = True, laser: tuple[float, float, float] = LASER, pitch: float = 0.0,
              world_at=None, timing: ScanTiming | None = None, odom_keep=None, scan_at=None,
              angles: np.ndarray = SCAN_ANGLES, range_noise: float = 0.0, range_max: float = 10.0,
              grazing: float = 0.0) -> Path:
    """A bag of a robot driving ``truth`` ((n, 4) t, x, y, yaw in the map frame) through ``world``.

    ``drift`` ((n, 3) the map -> odom transform at each time): the odometry is the truth seen
    through it (odom = drift^-1 . truth) and the exact correction is published on /tf. Scans at
    every pose from a laser at ``laser`` (x, y, z on /tf_static); ``cloud``: keyword arguments of
    ``cloud_points`` (azimuths, elevations) plus "layout" ("velodyne" or "ouster") for a
    PointCloud2 on /points instead of (or beside) the scans; ``pitch`` (degrees, positive nose
    down) tilts the lidar, on /tf_static and in its points; ``world_at(t)`` gives the world at time t
    (something that moves) instead of ``world``. ``extra(bag)`` writes more. ``timing``: the laser
    takes each beam at its own time (the scan starts at the pose's time; each beam is cast from the
    truth interpolated at its time) and stamps and declares it as ``ScanTiming`` says; without it,
    every beam at once, as a simulator does. ``odom_keep(t)`` False: that odometry message is not
    written (a gap). ``angles``: the beams of an untimed scan (default 360, one a degree);
    ``range_noise``: the standard deviation (m) of Gaussian noise on every return (seeded: the
    same bag each time), as a real laser has; ``grazing`` (degrees): beams meeting a surface at
    a shallower angle return nothing (laser_ranges).
    """
    noise = np.random.default_rng(0)
    p = math.radians(pitch)
    tilt = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])  # sensor -> level
    drift = np.zeros((len(truth), 3)) if drift is None else drift
    odom = compose(invert(drift), truth[:, 1:4])
    with BagOut(path, ros1=ros1) as bag:
        t0 = truth[0, 0]
        bag.write("/tf_static", "tf2_msgs/msg/TFMessage", t0, {"transforms": [
            {"header": {"stamp": stamp(t0), "frame_id": "base_link"}, "child_frame_id": "laser",
             "transform": {"translation": dict(zip("xyz", laser)),
                           "rotation": {"y": math.sin(p / 2), "w": math.cos(p / 2)}}}]})
        for (t, x, y, yaw), (ox, oy, oyaw), (dx, dy, dyaw) in zip(truth, odom, drift):
            if odom_keep is None or odom_keep(t):
                bag.write("/odom", "nav_msgs/msg/Odometry", t, {
                    "header": {"stamp": stamp(t), "frame_id": "odom"}, "child_frame_id": "base_link",
                    "pose": {"pose": pose_msg(ox, oy, oyaw)}})
            if tf_map:
                bag.write("/tf", "tf2_msgs/msg/TFMessage", t, {"transforms": [
                    {"header": {"stamp": stamp(t), "frame_id": "map"}, "child_frame_id": "odom",
                     "transform": {"translation": {"x": dx, "y": dy}, "rotation": quat(dyaw)}}]})
            lx, ly = x + math.cos(yaw) * laser[0], y + math.sin(yaw) * laser[0]
            world = world_at(t) if world_at is not None else world
            if scan_at is not None and not scan_at(t):
                pass
            elif scans and timing is None:
                ranges = laser_ranges(world, lx, ly, yaw, angles, z=laser[2], range_max=range_max, grazing=grazing)
                if range_noise:
                    ranges = (ranges + noise.normal(0.0, range_noise, len(ranges))).astype(np.float32)
                bag.write("/scan", "sensor_msgs/msg/LaserScan", t, {
                    "header": {"stamp": stamp(t), "frame_id": "laser"}, "angle_min": float(angles[0]),
                    "angle_max": float(angles[-1]), "angle_increment": float(angles[1] - angles[0]),
                    "range_min": 0.05, "range_max": range_max, "ranges": ranges})
            elif scans:
                bt = timing.beam_times(t)
                bx, by, byaw = pose_at(truth, bt)
                ranges = laser_ranges(world, bx + np.cos(byaw) * laser[0], by + np.sin(byaw) * laser[0], byaw,
                                      SCAN_ANGLES, z=laser[2])
                ti, st = timing.fields()
                stamped = (bt[0] if timing.stamp == "start" else bt[-1]) + timing.stamp_error   # first / last in the array
                bag.write("/scan", "sensor_msgs/msg/LaserScan", bt.max() + timing.latency, {
                    "header": {"stamp": stamp(stamped), "frame_id": "laser"}, "angle_min": float(SCAN_ANGLES[0]),
                    "angle_max": float(SCAN_ANGLES[-1]), "angle_increment": float(SCAN_ANGLES[1] - SCAN_ANGLES[0]),
                    "time_increment": ti, "scan_time": st, "range_min": 0.05, "range_max": 10.0,
                    "ranges": ranges})
            if cloud is not None:
                args = {k: v for k, v in cloud.items() if k != "layout"}
                pts = cloud_points(world, lx, ly, yaw, laser[2], **args) @ tilt   # level -> the sensor's axes
                bag.write("/points", "sensor_msgs/msg/PointCloud2", t,
                          cloud_msg(pts, t, cloud.get("layout", "velodyne")))
        if extra is not None:
            extra(bag)
    return path


def cloud_msg(pts: np.ndarray, t: float, layout: str) -> dict[str, Any]:
    """A PointCloud2 of ``pts`` (rings, columns, 3) in a driver's field layout ("hesai": see below): "velodyne"
    (x, y, z, intensity float32, ring uint16, time float32; unorganised, NaN points dropped,
    point_step 22) or "ouster" (organised rings x columns with NaN points kept, x, y, z, pad,
    intensity, t uint32, reflectivity uint16, ring uint16, ambient uint16, range uint32; step 48)."""
    if layout == "velodyne":
        flat = pts.reshape(-1, 3)
        ring = np.repeat(np.arange(pts.shape[0]), pts.shape[1])
        ok = np.isfinite(flat).all(axis=1)
        flat, ring = flat[ok], ring[ok]
        dt = np.dtype({"names": ["x", "y", "z", "intensity", "ring", "time"],
                       "formats": ["<f4", "<f4", "<f4", "<f4", "<u2", "<f4"], "offsets": [0, 4, 8, 12, 16, 18],
                       "itemsize": 22})
        arr = np.zeros(len(flat), dt)
        arr["x"], arr["y"], arr["z"], arr["ring"] = flat[:, 0], flat[:, 1], flat[:, 2], ring
        fields = [("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("intensity", 12, 7), ("ring", 16, 4), ("time", 18, 7)]
        height, width = 1, len(flat)
    elif layout == "hesai":
        # organised rings x columns, NaN kept, x, y, z, intensity float32, timestamp float64, ring
        # uint16, 32-byte points, each row padded by 16 bytes (row_step > width * point_step)
        dt = np.dtype({"names": ["x", "y", "z", "intensity", "timestamp", "ring"],
                       "formats": ["<f4", "<f4", "<f4", "<f4", "<f8", "<u2"], "offsets": [0, 4, 8, 12, 16, 24],
                       "itemsize": 32})
        arr = np.zeros(pts.shape[:2], dt)
        arr["x"], arr["y"], arr["z"] = pts[..., 0], pts[..., 1], pts[..., 2]
        rows = np.zeros((pts.shape[0], pts.shape[1] * 32 + 16), np.uint8)
        rows[:, :pts.shape[1] * 32] = np.frombuffer(arr.tobytes(), np.uint8).reshape(pts.shape[0], -1)
        fields = [("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("intensity", 12, 7), ("timestamp", 16, 8), ("ring", 24, 4)]
        return {"header": {"stamp": stamp(t), "frame_id": "laser"}, "height": pts.shape[0], "width": pts.shape[1],
                "fields": [{"name": n, "offset": o, "datatype": d, "count": 1} for n, o, d in fields],
                "is_bigendian": False, "point_step": 32, "row_step": rows.shape[1], "data": rows.reshape(-1),
                "is_dense": False}
    else:
        dt = np.dtype({"names": ["x", "y", "z", "intensity", "t", "reflectivity", "ring", "ambient", "range"],
                       "formats": ["<f4", "<f4", "<f4", "<f4", "<u4", "<u2", "<u2", "<u2", "<u4"],
                       "offsets": [0, 4, 8, 16, 20, 24, 26, 28, 32], "itemsize": 48})
        arr = np.zeros(pts.shape[:2], dt)
        arr["x"], arr["y"], arr["z"] = pts[..., 0], pts[..., 1], pts[..., 2]
        fields = [("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("intensity", 16, 7), ("t", 20, 6),
                  ("reflectivity", 24, 4), ("ring", 26, 4), ("ambient", 28, 4), ("range", 32, 6)]
        height, width = pts.shape[0], pts.shape[1]
    return {"header": {"stamp": stamp(t), "frame_id": "laser"}, "height": height, "width": width,
            "fields": [{"name": n, "offset": o, "datatype": d, "count": 1} for n, o, d in fields],
            "is_bigendian": False, "point_step": dt.itemsize, "row_step": dt.itemsize * width,
            "data": np.frombuffer(arr.tobytes(), np.uint8), "is_dense": layout == "velodyne"}


def register_goal_types(ts: Any, ros1: bool) -> None:
    """Add the move_base (ROS 1) or Nav2 NavigateToPose (ROS 2) goal types to a typestore."""
    from rosbags.typesys import get_types_from_msg

    if ros1:
        defs = {"actionlib_msgs/msg/GoalID": "time stamp\nstring id",
                "move_base_msgs/msg/MoveBaseGoal": "geometry_msgs/PoseStamped target_pose",
                "move_base_msgs/msg/MoveBaseActionGoal": "std_msgs/Header header\nactionlib_msgs/GoalID goal_id\n"
                                                         "move_base_msgs/MoveBaseGoal goal"}
    else:
        goal = "geometry_msgs/PoseStamped pose\nstring behavior_tree"
        # rosbags writes nested definitions only from msg/ names: the recorded event's parts go there
        defs = {"nav2_msgs/action/NavigateToPose_Goal": goal, "nav2_msgs/msg/NavigateToPose_Goal": goal,
                "service_msgs/msg/ServiceEventInfo": "uint8 event_type\nbuiltin_interfaces/Time stamp\n"
                                                     "char[16] client_gid\nint64 sequence_number",
                "nav2_msgs/msg/NavigateToPose_SendGoal_Request": "unique_identifier_msgs/UUID goal_id\n"
                                                                    "nav2_msgs/NavigateToPose_Goal goal",
                "nav2_msgs/msg/NavigateToPose_SendGoal_Response": "bool accepted\nbuiltin_interfaces/Time stamp",
                "nav2_msgs/msg/NavigateToPose_SendGoal_Event": (
                    "service_msgs/ServiceEventInfo info\nnav2_msgs/NavigateToPose_SendGoal_Request[<=1] request\n"
                    "nav2_msgs/NavigateToPose_SendGoal_Response[<=1] response")}
    for name, text in defs.items():
        if name not in ts.types:
            ts.register(get_types_from_msg(text, name))


def stop_drive(speed: float = 0.5, stop_x: float = 2.0, duration: float = 8.0, dt: float = 0.1) -> np.ndarray:
    """(n, 4) t, x, y, yaw: along +x at ``speed`` until ``stop_x``, then standing still."""
    t = np.arange(0.0, duration + 1e-9, dt)
    return np.stack([t, np.minimum(speed * t, stop_x), 0 * t, 0 * t], 1)


ROOM = World(pillars=[(0.3, 0.2, 0.2, 1.0), (-1.5, -0.5, 0.25, 1.0), (2.5, -1.8, 0.15, 1.0)],
             boxes=[(0.0, 3.5, 9.0, 0.1, 0.0, 1.0), (0.0, -3.5, 9.0, 0.1, 0.0, 1.0),
                    (4.5, 0.0, 0.1, 7.0, 0.0, 1.0), (-4.5, 0.0, 0.1, 7.0, 0.0, 1.0),
                    (-2.5, 2.0, 1.0, 0.6, 30.0, 1.0), (3.0, 1.5, 0.6, 0.6, 0.0, 1.0)])


def drift_bag(folder: Path, drift_deg: float = 6.0, drift_m: float = 0.35, seconds: float = 46.0,
              angles: np.ndarray | None = None) -> tuple[Path, np.ndarray]:
    """A robot driving a 2 m circle and a bit in a furnished room; its odometry drifts linearly to
    ``drift_deg`` and ``drift_m`` by the end; no map -> odom in the bag; a 720-beam laser (or
    ``angles``) with 1 cm of range noise. Returns the bag and the truth (issue 37)."""
    t = np.arange(0.0, seconds, 0.1)
    a = t * (2 * math.pi / 40.0)
    truth = np.stack([t, 2.0 * np.cos(a) - 0.5, 1.6 * np.sin(a), a + math.pi / 2], 1)
    f = t / t[-1]
    drift = np.stack([drift_m * f * 0.8, -drift_m * f * 0.6, np.radians(drift_deg) * f], 1)
    path = robot_bag(folder / "drift", ROOM, truth, drift=drift, tf_map=False,
                     angles=np.radians(np.arange(-180.0, 180.0, 0.5)) if angles is None else angles,
                     range_noise=0.01, range_max=12.0)
    return path, truth
