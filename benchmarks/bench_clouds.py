"""``from-bag`` on a long 3D-lidar bag: time and memory of importing point clouds.

    python benchmarks/bench_clouds.py [--minutes 10] [--points 30000] [--rate 10]

Writes a rosbag2 MCAP bag of a robot driving laps through a room of pillars and boxes for
``--minutes`` (odometry at 20 Hz with map -> odom on /tf, a 16-ring lidar at ``--rate`` Hz with
``--points`` points per cloud in the Velodyne layout, ground included), then imports it with
``scenario_from_bag`` in a fresh process and prints its CPU time, wall time and peak resident
memory; then the same for a bag of half the length, to show that memory does not grow with the
bag's length (clouds are streamed one at a time). Budget (issue 17): 10 minutes at 10 Hz with
30 000 points per cloud in under 30 s. The bag is deleted afterwards unless ``--keep``.
"""
from __future__ import annotations

import argparse
import json
import math
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "ros"))

from ros_synthetic import BagOut, World, cloud_points, pose_msg, quat, stamp  # noqa: E402

WORLD = World(pillars=[(2.0, 0.0, 0.3, 1.0), (-2.0, 1.0, 0.25, 1.0), (0.5, 3.5, 0.2, 1.0)],
              boxes=[(0.0, -4.0, 10.0, 0.2, 0.0, 2.0), (0.0, 5.0, 10.0, 0.2, 0.0, 2.0),
                     (-5.0, 0.5, 0.2, 9.0, 0.0, 2.0), (5.0, 0.5, 0.2, 9.0, 0.0, 2.0),
                     (-1.0, -2.0, 0.6, 0.6, 30.0, 0.2)])


def write_bag(path: Path, seconds: float, points: int, rate: float) -> None:
    rings = 16
    az = np.radians(np.linspace(-180.0, 180.0, points // rings, endpoint=False))
    el = np.radians(np.linspace(-15.0, 15.0, rings))
    dt = np.dtype({"names": ["x", "y", "z", "intensity"], "formats": ["<f4"] * 4, "offsets": [0, 4, 8, 12],
                   "itemsize": 16})
    fields = [{"name": n, "offset": 4 * i, "datatype": 7, "count": 1} for i, n in enumerate(["x", "y", "z", "intensity"])]
    lap = 40.0   # s per lap of an ellipse through the room
    with BagOut(path) as bag:
        bag.write("/tf_static", "tf2_msgs/msg/TFMessage", 0.0, {"transforms": [{
            "header": {"stamp": stamp(0.0), "frame_id": "base_link"}, "child_frame_id": "lidar",
            "transform": {"translation": {"z": 0.5}, "rotation": {"w": 1.0}}}]})
        for i in range(int(seconds * 20)):
            t = i / 20
            a = 2 * math.pi * t / lap
            x, y, yaw = 3.2 * math.cos(a), 1.8 * math.sin(a) + 0.5, a + math.pi / 2
            bag.write("/odom", "nav_msgs/msg/Odometry", t, {"header": {"stamp": stamp(t), "frame_id": "odom"},
                      "child_frame_id": "base_link", "pose": {"pose": pose_msg(x, y, yaw)}})
            bag.write("/tf", "tf2_msgs/msg/TFMessage", t, {"transforms": [{
                "header": {"stamp": stamp(t), "frame_id": "map"}, "child_frame_id": "odom",
                "transform": {"rotation": quat(0.0)}}]})
            if i % round(20 / rate) == 0:
                pts = cloud_points(WORLD, x, y, yaw, 0.5, az, el).reshape(-1, 3)
                arr = np.zeros(len(pts), dt)
                arr["x"], arr["y"], arr["z"] = pts[:, 0], pts[:, 1], pts[:, 2]
                bag.write("/points", "sensor_msgs/msg/PointCloud2", t, {
                    "header": {"stamp": stamp(t), "frame_id": "lidar"}, "height": 1, "width": len(pts),
                    "fields": fields, "is_bigendian": False, "point_step": 16, "row_step": 16 * len(pts),
                    "data": np.frombuffer(arr.tobytes(), np.uint8), "is_dense": False})


CHILD = """
import json, resource, sys, time
from pytest_navscenario.ros.bag_import import scenario_from_bag
c0, w0 = time.process_time(), time.perf_counter()
seed = scenario_from_bag(sys.argv[1])
cpu, wall = time.process_time() - c0, time.perf_counter() - w0
print(json.dumps({"cpu": cpu, "wall": wall, "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "obstacles": len(seed.scenario.obstacles), "notes": seed.notes}))
"""


def measure(path: Path) -> dict:
    out = subprocess.run([sys.executable, "-c", CHILD, str(path)], check=True, capture_output=True, text=True,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--points", type=int, default=30000)
    ap.add_argument("--rate", type=float, default=10.0)
    ap.add_argument("--keep", action="store_true", help="keep the bags (printed paths)")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_clouds."))
    try:
        for minutes in (args.minutes / 2, args.minutes):
            path = tmp / f"lidar_{minutes:g}min"
            w0 = time.perf_counter()
            write_bag(path, minutes * 60, args.points, args.rate)
            size = sum(f.stat().st_size for f in path.iterdir()) / 1e9
            r = measure(path)
            print(f"{minutes:g} min, {int(minutes * 60 * args.rate)} clouds of {args.points} points ({size:.2f} GB, "
                  f"written in {time.perf_counter() - w0:.0f} s): import {r['cpu']:.1f} s CPU, {r['wall']:.1f} s wall, "
                  f"peak memory {r['rss_mb']:.0f} MB, {r['obstacles']} obstacles")
            print("    " + next(n for n in r["notes"] if "point clouds from" in n))
    finally:
        if args.keep:
            print(f"bags kept in {tmp}")
        else:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
