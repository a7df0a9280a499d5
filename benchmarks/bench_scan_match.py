"""Issue 37: odometry drift corrected by scan matching, the own correlative matcher against KISS-ICP,
on a generated bag with a known drift (the truth is known, so the corrected poses are compared with
it). Run: python benchmarks/bench_scan_match.py [--drift-deg 6] [--drift-m 0.35]

Prints, per method: the poses' error against the truth (median, max; m and deg) and the seconds the
matching took; and the same for the odometry uncorrected."""
from __future__ import annotations

import argparse
import math
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "ros"))
from ros_synthetic import drift_bag  # noqa: E402

from pytest_navscenario.ros.bag_import.mount import choose_mount  # noqa: E402
from pytest_navscenario.ros.bag_import.reading import read_bag  # noqa: E402
from pytest_navscenario.ros.bag_import.scan_match import correct_drift  # noqa: E402

def pose_errors(odom: np.ndarray, truth: np.ndarray) -> tuple[float, float, float, float]:
    tx = np.interp(odom[:, 0], truth[:, 0], truth[:, 1])
    ty = np.interp(odom[:, 0], truth[:, 0], truth[:, 2])
    tyaw = np.interp(odom[:, 0], truth[:, 0], np.unwrap(truth[:, 3]))
    d = np.hypot(odom[:, 1] - tx, odom[:, 2] - ty)
    a = np.degrees(np.abs(np.remainder(odom[:, 3] - tyaw + math.pi, 2 * math.pi) - math.pi))
    return float(np.median(d)), float(d.max()), float(np.median(a)), float(a.max())


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--drift-deg", type=float, default=6.0)
    p.add_argument("--drift-m", type=float, default=0.35)
    args = p.parse_args()
    folder = Path(tempfile.mkdtemp())
    try:
        path, truth = drift_bag(folder, args.drift_deg, args.drift_m)
        for method in ("off", "own", "kiss-icp"):
            data = read_bag(path)
            mount, _ = choose_mount(data, None)
            t0 = time.perf_counter()
            note = correct_drift(data, mount, method)
            took = time.perf_counter() - t0
            med, worst, amed, aworst = pose_errors(data.odom, truth)
            print(f"{method:9s} pose error median {med:.3f} m max {worst:.3f} m, heading median {amed:.2f} max "
                  f"{aworst:.2f} deg; {took:.2f} s" + (f"\n          {note}" if note else ""))
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
