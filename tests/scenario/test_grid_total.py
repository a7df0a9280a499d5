"""All rough ground and heightfields of a scenario together hold at most MAX_GRID_SAMPLES samples
(issue 38, part 1: 400 heightfields of 1024^2 made a verdict of over 300 s and a MuJoCo model of
1.6 GB); the element that crosses the limit is refused at its line, before more is read."""
from __future__ import annotations

import numpy as np
import pytest

from pytest_navscenario import ScenarioError, load_scenario
from pytest_navscenario.scenario.ground.heightmap import MAX_GRID_SAMPLES

HEAD = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 5, y: 0}}\nrobot: {drive: diff, body: {type: wheeled}}\nterrain:\n"


def test_the_grid_that_crosses_the_total_is_refused_at_its_line(tmp_path):
    np.save(tmp_path / "big.npy", np.zeros((1024, 1024)))
    per = 1024 * 1024
    fits = MAX_GRID_SAMPLES // per
    lines = [f"  - {{type: heightfield, x: {20 + 3 * i}, y: 50, file: big.npy, length: 2, width: 2}}"
             for i in range(fits + 1)]
    (tmp_path / "s.yaml").write_text(HEAD + "\n".join(lines) + "\n")
    with pytest.raises(ScenarioError) as err:
        load_scenario(tmp_path / "s.yaml")
    assert err.value.field == f"terrain[{fits}]" and err.value.line == 5 + fits
    assert f"more than the limit of {MAX_GRID_SAMPLES}" in str(err.value)
    (tmp_path / "ok.yaml").write_text(HEAD + "\n".join(lines[:fits]) + "\n")
    assert len(load_scenario(tmp_path / "ok.yaml").terrain) == fits


def test_rough_patches_count_too(tmp_path):
    per = 1023 * 1023          # 19 m at a wavelength of 19 * 8 / 1022 m: 1023 samples a side
    n = MAX_GRID_SAMPLES // per + 1
    lines = [f"  - {{type: rough, x: {30 + 20 * i}, y: 50, length: 19, width: 19, amplitude: 0.01, "
             f"wavelength: {19 * 8 / 1022:.6f}, seed: {i}}}" for i in range(n)]
    (tmp_path / "s.yaml").write_text(HEAD + "\n".join(lines) + "\n")
    with pytest.raises(ScenarioError, match=f"terrain\\[{n - 1}\\]: brings the rough ground's"):
        load_scenario(tmp_path / "s.yaml")


def test_a_rough_patchs_lowest_surface_is_its_z_without_making_its_grid():
    """Rough ground's heights run from 0 (the tapered border) up, so the loader's check of grids
    dipping below the floor need not generate 50 grids of 1023^2 (22 s of the load at the limit)."""
    from pytest_navscenario.scenario.ground import heightmap
    from pytest_navscenario.scenario.ground.surface import grid_low
    from pytest_navscenario.scenario.terrain import Rough

    for args in [(6, 4, 0.05, 0.6, 1), (19, 19, 0.3, 0.2, 3), (2, 1, 1.0, 0.5, 7), (0.5, 0.5, 0.2, 2.0, 2)]:
        el = Rough("r", 0, 0, length=args[0], width=args[1], amplitude=args[2], wavelength=args[3], seed=args[4],
                   z=-0.25)
        assert grid_low(el, None) == -0.25 == el.z + float(np.asarray(heightmap.height_grid(el).heights).min())
