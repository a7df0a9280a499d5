"""The compiled heightfield ray cast (sim/ground/hfield_march.py) gives the distances a brute force
over every triangle of the closed solid gives (the surface's triangles, the side walls down to the
base, the base's bottom), within 1e-9 m, and the vectorised numpy cast's, bit for bit: for random
rays from above, below, beside and inside the field's box, rays along the cells' edges and
diagonals and through their corners, level rays, rays parallel to the grid's rows, and vertical
rays; turned, raised and lowered grids; and a lidar's 16 x 360 scan over a 256-cell field."""
import math

import numpy as np
import pytest

from pytest_navscenario.scenario.ground.heightmap import HeightGrid, height_grid
from pytest_navscenario.scenario.terrain import Heightfield, Lidar3D, Rough
from pytest_navscenario.sim.ground import hfield_march, hfield_rays
from pytest_navscenario.sim.ground.heightfield import hfield_size, placed_grid
from pytest_navscenario.sim.lidar3d import sensor_directions

TOLERANCE = 1e-9     # m, against the brute force


def _solid_triangles(placed):
    """Every triangle of the grid's closed solid in the world frame, (m, 3, 3): the surface (each
    cell split from (c, r) to (c + 1, r + 1), as MuJoCo), the four side walls from the edge
    profile down to the base, and the base's bottom."""
    grid = placed.grid
    h = grid.heights
    rows, cols = h.shape
    dx, dy = grid.cell
    size, _ = hfield_size(grid, placed.z)
    low = float(h.min()) - size[3]
    x = np.arange(cols) * dx - size[0]
    y = np.arange(rows) * dy - size[1]
    X, Y = np.meshgrid(x, y)
    P = np.stack([X, Y, h], -1)
    a, b, c, d = P[:-1, :-1], P[:-1, 1:], P[1:, :-1], P[1:, 1:]
    tris = [np.stack([a, b, d], -2).reshape(-1, 3, 3), np.stack([a, d, c], -2).reshape(-1, 3, 3)]
    for edge in (P[0, :], P[-1, :], P[:, 0], P[:, -1]):
        top0, top1 = edge[:-1], edge[1:]
        bot0, bot1 = top0.copy(), top1.copy()
        bot0[:, 2] = low
        bot1[:, 2] = low
        tris += [np.stack([bot0, bot1, top1], 1), np.stack([bot0, top1, top0], 1)]
    corners = np.array([[x[0], y[0], low], [x[-1], y[0], low], [x[-1], y[-1], low], [x[0], y[-1], low]])
    tris.append(np.array([[corners[0], corners[1], corners[2]], [corners[0], corners[2], corners[3]]]))
    tris = np.concatenate(tris)
    cs, sn = math.cos(placed.yaw), math.sin(placed.yaw)
    world = tris.copy()
    world[..., 0] = cs * tris[..., 0] - sn * tris[..., 1] + placed.x
    world[..., 1] = sn * tris[..., 0] + cs * tris[..., 1] + placed.y
    world[..., 2] = tris[..., 2] + placed.z
    return world


def _brute_force(placed, pnts, dirs, rmax):
    """The nearest triangle of the solid along each ray within rmax (Moller-Trumbore), inf if none."""
    tris = _solid_triangles(placed)
    v0, e1, e2 = tris[:, 0], tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]
    out = np.full(len(dirs), np.inf)
    for i, (p, d) in enumerate(zip(pnts, dirs)):
        pv = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, pv)
        ok = np.abs(det) > 1e-15
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        tv = p - v0
        u = np.einsum("ij,ij->i", tv, pv) * inv
        qv = np.cross(tv, e1)
        v = (qv @ d) * inv
        t = np.einsum("ij,ij->i", e2, qv) * inv
        hit = ok & (u >= -1e-12) & (v >= -1e-12) & (u + v <= 1 + 1e-12) & (t >= 0) & (t <= rmax)
        if hit.any():
            out[i] = t[hit].min()
    return out


def _compiled(placed, pnts, dirs, rmax):
    out = np.full(len(dirs), np.inf)
    hfield_march.cast(hfield_rays._prepared(placed), pnts, dirs, rmax, out)
    return out


def _vectorised(placed, pnts, dirs, rmax):
    out = np.full(len(dirs), np.inf)
    hfield_rays._cast_one(hfield_rays._prepared(placed), pnts, dirs, rmax, out)
    return out


