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
    best = np.full(len(dirs), np.inf)
    height = np.zeros(len(dirs))
    for cx, cy, r, h in world.pillars:
        fx, fy = ox - cx, oy - cy
        b = dirs[:, 0] * fx + dirs[:, 1] * fy
        c = fx * fx + fy * fy - r * r
        disc = b * b - c
        t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
        t = np.where(t > 1e-6, t, np.inf)
        closer = t < best
        best, height = np.where(closer, t, best), np.where(closer, h, height)
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
        best, height = np.where(closer, t, best), np.where(closer, h, height)
    return best, height


def laser_ranges(world: World, x: float, y: float, yaw: float, angles: np.ndarray, z: float = 0.2,
                 range_max: float = 10.0) -> np.ndarray:
    """A planar scan from a laser at (x, y, yaw) and height ``z``: inf where nothing is hit."""
    a = yaw + angles
    d, h = _hit_distances(world, x, y, np.stack([np.cos(a), np.sin(a)], 1))
    d = np.where((h >= z) & (d <= range_max), d, np.inf)
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
