"""The lidars' own ray cast over height grids equals MuJoCo's mj_ray on the same hfield geom, ray by
ray: the same rays hit, at the same distance within 1e-5 m (MuJoCo keeps the grid in float32; the
largest difference measured over 59 000 random rays was 4e-7 m), over smooth, noisy, terraced and
cliff grids, turned and raised, for level, steep, grazing and vertical rays and a lidar's fan."""
import math

import mujoco
import numpy as np
import pytest

from pytest_navscenario.scenario.ground.heightmap import HeightGrid, height_grid
from pytest_navscenario.scenario.terrain import Heightfield, Rough
from pytest_navscenario.sim.ground.heightfield import add_heightfield, placed_grid
from pytest_navscenario.sim.ground.hfield_rays import cast_grids

TOLERANCE = 1e-5    # m


def _mujoco(element, grid):
    spec = mujoco.MjSpec()
    add_heightfield(spec, element, grid)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def _reference(model, data, pnts, dirs, rmax):
    geom = np.empty(1, dtype=np.int32)
    ref = np.array([mujoco.mj_ray(model, data, p, d, None, 1, -1, geom) for p, d in zip(pnts, dirs)])
    ref[(ref < 0) | (ref > rmax)] = np.inf
    return ref


def _above_ground(element, grid, pnts):
    c, s = math.cos(math.radians(element.yaw)), math.sin(math.radians(element.yaw))
    dx, dy = pnts[:, 0] - element.x, pnts[:, 1] - element.y
    ground = element.z + grid.sample(c * dx + s * dy, -s * dx + c * dy)
    return ~(pnts[:, 2] <= np.nan_to_num(ground, nan=-np.inf) + 1e-6)


def _assert_same(ref, mine):
    assert np.array_equal(np.isfinite(ref), np.isfinite(mine)), "the same rays hit"
    both = np.isfinite(ref)
    assert both.any()
    assert np.abs(ref[both] - mine[both]).max() <= TOLERANCE


@pytest.mark.parametrize("shape", ["smooth", "noise", "terraces", "cliff"])
def test_random_rays_meet_the_grid_where_mujoco_says(shape):
    rng = np.random.default_rng(["smooth", "noise", "terraces", "cliff"].index(shape))
    rows, cols = 37, 53
    if shape == "smooth":
        heights = height_grid(Rough("r", 0, 0, length=8, width=6, amplitude=0.4, wavelength=1.5, seed=3)).heights
        rows, cols = heights.shape
    elif shape == "noise":
        heights = rng.uniform(0, 0.8, (rows, cols))
    elif shape == "terraces":                 # flat cells and vertical-ish steps
        heights = np.round(rng.uniform(0, 3, (rows, cols))) * 0.2
    else:
        heights = np.zeros((rows, cols))
        heights[rows // 3:, :] = 0.5
    grid = HeightGrid(heights, (8.0 / (cols - 1), 6.0 / (rows - 1)))
    element = Heightfield("h", 0.7, -0.4, file="h.npy", length=8.0, width=6.0, yaw=37.0, z=0.3)
    model, data = _mujoco(element, grid)
    n = 1500
    pnts = np.column_stack([rng.uniform(-8, 8, n), rng.uniform(-8, 8, n), rng.uniform(0.0, 2.5, n)])
    pnts = pnts[_above_ground(element, grid, pnts)]
    dirs = rng.normal(size=(len(pnts), 3))
    dirs[:, 2] *= rng.uniform(0.05, 1.0, len(pnts))       # many shallow, grazing rays
    dirs[:100, 2] = 0.0                                  # level
    dirs[100:150] = (0.0, 0.0, -1.0)                     # vertical
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    _assert_same(_reference(model, data, pnts, dirs, 30.0), cast_grids([placed_grid(element, grid)], pnts,
                                                                       dirs, 30.0))


def test_a_lidar_fan_over_a_256_cell_field_and_its_range():
    element = Rough("yard", 0.0, 0.0, length=32, width=32, amplitude=0.4, wavelength=1.0, seed=2)
    grid = height_grid(element)
    assert grid.heights.shape == (257, 257)
    model, data = _mujoco(element, grid)
    elev = np.radians(np.linspace(-15, 15, 16))
    azim = np.radians(np.arange(0, 360, 3))
    e, a = np.meshgrid(elev, azim, indexing="ij")
    dirs = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], -1).reshape(-1, 3)
    for origin, rmax in (((0.0, 0.0, 0.9), 30.0), ((3.0, -2.0, 0.6), 5.0), ((-20.0, 0.0, 0.5), 30.0)):
        pnt = np.array(origin)
        mine = cast_grids([placed_grid(element, grid)], pnt, dirs, rmax)
        ref = _reference(model, data, np.tile(pnt, (len(dirs), 1)), dirs, rmax)
        _assert_same(ref, mine)
        assert np.all(mine[np.isfinite(mine)] <= rmax)


