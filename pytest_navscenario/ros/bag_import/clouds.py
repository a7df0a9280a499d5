"""3D lidar point clouds (``sensor_msgs/PointCloud2``) into the obstacle grid, streamed: one
cloud at a time from a second pass over the bag, so memory does not grow with its length.

Any driver's field layout that has float ``x``, ``y``, ``z`` fields (Velodyne, Ouster, Hesai,
Livox...; organised or not, padded rows, either byte order) is read; NaN points (no return) are
dropped. Points are moved into the robot's base frame with the sensor's 3D mounting from
/tf_static (else assumed level at the base, with ``--laser-pose`` x, y, yaw if given), the
ground is found per cloud (the lowest dense layer near the robot) and only the band the robot
can hit is kept: from ``clearance`` above the ground to the robot's height. Each cell remembers
the highest point seen, so a low obstacle comes through with its height.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .projection import Grid, GridAccumulator, poses_at
from .reading import BagData, BagImportError

FLOAT_TYPES = {7: "f4", 8: "f8"}   # sensor_msgs/PointField FLOAT32, FLOAT64


@dataclass(frozen=True)
class CloudSettings:
    robot_height: float = 1.0     # m above the ground: higher points cannot be hit
    clearance: float = 0.05       # m above the ground: lower points are the ground
    near: float = 0.0             # m, horizontal: closer points are the robot itself (set to its radius)
    ground_ring: tuple[float, float] = (0.5, 8.0)   # m, horizontal ring where the ground is looked for
    # a cloud is used when the robot moved or turned this much since the last one used, or this much time passed
    keyframe: tuple[float, float, float] = (0.1, 5.0, 1.0)   # m, degrees, s


def cloud_xyz(msg: Any, where: str) -> tuple[np.ndarray, int]:
    """The finite points (k, 3) of a PointCloud2 and how many NaN / inf points were dropped."""
    fields = {f.name: f for f in msg.fields}
    missing = [n for n in "xyz" if n not in fields]
    if missing:
        raise BagImportError(f"{where}: the point cloud has no {', '.join(missing)} field(s) (fields: "
                             f"{', '.join(fields) or 'none'}); a cloud needs float x, y, z to be read")
    bad = [n for n in "xyz" if fields[n].datatype not in FLOAT_TYPES]
    if bad:
        raise BagImportError(f"{where}: point cloud field(s) {', '.join(bad)} are not float32/float64 "
                             f"(datatype {fields[bad[0]].datatype}); cannot read them as metres")
    order = ">" if msg.is_bigendian else "<"
    step, width, height = int(msg.point_step), int(msg.width), max(int(msg.height), 1)
    _check_layout(msg, fields, step, width, height, where)
    dt = np.dtype({"names": list("xyz"), "formats": [order + FLOAT_TYPES[fields[n].datatype] for n in "xyz"],
                   "offsets": [int(fields[n].offset) for n in "xyz"], "itemsize": step})
    raw = np.frombuffer(memoryview(msg.data), np.uint8)
    row = int(msg.row_step) or step * width
    if row != step * width:  # padded rows: cut each row to its points
        raw = raw[:row * height].reshape(height, row)[:, :step * width].reshape(-1)
    n = min(width * height, len(raw) // step)
    arr = np.frombuffer(raw[:n * step].tobytes() if not raw.flags.c_contiguous else raw[:n * step], dt)
    pts = np.stack([arr["x"], arr["y"], arr["z"]], axis=1).astype(np.float32)
    ok = np.isfinite(pts.sum(axis=1))
    if ok.all():
        return pts, 0
    return pts[ok], int(n - ok.sum())


def _check_layout(msg: Any, fields: dict, step: int, width: int, height: int, where: str) -> None:
    """A cloud whose header does not describe its data is refused with what does not fit (reading
    it anyway would give points made of the wrong bytes)."""
    if step <= 0:
        raise BagImportError(f"{where}: the point cloud's point_step is {step}: each point must take at least "
                             f"the bytes of its x, y, z; the cloud is not readable")
    for name in "xyz":
        f = fields[name]
        size = np.dtype(FLOAT_TYPES[f.datatype]).itemsize
        if int(f.offset) < 0 or int(f.offset) + size > step:
            raise BagImportError(f"{where}: point cloud field {name} at offset {int(f.offset)} ({size} bytes) lies "
                                 f"outside a point of point_step {step} bytes; the cloud's header is wrong")
    row = int(msg.row_step) or step * width
    if row < step * width:
        raise BagImportError(f"{where}: the point cloud's row_step {row} is shorter than width {width} x point_step "
                             f"{step} = {step * width} bytes; the cloud's header is wrong")
    have = len(msg.data)
    need = row * (height - 1) + step * width
    if have < need:
        per = f"; its data holds {have / (width * height):.4g} bytes a point" if width * height else ""
        raise BagImportError(f"{where}: the point cloud's data is {have} bytes, but its header (width {width} x height "
                             f"{height}, point_step {step}, row_step {row}) needs {need}{per}: point_step or the "
                             f"size is wrong")


def _quat_matrix(q: tuple[float, ...]) -> np.ndarray:
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def sensor_mount(data: BagData, laser_pose: tuple[float, float, float] | None) -> tuple[np.ndarray, str]:
    """The 4x4 transform from the cloud's frame to the base frame, and where it came from."""
    if laser_pose is not None:
        m = np.eye(4)
        yaw = math.radians(laser_pose[2])
        m[:3, :3] = _quat_matrix((0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)))
        m[:2, 3] = laser_pose[:2]
        return m, "from --laser-pose (level; the ground is found from the points)"
    frame, m = data.cloud_frame, np.eye(4)
    for _ in range(32):
        if frame == data.base_frame:
            return m, "from /tf_static"
        if frame not in data.static_tf3:
            break
        parent, (x, y, z, *q) = data.static_tf3[frame]
        step = np.eye(4)
        step[:3, :3], step[:3, 3] = _quat_matrix(tuple(q)), (x, y, z)
        m, frame = step @ m, parent
    if data.cloud_frame == data.base_frame:
        return np.eye(4), "the base frame itself"
    return np.eye(4), (f"assumed level at the base's origin: no transform {data.base_frame} -> {data.cloud_frame} "
                       f"on /tf_static; pass --laser-pose=X,Y,YAW to place it")


