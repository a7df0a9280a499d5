"""A long 2D-lidar bag: ``navscenario from-bag`` on 1, 5 and 10 minutes of a robot patrolling an
office floor, each in a fresh process: its CPU time and its peak memory (memory must not grow with
the bag's length: the scans are streamed, only the grid of the floor is kept).

    python benchmarks/bench_long_bag.py [--minutes 1 5 10] [--keep DIR]

The bags are generated from a known world (tests/ros/ros_synthetic.py): a 10 Hz rotating lidar
(360 beams in 0.1 s, each beam at its own time, ``time_increment`` declared), odometry at 20 Hz,
the robot driving laps of a rectangular corridor around a block of offices at 0.6 m/s and turning
at its corners, a few pillars and cabinets along the walls. The issue-24 target: the 10-minute bag
in under 10 s of CPU, with memory that does not grow with its length. CPU and peak memory (the
largest resident set) are the operating system's accounting of the finished child.
"""
from __future__ import annotations

import argparse
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

from ros_synthetic import ScanTiming, World, robot_bag  # noqa: E402

# a 24 x 14 m floor: outer walls, a 16 x 6 m block of offices in the middle, a 4 m wide corridor round it
FLOOR = World(
    pillars=[(-6.0, 5.4, 0.2, 1.0), (6.0, -5.4, 0.2, 1.0), (10.4, 0.0, 0.25, 1.0), (-10.4, 2.0, 0.25, 1.0)],
    boxes=[(0.0, 7.0, 24.0, 0.2, 0.0, 1.0), (0.0, -7.0, 24.0, 0.2, 0.0, 1.0),
           (12.0, 0.0, 0.2, 14.0, 0.0, 1.0), (-12.0, 0.0, 0.2, 14.0, 0.0, 1.0),
           (0.0, 0.0, 16.0, 6.0, 0.0, 1.0),
           (2.0, 6.5, 1.2, 0.6, 0.0, 1.0), (-3.0, -6.5, 1.2, 0.6, 0.0, 1.0)])
SPEED, DT = 0.6, 0.05


def patrol(minutes: float) -> np.ndarray:
    """(n, 4) t, x, y, yaw at 20 Hz: laps of the corridor's centre line (a 20 x 10 m rectangle),
    turning in place 90 degrees at each corner (1 s)."""
    corners = [(-10.0, -5.0), (10.0, -5.0), (10.0, 5.0), (-10.0, 5.0)]
    rows, t = [], 0.0
    end = minutes * 60.0
    x, y = corners[0]
    yaw = 0.0
    i = 0
    while t < end:
        nx, ny = corners[(i + 1) % 4]
        length = math.hypot(nx - x, ny - y)
        steps = int(length / (SPEED * DT))
        for k in range(steps):
            rows.append((t, x + (nx - x) * k / steps, y + (ny - y) * k / steps, yaw))
            t += DT
        x, y = nx, ny
        for k in range(int(1.0 / DT)):          # turn in place at the corner
            rows.append((t, x, y, yaw + (math.pi / 2) * k / int(1.0 / DT)))
            t += DT
        yaw += math.pi / 2
        i += 1
    arr = np.array(rows)
    return arr[arr[:, 0] < end]


def write(folder: Path, minutes: float) -> Path:
    drive = patrol(minutes)
    scan_rows = drive[::2]                       # scans at 10 Hz, odometry at 20 Hz
    keep = set(np.round(scan_rows[:, 0], 6))
    path = folder / f"patrol_{minutes:g}min.bag"
    robot_bag(path, FLOOR, drive, ros1=True, tf_map=False, timing=ScanTiming(increment=0.1 / 360),
              scan_at=lambda t: round(t, 6) in keep)
    return path


RUN = ("import resource, sys, time\n"
       "from pytest_navscenario.cli import main\n"
       "rc = main(sys.argv[1:])\n"
       "r = resource.getrusage(resource.RUSAGE_SELF)\n"
       "print(f'MEASURED {r.ru_utime + r.ru_stime} {r.ru_maxrss}', file=sys.stderr)\n"
       "sys.exit(rc)\n")


def measure(bag: Path, out: Path) -> tuple[float, float, float]:
    """(CPU s, wall s, peak MB) of one from-bag run in a fresh process, as that process counts them."""
    cmd = [sys.executable, "-c", RUN, "from-bag", str(bag), "-o", str(out), "--force", "--no-plot"]
    w0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - w0
    if proc.returncode:
        raise SystemExit(f"from-bag failed on {bag}:\n{proc.stderr}")
    cpu, rss = next(line.split()[1:] for line in proc.stderr.splitlines() if line.startswith("MEASURED"))
    return float(cpu), wall, float(rss) / 1024.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, nargs="+", default=[1.0, 5.0, 10.0])
    ap.add_argument("--keep", type=Path, default=None, help="generate the bags into DIR (and keep them)")
    args = ap.parse_args()
    folder = args.keep or Path(tempfile.mkdtemp(prefix="bench_long_bag."))
    folder.mkdir(parents=True, exist_ok=True)
    try:
        for minutes in sorted(args.minutes):     # peak memory of children only grows: shortest first
            bag = folder / f"patrol_{minutes:g}min.bag"
            if not bag.exists():
                t0 = time.perf_counter()
                bag = write(folder, minutes)
                print(f"generated {bag.name}: {bag.stat().st_size / 1e6:.1f} MB in {time.perf_counter() - t0:.0f} s")
            cpu, wall, peak = measure(bag, folder / "seed.yaml")
            fit = (folder / "seed.fit.json").read_text() if (folder / "seed.fit.json").exists() else ""
            import json
            f = json.loads(fit) if fit else {}
            print(f"{minutes:g} min ({bag.stat().st_size / 1e6:.0f} MB, {int(minutes * 600)} scans): {cpu:.2f} s CPU, "
                  f"{wall:.2f} s wall, peak memory {peak:.0f} MB; fit: blocked {f.get('blocked', 0):.1%}, missed "
                  f"{f.get('missed', 0):.1%}, median error {f.get('median_error', 0):.3f} m")
    finally:
        if args.keep is None:
            shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