def _edge_rays(placed, rng, n):
    """Rays that meet the grid's plan exactly along cell edges, diagonals and through corners: from
    an inner grid vertex, along a grid line or a diagonal (in the grid's frame), coming down. (Not
    along the footprint's own edge: such a ray runs in the plane of a side wall, tangent to the
    solid, where either answer is right; the casts say it misses the wall.)"""
    grid = placed.grid
    rows, cols = grid.heights.shape
    dx, dy = grid.cell
    size, _ = hfield_size(grid, placed.z)
    cs, sn = math.cos(placed.yaw), math.sin(placed.yaw)
    c = rng.integers(1, cols - 1, n)
    r = rng.integers(1, rows - 1, n)
    lx, ly = c * dx - size[0], r * dy - size[1]
    plan = np.array([(1, 0), (-1, 0), (0, 1), (0, -1), (dx, dy), (-dx, -dy), (dx, -dy)], dtype=float)
    step = plan[rng.integers(0, len(plan), n)]
    step /= np.linalg.norm(step, axis=1)[:, None]
    back = rng.uniform(0.5, 3.0, n)                # start this far back along the line, above
    sx, sy = lx - step[:, 0] * back, ly - step[:, 1] * back
    top = placed.z + float(grid.heights.max())
    pnts = np.column_stack([cs * sx - sn * sy + placed.x, sn * sx + cs * sy + placed.y,
                            np.full(n, top + 0.3)])
    drop = rng.uniform(0.05, 0.6, n)
    dirs = np.column_stack([cs * step[:, 0] - sn * step[:, 1], sn * step[:, 0] + cs * step[:, 1], -drop])
    return pnts, dirs / np.linalg.norm(dirs, axis=1)[:, None]


def _random_rays(placed, rng, n):
    """Rays from above, beside, below and inside the grid's box, with many shallow, level,
    row-parallel and vertical ones; none starts inside the solid."""
    grid = placed.grid
    span = max(grid.extent) * 0.8
    low, high = placed.z - 0.5, placed.z + float(grid.heights.max()) + 1.0
    pnts = np.column_stack([placed.x + rng.uniform(-span, span, n), placed.y + rng.uniform(-span, span, n),
                            rng.uniform(low, high, n)])
    dirs = rng.normal(size=(n, 3))
    dirs[:, 2] *= rng.uniform(0.02, 1.0, n)
    k = n // 8
    dirs[:k, 2] = 0.0                                               # level
    dirs[k:2 * k] = (0.0, 0.0, -1.0)                                # vertical, down
    dirs[2 * k:2 * k + 10] = (0.0, 0.0, 1.0)                        # vertical, up (from below: the base)
    cs, sn = math.cos(placed.yaw), math.sin(placed.yaw)
    row = np.array([cs, sn, 0.0])                                   # parallel to the grid's rows
    dirs[3 * k:3 * k + 20] = row * rng.choice([-1.0, 1.0], (20, 1))
    dirs[3 * k + 20:3 * k + 40] = (row - np.array([0, 0, 0.2])) * rng.choice([-1.0, 1.0], (20, 1))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    inside = _in_solid(placed, pnts)
    return pnts[~inside], dirs[~inside]


def _in_solid(placed, pnts):
    """Points on or under the grid's surface (within its footprint, above its base's bottom)."""
    grid = placed.grid
    size, _ = hfield_size(grid, placed.z)
    low = placed.z + float(grid.heights.min()) - size[3]
    cs, sn = math.cos(placed.yaw), math.sin(placed.yaw)
    dx, dy = pnts[:, 0] - placed.x, pnts[:, 1] - placed.y
    ground = placed.z + grid.sample(cs * dx + sn * dy, -sn * dx + cs * dy)
    ground = np.nan_to_num(ground, nan=-np.inf)
    return (pnts[:, 2] <= ground + 1e-6) & (pnts[:, 2] >= low - 1e-6)


def _grids():
    rng = np.random.default_rng(5)
    noise = HeightGrid(rng.uniform(0.0, 0.6, (23, 31)), (6.0 / 30, 4.4 / 22))
    terraces = HeightGrid(np.round(rng.uniform(0, 3, (19, 17))) * 0.2, (4.0 / 16, 3.6 / 18))
    flat = HeightGrid(np.full((9, 12), 0.25), (0.3, 0.3))
    smooth = Rough("r", 0, 0, length=5, width=4, amplitude=0.3, wavelength=1.2, seed=3)
    return [("noise", noise, dict(yaw=0.0, z=0.0)), ("terraces, turned, raised", terraces, dict(yaw=37.0, z=0.4)),
            ("flat, turned", flat, dict(yaw=90.0, z=0.0)),
            ("smooth, lowered", height_grid(smooth), dict(yaw=-20.0, z=-0.2))]


