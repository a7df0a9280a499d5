"""The pictures of issue 37: seeds against the raw returns they were made from, before and after.

    python benchmarks/make_bag_walls_picture.py --before OTHER_CHECKOUT [--out-dir docs/pictures]

``from-bag-walls-corridor.png``: a generated 46 s corridor drive (720 beams, a wall 0.6 m beside the
path, no echo from beams meeting a surface at less than 10 degrees) imported by OTHER_CHECKOUT (before
issue 37) and by this checkout. ``from-bag-walls-drift.png``: a generated drive round a furnished room
whose odometry drifts to 6 degrees and 0.35 m, no map -> odom. Each seed is drawn over the bag's
returns placed with the poses that seed used (this checkout's drift seed: --scan-match auto), the beams
along which the seed blocks space the lidar saw free in red, the truth dashed.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "ros"))
sys.path.insert(0, str(ROOT / "benchmarks"))
from make_bag_fit_picture import draw, fit_of, import_with  # noqa: E402

CORRIDOR_BEAMS = np.radians(np.arange(-180.0, 180.0, 0.5))


def corridor_bag(folder: Path):
    from ros_synthetic import World, robot_bag

    world = World(boxes=[(5.0, 0.7, 14.0, 0.1, 0.0, 1.0), (5.0, -1.6, 14.0, 0.1, 0.0, 1.0)])
    t = np.arange(0.0, 46.0, 0.1)
    drive = np.stack([t, 8.3 * t / 46.0, 0 * t, 0 * t], 1)
    return robot_bag(folder / "corridor", world, drive, tf_map=False, angles=CORRIDOR_BEAMS, range_noise=0.01,
                     range_max=12.0, grazing=10.0), world


def main() -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from ros_synthetic import ROOM, drift_bag

    from pytest_navscenario.scenario.loader import load_scenario

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, required=True, metavar="OTHER_CHECKOUT",
                    help="a checkout of the version before issue 37 (e.g. git archive ef414ed | tar -x -C /tmp/before)")
    ap.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "pictures")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="walls_picture."))
    cases = [("corridor", *corridor_bag(tmp)), ("drift", drift_bag(tmp)[0], ROOM)]
    for name, bag, truth in cases:
        panels = []
        for label, checkout, match in (("before (the version before issue 37)", args.before, "off"),
                                       ("after", ROOT, "auto" if name == "drift" else "off")):
            out = tmp / f"{name}-{match}.yaml"
            import_with(checkout, bag, out, [] if checkout == args.before else ["--scan-match", match])
            scenario = load_scenario(out)
            panels.append((label, scenario, *fit_of(scenario, bag, match)))
        fig, axes = plt.subplots(2 if name == "corridor" else 1, 1 if name == "corridor" else 2,
                                 figsize=(11, 6.5) if name == "corridor" else (11, 6.0))
        for ax, (label, scenario, fit, returns, spots, path) in zip(axes, panels):
            draw(ax, scenario, returns, spots, path, fit, label, truth)
            ax.set_title(ax.get_title() + f"; start clearance {fit.start_seed:.2f} m (first scan "
                         f"{fit.start_scan:.2f} m)", fontsize=9)
            print(f"{name} {label}: {len(scenario.obstacles)} obstacles; " + fit.lines()[0])
        lim = [min(a.get_xlim()[0] for a in axes), max(a.get_xlim()[1] for a in axes),
               min(a.get_ylim()[0] for a in axes), max(a.get_ylim()[1] for a in axes)]
        for ax in axes:
            ax.set_xlim(lim[:2])
            ax.set_ylim(lim[2:])
        fig.tight_layout()
        target = args.out_dir / f"from-bag-walls-{name}.png"
        fig.savefig(target, dpi=90)
        plt.close(fig)
        print(f"wrote {target}")


if __name__ == "__main__":
    main()