def ground_height(pts: np.ndarray, s: CloudSettings) -> float | None:
    """The ground's height in the base frame under a cloud: the lowest 5 cm layer near the robot
    that holds at least 2 % of the points there (None when there are too few points)."""
    sub = pts[::4] if len(pts) > 4000 else pts   # a quarter of a dense cloud finds the ground as well
    r2 = sub[:, 0] * sub[:, 0] + sub[:, 1] * sub[:, 1]
    z = sub[(r2 >= s.ground_ring[0] ** 2) & (r2 <= s.ground_ring[1] ** 2), 2]
    if len(z) < 50:
        return None
    lo = np.floor(z.min() / 0.05)
    counts = np.bincount((np.floor(z / 0.05) - lo).astype(np.int64))
    dense = np.nonzero(counts >= max(10, 0.02 * len(z)))[0]
    k = int(dense[0]) if len(dense) else 0
    layer = z[(z >= (lo + k) * 0.05) & (z < (lo + k + 1) * 0.05)]
    return float(np.median(layer))


class CloudGrid:
    """Clouds into a grid one at a time (see the module docstring); counts what it left out. The
    sensor's mounting is looked up at the first cloud (its frame is in the cloud's header)."""

    def __init__(self, data: BagData, laser_pose: tuple[float, float, float] | None, s: CloudSettings, res: float):
        self.data, self.laser_pose, self.s = data, laser_pose, s
        self.mount: np.ndarray | None = None
        self.how = ""
        self.acc = GridAccumulator(res)
        self.used = self.outside = self.nan = self.no_ground = self.same_place = 0
        self.last_used: np.ndarray | None = None   # t, x, y, yaw of the last cloud used
        self.nearest: list[tuple[float, float]] = []  # t, horizontal distance to the nearest point in the band
        self.grounds: list[float] = []
        self.last_ground: float | None = None
        from .ground import GroundMap
        self.ground_map = GroundMap(max(res, 0.1))   # the ground itself, kept as terrain (ground.py)
        self.layout: tuple[int, int] | None = None   # the first cloud's rows and columns (an organised one: rings, beams)

    def add(self, msg: Any, t: float) -> None:
        od = self.data.odom
        if not od[0, 0] <= t <= od[-1, 0]:
            self.outside += 1
            return
        x, y, yaw = poses_at(self.data, np.array([t]))[0]
        if self.last_used is not None:
            lt, lx, ly, lyaw = self.last_used
            move, turn, wait = self.s.keyframe
            if math.hypot(x - lx, y - ly) < move and math.degrees(abs(yaw - lyaw)) < turn and t - lt < wait:
                self.same_place += 1   # the robot has not moved: this cloud sees what the last one saw
                return
        if self.mount is None:
            self.data.cloud_frame = msg.header.frame_id.lstrip("/")
            self.mount, self.how = sensor_mount(self.data, self.laser_pose)
        pts, nan = cloud_xyz(msg, f"{self.data.path}: {self.data.cloud_topic}")
        self.nan += nan
        if self.layout is None:
            self.layout = (max(int(msg.height), 1), int(msg.width))
        pts = pts @ self.mount[:3, :3].T.astype(np.float32) + self.mount[:3, 3].astype(np.float32)
        z, roll, pitch = _up_at(self.data, t)
        if roll or pitch:      # levelled: on a tilted robot the ground is the ground, not a slope
            pts = (pts @ _rp_matrix(roll, pitch).T).astype(np.float32)
        self.ground_map.add(_levelled_to_world(pts, x, y, yaw, z))
        ground = ground_height(pts, self.s)
        ground = self.last_ground if ground is None else ground
        if ground is None:
            self.no_ground += 1
            return
        self.last_ground = ground
        self.grounds.append(ground)
        h = pts[:, 2] - ground
        keep = (h >= self.s.clearance) & (h <= self.s.robot_height) & \
            (pts[:, 0] * pts[:, 0] + pts[:, 1] * pts[:, 1] > self.s.near * self.s.near)
        c, sn = math.cos(yaw), math.sin(yaw)
        px, py = pts[keep, 0], pts[keep, 1]
        if len(px):
            self.nearest.append((t, float(np.sqrt((px * px + py * py).min()))))
        world = np.stack([x + c * px - sn * py, y + sn * px + c * py], 1)
        mx, my = self.mount[0, 3], self.mount[1, 3]
        origin = np.array([x + c * mx - sn * my, y + sn * mx + c * my])
        self.acc.add(world, np.broadcast_to(origin, world.shape), h[keep])
        self.used += 1
        self.last_used = np.array([t, x, y, yaw])

    def notes(self) -> list[str]:
        d, s = self.data, self.s
        m = self.mount if self.mount is not None else np.eye(4)
        notes = [f"point cloud frame {d.cloud_frame} at x={m[0, 3]:.3f} y={m[1, 3]:.3f} z={m[2, 3]:.3f} in "
                 f"{d.base_frame}, {self.how or 'no cloud in the window'}",
                 f"{self.used} point clouds from {d.cloud_topic}, {self.acc.returns} points between {s.clearance} and "
                 f"{s.robot_height} m above the ground"
                 + (f"; ground found at z={np.median(self.grounds):.2f} m in {d.base_frame}" if self.grounds else "")]
        if self.same_place:
            notes.append(f"{self.same_place} cloud(s) taken where the robot had moved < {s.keyframe[0]} m and turned < "
                         f"{s.keyframe[1]:g} deg within {s.keyframe[2]:g} s of the last one used: skipped")
        if self.nan:
            notes.append(f"{self.nan} NaN points (no return) dropped")
        if self.no_ground:
            notes.append(f"warning: {self.no_ground} cloud(s) skipped: too few points near the robot to find the ground")
        return notes


