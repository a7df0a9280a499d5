"""The docs' before/after picture of ``from-bag``: one bag imported in the odometry frame and in
the map frame.

    python benchmarks/make_bag_frames_picture.py [--out docs/pictures/from-bag-frames.png]

The bag is generated from a known world (tests/ros/ros_synthetic.py): a robot drives a 30 s
circle among six pillars while its odometry drifts (2 cm/s, 0.4 deg/s) and slips 0.5 m once; the
exact ``map -> odom`` correction is on /tf, as AMCL publishes it. Left: ``--frame odom`` (before
issue 17: every scan placed with the drifted pose); right: the default, the map frame. The true
pillars are dashed.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "ros"))

from ros_synthetic import loop_drive, robot_bag  # noqa: E402
from test_import_map_frame import WORLD, _drift  # noqa: E402


def main() -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Polygon

    from pytest_navscenario.ros.bag_import import scenario_from_bag
    from pytest_navscenario.scenario.geometry import obstacle_polygon

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "docs" / "pictures" / "from-bag-frames.png"))
    args = ap.parse_args()
    truth = loop_drive(n=300, dt=0.1, radius=1.8)
    with tempfile.TemporaryDirectory() as tmp:
        bag = robot_bag(Path(tmp) / "drift", WORLD, truth, drift=_drift(truth))
        seeds = [("--frame odom (before): odometry frame", scenario_from_bag(bag, frame="odom")),
                 ("default: map frame (map -> odom on /tf)", scenario_from_bag(bag))]
    fig, axes = plt.subplots(1, 2, figsize=(10, 5), constrained_layout=True)
    for ax, (title, seed) in zip(axes, seeds):
        for o in seed.scenario.obstacles:
            xy = np.asarray(obstacle_polygon(o).exterior.coords)
            ax.add_patch(Polygon(xy, closed=True, facecolor="#888", edgecolor="#333", alpha=0.8))
        for x, y, r, _ in WORLD.pillars:
            ax.add_patch(Circle((x, y), r, fill=False, linestyle="--", edgecolor="tab:green", linewidth=1.5))
        ax.plot(seed.path[:, 1], seed.path[:, 2], color="tab:blue", linewidth=1.2, label="recorded path")
        ax.plot(truth[:, 1], truth[:, 2], color="tab:green", linewidth=0.8, linestyle=":", label="true path")
        n = len(seed.scenario.obstacles)
        ax.set_title(f"{title}\n{n} obstacles fitted (truth: {len(WORLD.pillars)} pillars, dashed)", fontsize=10)
        ax.set_aspect("equal")
        ax.set_xlim(-4.2, 4.2)
        ax.set_ylim(-4.2, 4.2)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="lower left", fontsize=8)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=90)
    print(f"wrote {args.out}: odometry frame {len(seeds[0][1].scenario.obstacles)} obstacles, "
          f"map frame {len(seeds[1][1].scenario.obstacles)}")


if __name__ == "__main__":
    main()
