"""A height grid as MuJoCo's hfield geom: the surface MuJoCo builds is the grid's (same place, same
heights, same triangles), turned by the element's yaw and raised to its base z."""
import math

import mujoco
import numpy as np
import pytest

from pytest_navscenario.scenario.ground.heightmap import height_grid
from pytest_navscenario.scenario.terrain import Rough
from pytest_navscenario.sim.ground.heightfield import HFIELD_GROUP, add_heightfield


@pytest.mark.parametrize("yaw, z", [(0.0, 0.0), (30.0, 0.4)])
def test_the_hfield_surface_is_the_grids(yaw, z):
    rough = Rough("yard", 1.0, -2.0, length=6.0, width=4.0, amplitude=0.3, wavelength=1.0, seed=3,
                  yaw=yaw, z=z)
    grid = height_grid(rough)
    spec = mujoco.MjSpec()
    geom = add_heightfield(spec, rough, grid)
    assert geom.name == "terrain:yard" and geom.group == HFIELD_GROUP
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rng = np.random.default_rng(0)
    local = rng.uniform([-2.9, -1.9], [2.9, 1.9], size=(200, 2))
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    world = np.column_stack([1.0 + c * local[:, 0] - s * local[:, 1], -2.0 + s * local[:, 0] + c * local[:, 1]])
    geomid = np.empty(1, dtype=np.int32)
    found = []
    for wx, wy in world:
        dist = mujoco.mj_ray(model, data, np.array([wx, wy, 5.0]), np.array([0.0, 0.0, -1.0]), None, 1, -1,
                             geomid)
        found.append(5.0 - dist)
    expected = z + grid.sample(local[:, 0], local[:, 1])
    assert np.allclose(found, expected, atol=1e-5)      # MuJoCo keeps the grid as float32