@pytest.mark.parametrize("case", range(4), ids=[name for name, _, _ in _grids()])
def test_the_compiled_cast_meets_the_solid_where_a_brute_force_does(case):
    name, grid, pose = _grids()[case]
    length, width = grid.extent
    element = Heightfield("h", 0.3, -0.2, file="h.npy", length=length, width=width, **pose)
    placed = placed_grid(element, grid)
    rng = np.random.default_rng(case)
    for pnts, dirs in (_random_rays(placed, rng, 600), _edge_rays(placed, rng, 300)):
        ref = _brute_force(placed, pnts, dirs, 20.0)
        mine = _compiled(placed, pnts, dirs, 20.0)
        assert np.array_equal(np.isfinite(ref), np.isfinite(mine)), f"{name}: the same rays hit"
        hit = np.isfinite(ref)
        assert hit.sum() > 50
        assert np.abs(ref[hit] - mine[hit]).max() <= TOLERANCE, name
        assert np.array_equal(mine, _vectorised(placed, pnts, dirs, 20.0)), f"{name}: bit for bit"


def test_rays_that_met_something_nearer_and_rays_out_of_range_keep_their_answer():
    element = Rough("mound", 0.0, 0.0, length=4, width=4, amplitude=0.3, wavelength=1.0, seed=1)
    placed = placed_grid(element, height_grid(element))
    pnt = np.array([-5.0, 0.0, 0.5])
    dirs = np.array([[0.99, 0.0, -0.14]] * 3)
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    free = _compiled(placed, pnt, dirs, 30.0)
    assert np.isfinite(free).all()
    out = np.array([1.0, np.inf, np.inf])
    hfield_march.cast(hfield_rays._prepared(placed), pnt, dirs, free[2] - 1e-6, out)
    assert out[0] == 1.0 and out[1] == np.inf and out[2] == np.inf   # nearer met first; out of range


def test_a_16_by_360_scan_over_a_256_cell_field_is_the_vectorised_scan_bit_for_bit():
    field = Rough("field", 0.0, 0.0, length=20.0, width=20.0, amplitude=0.3, wavelength=20.0 / 256 * 8, seed=1)
    placed = placed_grid(field, height_grid(field))
    dirs = sensor_directions(Lidar3D(rings=16, beams=360))
    tilt = math.radians(7.0)                        # a base pitched nose down, as on a slope
    rot = np.array([[math.cos(tilt), 0, math.sin(tilt)], [0, 1, 0], [-math.sin(tilt), 0, math.cos(tilt)]])
    for origin, d in (((0.013, 0.007, 0.5), dirs), ((3.0, -2.0, 0.45), dirs @ rot.T), ((-12.0, 1.0, 0.4), dirs)):
        pnt = np.array(origin)
        mine = _compiled(placed, pnt, d, 30.0)
        assert np.isfinite(mine).sum() > 500
        assert np.array_equal(mine, _vectorised(placed, pnt, d, 30.0))
        assert np.array_equal(mine, hfield_rays.cast_grids([placed], pnt, d, 30.0))   # the lidars' entry


def test_without_numba_the_lidars_cast_with_numpy_and_read_the_same(tmp_path):
    """Where numba cannot be imported (a Python it has no release for yet), ``cast_grids`` falls back
    to the numpy cast: a process with numba blocked gives the same distances, bit for bit."""
    import subprocess
    import sys

    field = Rough("yard", 0.5, -0.3, length=6.0, width=5.0, amplitude=0.2, wavelength=0.7, seed=4, yaw=25.0)
    placed = placed_grid(field, height_grid(field))
    dirs = sensor_directions(Lidar3D(rings=16, beams=90))
    pnt = np.array([0.2, 0.1, 0.6])
    np.save(tmp_path / "dirs.npy", dirs)
    code = (
        "import sys, numpy as np\n"
        "sys.modules['numba'] = None\n"          # import numba now raises ImportError
        "from pytest_navscenario.scenario.ground.heightmap import height_grid\n"
        "from pytest_navscenario.scenario.terrain import Rough\n"
        "from pytest_navscenario.sim.ground import hfield_march\n"
        "from pytest_navscenario.sim.ground.heightfield import placed_grid\n"
        "from pytest_navscenario.sim.ground.hfield_rays import cast_grids\n"
        "f = Rough('yard', 0.5, -0.3, length=6.0, width=5.0, amplitude=0.2, wavelength=0.7, seed=4, yaw=25.0)\n"
        f"d = cast_grids([placed_grid(f, height_grid(f))], np.array([0.2, 0.1, 0.6]), np.load(r'{tmp_path / 'dirs.npy'}'), 30.0)\n"
        f"np.save(r'{tmp_path / 'numpy.npy'}', d)\n"
        "print('compiled' if hfield_march.available() else 'numpy')\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == "numpy"
    fallback = np.load(tmp_path / "numpy.npy")
    mine = hfield_rays.cast_grids([placed], pnt, dirs, 30.0)
    assert hfield_march.available() and np.isfinite(mine).sum() > 200
    assert np.array_equal(fallback, mine)
