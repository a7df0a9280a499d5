"""Heightfield ray casting: a 16 x 360 lidar scan (5760 rays) against rough ground of 32, 64, 128
and 256 cells a side, by MuJoCo's mj_multiRay, by the lidars' own cast (``cast_grids``: compiled,
sim/ground/hfield_march.py, where numba imports) and by its vectorised numpy form
(sim/ground/hfield_rays.py), alternated A B C in one run; CPU time (time.process_time) medians and
the median of the per-pair ratios mj_multiRay / own, and the largest distance difference between
mj_multiRay and the own cast; ``numpy=`` whether the numpy cast gave the own cast's distances bit for bit.

    python benchmarks/bench_hfield_rays.py [--repeats 15] [--size 16] [--height 0.6]

The patch is ``--size`` metres a side with bumps of 0.3 m every ``size / cells * 8`` metres (rough
ground of 8 samples a wavelength), the lidar ``--height`` metres above the floor at its centre,
rings from -15 to +15 degrees. ``differ``: rays whose distances differ by more than 1e-5 m (or
that only one of the two hits). A lidar standing exactly on a vertex of the grid sends its 45-degree
beams exactly along the cells' diagonals, the edge shared by their two triangles, and there MuJoCo's
triangle test can miss both (measured: one beam of 5760 over the 128-cell field, whose ray MuJoCo
sees pass under the surface to its base); the lidar here stands off the vertices.
"""
from __future__ import annotations

import argparse
import statistics
import time

import mujoco
import numpy as np

from pytest_navscenario.scenario.ground.heightmap import height_grid
from pytest_navscenario.scenario.terrain import Rough
from pytest_navscenario.sim.ground.heightfield import add_heightfield, placed_grid
from pytest_navscenario.sim.ground import hfield_rays
from pytest_navscenario.sim.ground.hfield_rays import cast_grids


def fan(rings: int = 16, beams: int = 360) -> np.ndarray:
    elev = np.radians(np.linspace(-15.0, 15.0, rings))
    azim = np.radians(np.arange(beams) * 360.0 / beams)
    e, a = np.meshgrid(elev, azim, indexing="ij")
    return np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], -1).reshape(-1, 3)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--size", type=float, default=16.0)
    ap.add_argument("--height", type=float, default=0.6)
    args = ap.parse_args()
    dirs = fan()
    flat = np.ascontiguousarray(dirs).ravel()
    n = len(dirs)
    pnt = np.array([0.013, 0.007, args.height])   # off the grid's vertices: see "edge" below
    print(f"{'cells':>6} {'mj_multiRay ms':>15} {'own cast ms':>12} {'ratio':>7} {'numpy ms':>9} {'hits':>6} "
          f"{'max diff m':>11} {'differ':>6} numpy=")
    for cells in (32, 64, 128, 256):
        element = Rough("field", 0.0, 0.0, length=args.size, width=args.size, amplitude=0.3,
                        wavelength=args.size / cells * 8, seed=1)
        grid = height_grid(element)
        spec = mujoco.MjSpec()
        add_heightfield(spec, element, grid)
        model = spec.compile()
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        placed = [placed_grid(element, grid)]
        geom, dist = np.empty(n, dtype=np.int32), np.empty(n)
        own = cast_grids(placed, pnt, dirs, 30.0)                       # warm-up (grid prepared)
        mujoco.mj_multiRay(model, data, pnt, flat, None, 1, -1, geom, dist, None, n, 30.0)
        a_times, b_times, c_times, ratios = [], [], [], []
        prepared = hfield_rays._prepared(placed[0])
        for _ in range(args.repeats):
            t0 = time.process_time()
            mujoco.mj_multiRay(model, data, pnt, flat, None, 1, -1, geom, dist, None, n, 30.0)
            a = time.process_time() - t0
            t0 = time.process_time()
            own = cast_grids(placed, pnt, dirs, 30.0)
            b = time.process_time() - t0
            vec = np.full(n, np.inf)
            t0 = time.process_time()
            hfield_rays._cast_one(prepared, pnt, dirs, 30.0, vec)
            c_times.append(time.process_time() - t0)
            a_times.append(a)
            b_times.append(b)
            ratios.append(a / b if b > 0 else float("nan"))
        ref = np.where(geom >= 0, dist, np.inf)
        same = np.isfinite(ref) & np.isfinite(own)
        gap = np.abs(ref[same] - own[same])
        differ = int((np.isfinite(ref) != np.isfinite(own)).sum() + (gap > 1e-5).sum())
        diff = float(gap.max()) if same.any() else 0.0
        print(f"{grid.heights.shape[1] - 1:>6} {statistics.median(a_times) * 1e3:>15.2f} "
              f"{statistics.median(b_times) * 1e3:>12.2f} {statistics.median(ratios):>6.1f}x "
              f"{statistics.median(c_times) * 1e3:>9.2f} {int(np.isfinite(own).sum()):>6} {diff:>11.1e} {differ:>6} "
              f"{np.array_equal(vec, own)}")


if __name__ == "__main__":
    main()