def _up_at(data: BagData, t: float) -> tuple[float, float, float]:
    """The robot's height, roll and pitch at ``t`` (``odom_up``; 0 for planar odometry)."""
    up = data.odom_up
    if not len(up):
        return 0.0, 0.0, 0.0
    return tuple(float(np.interp(t, up[:, 0], up[:, k])) for k in (1, 2, 3))   # type: ignore[return-value]


def _rp_matrix(roll: float, pitch: float) -> np.ndarray:
    """Level from base: the rotation by pitch (about y) after roll (about x)."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    return np.array([[cp, sp * sr, sp * cr], [0.0, cr, -sr], [-sp, cp * sr, cp * cr]])


def _levelled_to_world(pts: np.ndarray, x: float, y: float, yaw: float, z: float) -> np.ndarray:
    """Levelled base-frame points (k, 3) into the world frame: turned by yaw, moved to (x, y, z)."""
    c, s = math.cos(yaw), math.sin(yaw)
    p = np.asarray(pts, dtype=float)
    return np.column_stack([x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1], z + p[:, 2]])


@dataclass
class CloudResult:
    grid: Grid
    notes: list[str]
    nearest: np.ndarray   # (k, 2) time, horizontal distance from the base to the nearest point in the band
    how: str              # where the sensor's mounting came from
    ground: Any = None    # ground.GroundMap: the ground the clouds saw
    mount: Any = None     # the sensor's 4 x 4 mounting in the base frame
    layout: tuple[int, int] | None = None   # the first cloud's rows, columns


def grid_clouds(data: BagData, laser_pose: tuple[float, float, float] | None, s: CloudSettings,
                res: float) -> CloudResult:
    """Stream the bag's clouds on ``data.cloud_topic`` into a grid (one cloud in memory at a time)."""
    from .reading import bag_pass

    g = CloudGrid(data, laser_pose, s, res)
    with bag_pass(data) as reader:
        conns = [c for c in reader.connections if c.topic == data.cloud_topic]
        for conn, bag_ns, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            ns = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec) or bag_ns
            g.add(msg, (ns - data.origin_ns) * 1e-9)
    return CloudResult(g.acc.grid(), g.notes(), np.array(g.nearest, dtype=float).reshape(-1, 2),
                       g.how or "no cloud in the window", g.ground_map, g.mount, g.layout)
