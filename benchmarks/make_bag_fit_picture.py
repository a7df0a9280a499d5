"""The docs' before/after pictures of issue 24: a seed against the scans it was made from.

    python benchmarks/make_bag_fit_picture.py --before OTHER_CHECKOUT [--out-dir docs/pictures]

``from-bag-fit-tb3.png``: the TurtleBot3 bag (tests/data) imported by OTHER_CHECKOUT (before issue 24)
and by this checkout, each seed drawn over a sample of the bag's own returns, with the beams along
which the seed blocks space the lidar saw free (red) and the fit figure of each (fit.py, the same
measure for both). ``from-bag-fit-turning.png``: a generated bag of a robot turning 1.5 rad/s while
its 10 Hz lidar scans, imported by both; the truth dashed.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "ros"))
TB3 = ROOT / "tests" / "data" / "fuse_turtlebot3.bag"


def import_with(checkout: Path, bag: Path, out: Path, options: list[str] = ()) -> None:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = str(checkout)
    subprocess.run([sys.executable, "-c", "import sys; from pytest_navscenario.cli import main; "
                    "sys.exit(main(sys.argv[1:]))", "from-bag", str(bag), "-o", str(out), "--force", "--no-plot", *options],
                   env=env, check=True, stdout=subprocess.DEVNULL, cwd=checkout)   # cwd: -c puts it first on the path


def fit_of(scenario, bag: Path, match: str = "off"):
    """The fit figure of ``scenario`` against ``bag``'s scans, and what to draw: the sampled returns
    and the points where the seed blocks a beam; the poses corrected by ``match`` (``--scan-match``)
    as the import that made the seed did."""
    from pytest_navscenario.ros.bag_import.fit import _segments, cast, fit_figure
    from pytest_navscenario.ros.bag_import.mount import choose_mount
    from pytest_navscenario.ros.bag_import.projection import beam_rays, map_scans, settle_timing
    from pytest_navscenario.ros.bag_import.reading import read_bag
    from pytest_navscenario.ros.bag_import.scan_match import correct_drift

    data = read_bag(bag)
    mount, _ = choose_mount(data, None)
    settle_timing(data, mount)
    correct_drift(data, mount, match)
    smap = map_scans(data, mount)
    fig = fit_figure(scenario, data, mount, smap.sample, smap.first)
    r = beam_rays(data, smap.sample, mount)
    use = r.valid | r.none
    ox, oy, ang = r.ox[use].astype(float), r.oy[use].astype(float), r.angle[use]
    seed, cosine = cast(ox, oy, np.cos(ang), np.sin(ang), *_segments(scenario.obstacles))
    real = np.where(r.valid[use], r.range[use].astype(float), np.inf)
    seen = np.where(np.isfinite(real), real, data.range_max)
    with np.errstate(invalid="ignore"):
        blocked = (seed < seen) & ((seen - seed) * cosine > 0.1)
    hits = np.isfinite(real)
    returns = np.stack([ox[hits] + real[hits] * np.cos(ang[hits]), oy[hits] + real[hits] * np.sin(ang[hits])], 1)
    spots = np.stack([ox[blocked] + seed[blocked] * np.cos(ang[blocked]),
                      oy[blocked] + seed[blocked] * np.sin(ang[blocked])], 1)
    return fig, returns, spots, data.odom[:, 1:3]


def draw(ax, scenario, returns, spots, path, fig, title, truth=None) -> None:
    from matplotlib.patches import Circle, Polygon

    from pytest_navscenario.scenario.geometry import obstacle_polygon

    ax.plot(returns[::3, 0], returns[::3, 1], ",", color="0.55")
    if truth is not None:
        for x, y, r, _ in truth.pillars:
            ax.add_patch(Circle((x, y), r, fill=False, ls="--", color="tab:green"))
        for x, y, ln, w, yaw, _ in truth.boxes:
            c, s = np.cos(np.radians(yaw)), np.sin(np.radians(yaw))
            corners = [(-ln / 2, -w / 2), (ln / 2, -w / 2), (ln / 2, w / 2), (-ln / 2, w / 2)]
            ax.add_patch(Polygon([(x + c * u - s * v, y + s * u + c * v) for u, v in corners], fill=False, ls="--",
                                 color="tab:green"))
    for o in scenario.obstacles:
        ax.add_patch(Polygon(np.asarray(obstacle_polygon(o).exterior.coords), facecolor="0.85", edgecolor="k", lw=0.8))
    ax.plot(path[:, 0], path[:, 1], "-", color="tab:blue", lw=0.8)
    ax.plot(spots[:, 0], spots[:, 1], ".", color="tab:red", ms=2)
    ax.set_aspect("equal")
    ax.set_title(f"{title}: {len(scenario.obstacles)} obstacles\nblocks {fig.blocked:.1%} of the beams, misses "
                 f"{fig.missed:.1%} of the returns,\nmedian range error {fig.median_error:.2f} m", fontsize=9)


def main() -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from pytest_navscenario.scenario.loader import load_scenario

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, required=True, metavar="OTHER_CHECKOUT",
                    help="a checkout of the version before issue 24 (e.g. git worktree add /tmp/before b54e7f1)")
    ap.add_argument("--out-dir", type=Path, default=ROOT / "docs" / "pictures")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="fit_picture."))

    from ros_synthetic import ScanTiming, robot_bag
    from test_import_scans import INC, ROOM, SPIN, _drive

    cases = [("tb3", TB3, None),
             ("turning", robot_bag(tmp / "turning", ROOM, _drive(SPIN), timing=ScanTiming(increment=INC), tf_map=False),
              ROOM)]
    for name, bag, truth in cases:
        panels = []
        for label, checkout in (("before (the version before issue 24)", args.before), ("after", ROOT)):
            out = tmp / f"{name}-{'before' if checkout == args.before else 'after'}.yaml"
            import_with(checkout, bag, out)
            scenario = load_scenario(out)
            panels.append((label, scenario, *fit_of(scenario, bag)))
        fig, axes = plt.subplots(1, 2, figsize=(11, 6.0))
        for ax, (label, scenario, fit, returns, spots, path) in zip(axes, panels):
            draw(ax, scenario, returns, spots, path, fit, label, truth)
            print(f"{name} {label}: {len(scenario.obstacles)} obstacles; " + fit.lines()[0])
        lim = [min(a.get_xlim()[0] for a in axes), max(a.get_xlim()[1] for a in axes),
               min(a.get_ylim()[0] for a in axes), max(a.get_ylim()[1] for a in axes)]
        for ax in axes:
            ax.set_xlim(lim[:2])
            ax.set_ylim(lim[2:])
        fig.tight_layout(rect=(0, 0, 1, 0.96))
        target = args.out_dir / f"from-bag-fit-{name}.png"
        fig.savefig(target, dpi=90)
        plt.close(fig)
        print(f"wrote {target}")


if __name__ == "__main__":
    main()
