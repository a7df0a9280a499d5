"""The seed's world frame: the map frame when the bag says where the odometry frame sits in it,
else the odometry frame.

Odometry drifts; a robot that localises publishes the correction ``map -> odom`` on ``/tf``
(AMCL, SLAM Toolbox, Cartographer) or its pose in the map on a topic (``/amcl_pose``, ``/pose``,
``/tracked_pose``). Each odometry pose is moved into the map frame with the latest correction
at or before its time (held, never interpolated: interpolating across a relocalisation jump
would smear the scans between the two corrections along the jump). Jumps are reported.
"""
from __future__ import annotations

import math

import numpy as np

from .reading import BagData, BagImportError

FRAMES = ("auto", "map", "odom")
JUMP_M, JUMP_DEG = 0.25, 10.0   # a change of map -> odom larger than this between two corrections is a jump
POSE_TOPICS = ("/amcl_pose", "/pose", "/tracked_pose", "/localization_pose")


def compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Planar poses (..., 3) x, y, yaw: ``a`` then ``b`` expressed in ``a``."""
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([a[..., 0] + c * b[..., 0] - s * b[..., 1], a[..., 1] + s * b[..., 0] + c * b[..., 1],
                     a[..., 2] + b[..., 2]], axis=-1)


def invert(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([-(c * a[..., 0] + s * a[..., 1]), s * a[..., 0] - c * a[..., 1], -a[..., 2]], axis=-1)


def odom_at(data: BagData, t: np.ndarray, full: np.ndarray | None = None) -> np.ndarray:
    """Odometry poses (k, 3) interpolated at times ``t`` (yaw unwrapped)."""
    od = data.odom if full is None else full
    return np.stack([np.interp(t, od[:, 0], od[:, 1]), np.interp(t, od[:, 0], od[:, 2]),
                     np.interp(t, od[:, 0], np.unwrap(od[:, 3]))], axis=1)


def corrections(data: BagData, full_odom: np.ndarray, map_frame: str = "map",
                pose_topic: str | None = None) -> tuple[np.ndarray | None, str, list[str]]:
    """(k, 4) t, x, y, yaw of ``map -> odom`` corrections in time order, where they came from,
    and warnings (a broken chain, a pose topic in another frame). None when the bag has none."""
    warnings: list[str] = []
    odom = data.odom_frame
    if pose_topic is None:
        rows = [(t, x, y, yaw) for t, parent, child, x, y, yaw in data.frame_tf if parent == map_frame and child == odom]
        if rows:
            return np.array(rows, dtype=float), f"{map_frame} -> {odom} on /tf ({len(rows)} transforms)", warnings
        others = sorted({child for _, parent, child, *_ in data.frame_tf if parent == map_frame})
        if others:
            warnings.append(f"/tf has {map_frame} -> {', '.join(others)} but no {map_frame} -> {odom}: the chain to "
                            f"the odometry frame is broken")
        candidates = [k for k, v in data.poses.items() if v and v[0][1] == map_frame]
        pose_topic = next((k for k in POSE_TOPICS if k in candidates), candidates[0] if len(candidates) == 1 else None)
        if pose_topic is None:
            return None, "", warnings
    elif pose_topic not in data.poses:
        raise BagImportError(f"{data.path}: no pose messages on {pose_topic!r} (pose topics: "
                             f"{', '.join(sorted(data.poses)) or 'none'}); fix --pose-topic")
    rows = [r for r in data.poses[pose_topic] if r[1] == map_frame]
    if len(rows) < len(data.poses[pose_topic]):
        warnings.append(f"{len(data.poses[pose_topic]) - len(rows)} pose(s) on {pose_topic} not in frame "
                        f"{map_frame} were left out")
    if not rows:
        return None, "", warnings
    t = np.array([r[0] for r in rows])
    inside = (t >= full_odom[0, 0]) & (t <= full_odom[-1, 0])
    if not inside.any():
        warnings.append(f"{pose_topic}: no pose within the odometry's time span")
        return None, "", warnings
    pose = np.array([r[2:5] for r in rows], dtype=float)[inside]
    corr = compose(pose, invert(odom_at(data, t[inside], full_odom)))
    return np.c_[t[inside], corr], f"the robot's pose in {map_frame} on {pose_topic} ({int(inside.sum())} poses)", warnings


def held(corr: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The correction (k, 3) in force at each time: the latest at or before it (the first before it)."""
    idx = np.clip(np.searchsorted(corr[:, 0], t, side="right") - 1, 0, len(corr) - 1)
    return corr[idx, 1:4]


def jumps(corr: np.ndarray) -> list[tuple[float, float, float]]:
    """(t, metres, degrees) of each relocalisation jump in the corrections."""
    if len(corr) < 2:
        return []
    d = np.hypot(*np.diff(corr[:, 1:3], axis=0).T)
    a = np.degrees(np.abs((np.diff(corr[:, 3]) + math.pi) % (2 * math.pi) - math.pi))
    idx = np.nonzero((d > JUMP_M) | (a > JUMP_DEG))[0]
    return [(float(corr[i + 1, 0]), float(d[i]), float(a[i])) for i in idx]


def to_world_frame(data: BagData, frame: str = "auto", map_frame: str = "map",
                   pose_topic: str | None = None, full_odom: np.ndarray | None = None) -> np.ndarray | None:
    """Move ``data.odom`` into the map frame when the bag has the correction (``frame`` "auto" or
    "map"; "map" without a correction is an error); note the source, jumps and warnings.
    Returns the corrections (None in the odometry frame)."""
    if frame not in FRAMES:
        raise BagImportError(f"--frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    full = data.odom if full_odom is None else full_odom
    if frame == "odom":
        data.notes.append(f"world frame: {data.odom_frame} (odometry; --frame odom), drift not corrected")
        return None
    corr, source, warnings = corrections(data, full, map_frame, pose_topic)
    data.notes.extend(f"warning: {w}" for w in warnings)
    if corr is None:
        if frame == "map":
            raise BagImportError(f"{data.path}: --frame map, but the bag has no {map_frame} -> {data.odom_frame} on "
                                 f"/tf and no pose topic in {map_frame}" + (f" ({warnings[0]})" if warnings else ""))
        data.notes.append(f"world frame: {data.odom_frame} (odometry): no {map_frame} -> {data.odom_frame} on /tf "
                          f"and no pose topic in {map_frame}, so the bag does not correct the odometry's drift"
                          + (" (--scan-match auto corrects it by scan matching)" if data.scan_topic else ""))
        return None
    od = data.odom
    world = compose(held(corr, od[:, 0]), od[:, 1:4])
    data.odom = np.c_[od[:, 0], world]
    data.frame = map_frame
    data.notes.append(f"world frame: {map_frame}, odometry corrected with {source}")
    if corr[0, 0] > od[0, 0] + 1e-6:
        data.notes.append(f"the first correction is at t={corr[0, 0]:.1f} s: it is used before it too")
    sensed = "scans" if data.scan_topic else "clouds" if data.cloud_topic else None
    for t, d, a in jumps(corr):
        data.notes.append(f"relocalisation jump at t={t:.1f} s: {map_frame} -> {data.odom_frame} moved {d:.2f} m, "
                          f"{a:.0f} deg" + (f"; {sensed} on each side are placed with their own correction"
                                            if sensed else ""))
    return corr