def test_a_raised_patch_has_solid_sides_and_rays_above_it_cost_nothing_to_miss():
    element = Rough("mound", 0.0, 0.0, length=4, width=4, amplitude=0.3, wavelength=1.0, seed=1, z=0.5)
    grid = height_grid(element)
    placed = placed_grid(element, grid)
    # level rays at 0.25 m from the side hit the side wall of the raised base at its edge (x = -2)
    dist = cast_grids([placed], np.array([-5.0, 0.0, 0.25]), np.array([[1.0, 0.0, 0.0]]), 30.0)
    assert dist[0] == pytest.approx(3.0)
    # rays from above the highest point going up or level never enter the box
    up = cast_grids([placed], np.array([0.0, 0.0, 2.0]), np.array([[1.0, 0.0, 0.0], [0.0, 0.6, 0.8]]), 30.0)
    assert np.all(np.isinf(up))


def test_a_ray_that_met_something_nearer_stops_looking_there():
    element = Rough("mound", 0.0, 0.0, length=4, width=4, amplitude=0.3, wavelength=1.0, seed=1)
    placed = [placed_grid(element, height_grid(element))]
    pnt = np.array([-5.0, 0.0, 0.5])
    dirs = np.array([[0.99, 0.0, -0.14], [0.99, 0.0, -0.14]])
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    free = cast_grids(placed, pnt, dirs, 30.0)
    assert np.isfinite(free).all()
    limited = cast_grids(placed, pnt, dirs, 30.0, within=np.array([1.0, np.inf]))
    assert limited[0] == 1.0 and limited[1] == free[1]     # the limit kept: nothing nearer on the grid


def test_rays_that_cannot_come_down_to_the_grid_are_left_out_with_every_answer_unchanged():
    """A tilted 2D lidar fan and a 16-ring scan from above a rough patch: the cast that first leaves
    out the rays starting above the grid's top that do not come down to it within range gives the
    same distances, bit for bit, as casting every ray."""
    from pytest_navscenario.sim.ground import hfield_rays

    element = Rough("yard", 1.0, 0.5, length=6.0, width=5.0, amplitude=0.1, wavelength=0.6, seed=7, yaw=20.0)
    placed = placed_grid(element, height_grid(element))
    grid = hfield_rays._prepared(placed)
    a = np.radians(np.arange(360.0))
    tilt = math.radians(8.0)          # pitched nose down: the front half of the fan comes down
    fan = np.column_stack([np.cos(a) * np.cos(tilt * np.cos(a)), np.sin(a),
                           -np.sin(tilt * np.cos(a))])
    fan /= np.linalg.norm(fan, axis=1)[:, None]
    el = np.radians(np.linspace(-15, 15, 16))[:, None]
    rings = np.stack([np.cos(el) * np.cos(a), np.cos(el) * np.sin(a), np.sin(el) * np.ones_like(a)], -1).reshape(-1, 3)
    for pnt, dirs in ((np.array([0.5, 0.0, 0.35]), fan), (np.array([1.0, 1.0, 0.6]), rings)):
        for within in (None, np.full(len(dirs), 4.0)):
            every = np.full(len(dirs), np.inf) if within is None else within.copy()
            hfield_rays._cast_rays(grid, pnt, dirs, 30.0, every)
            mine = cast_grids([placed], pnt, dirs, 30.0, within=within)
            assert np.array_equal(mine, every)
            assert np.isfinite(mine).sum() > 20
        z0 = pnt[2] - grid.base
        assert z0 > grid.zmax and (dirs[:, 2] >= 0).sum() > len(dirs) // 3     # rays it leaves out
