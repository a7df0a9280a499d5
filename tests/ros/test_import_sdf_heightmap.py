"""``navscenario import sdf`` reads Gazebo ``<heightmap>`` collisions: a heightfield element with the
image copied beside the seed, heights as Gazebo computes them (pixel / brightest pixel x size z),
placed on the composed pose plus ``<pos>``; what it cannot read (a DEM, a colour image, a missing
file) is a warning, not a silent drop."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from pytest_navscenario.ros.world_import import sdf_obstacles
from pytest_navscenario.scenario.ground.heightmap import HeightGrid, load_heightfield, read_height_file


def _world(folder: Path, models: str) -> Path:
    src = folder / "hills.world"
    src.write_text(f"<?xml version='1.0'?>\n<sdf version='1.6'><world name='w'>"
                   f"<model name='ground_plane'><static>true</static><link name='l'><collision name='c'>"
                   f"<geometry><plane><normal>0 0 1</normal></plane></geometry></collision></link></model>"
                   f"{models}</world></sdf>")
    return src


def _heightmap(uri: str, size: str = "20 10 2", pos: str = "1 0 0.5", pose: str = "3 4 0.1 0 0 1.5707963") -> str:
    return (f"<model name='hills'><static>true</static><pose>{pose}</pose><link name='l'><collision name='c'>"
            f"<geometry><heightmap><uri>{uri}</uri><size>{size}</size><pos>{pos}</pos></heightmap></geometry>"
            f"</collision></link></model>")


def test_a_png_heightmap_becomes_a_heightfield_with_gazebos_heights(tmp_path):
    (tmp_path / "media").mkdir()
    img = np.full((33, 65), 64, dtype=np.uint16)        # 65 columns (x), 33 rows (y)
    img[0, -1] = 256                                     # the brightest pixel: top right
    Image.fromarray(img).save(tmp_path / "media" / "hills.png")
    got = sdf_obstacles(_world(tmp_path, _heightmap("file://media/hills.png".replace("file://", ""))))
    assert got.obstacles == [] and got.ignored_planes == 1 and not got.warnings
    (hf,) = got.terrain
    # centre: the model at (3, 4) turned 90 degrees, plus <pos> (1, 0) turned with it
    assert (hf.x, hf.y, hf.z) == pytest.approx((3.0, 5.0, 0.6))
    assert hf.yaw == pytest.approx(90.0) and (hf.length, hf.width) == (20.0, 10.0)
    # Gazebo: height = pixel / brightest * size z: 64 / 256 * 2 = 0.5 for the lowest, 2 for the top
    assert (hf.min_height, hf.max_height) == pytest.approx((0.5, 2.0))
    assert hf.file == "heightmaps/hills.png" and got.meshes["heightmaps/hills.png"] == \
        (tmp_path / "media" / "hills.png").read_bytes()
    assert any("terrain 'hills'" in n for n in got.notes)
    # the copied file reads back as the same grid, its extent matching
    (tmp_path / "seed" / "heightmaps").mkdir(parents=True)
    (tmp_path / "seed" / hf.file).write_bytes(got.meshes[hf.file])
    load_heightfield(tmp_path / "seed", hf.file, hf.length, hf.width)
    assert np.array_equal(read_height_file(tmp_path / "seed" / hf.file), img.astype(float))


def test_what_cannot_be_read_is_said(tmp_path):
    (tmp_path / "m").mkdir()
    Image.new("RGB", (5, 5), (200, 10, 10)).save(tmp_path / "m" / "colour.png")
    models = (_heightmap("m/dem.tif").replace("'hills'", "'dem'") + _heightmap("m/colour.png").replace("'hills'", "'c'")
              + _heightmap("m/none.png").replace("'hills'", "'gone'")
              + _heightmap("m/colour.png", pose="0 0 0 0.3 0 0").replace("'hills'", "'tilted'"))
    got = sdf_obstacles(_world(tmp_path, models))
    assert got.terrain == []
    text = "\n".join(got.warnings)
    assert "only PNG heightmaps are read" in text and "colour image" in text
    assert "m/none.png: no such file" in text and "heightmap tilted" in text
    assert all("(not imported)" in w for w in got.warnings) and len(got.warnings) == 4


def test_the_imported_grid_is_the_one_gazebo_builds(tmp_path):
    """Samples of the scenario's grid equal Gazebo's heights at the image's pixels."""
    from types import SimpleNamespace

    from pytest_navscenario.scenario.ground.heightmap import height_grid

    img = (np.arange(9 * 9).reshape(9, 9) * 3).astype(np.uint8)
    img[4, 4] = 0
    Image.fromarray(img).save(tmp_path / "h.png")
    got = sdf_obstacles(_world(tmp_path, _heightmap("h.png", size="8 8 4", pos="0 0 0", pose="0 0 0 0 0 0")))
    (hf,) = got.terrain
    (tmp_path / "heightmaps").mkdir()
    (tmp_path / hf.file).write_bytes(got.meshes[hf.file])
    grid: HeightGrid = height_grid(hf, SimpleNamespace(source=str(tmp_path / "seed.yaml")))
    gazebo = img.astype(float) / img.max() * 4.0              # pixel / brightest * size z
    assert np.allclose(grid.heights, gazebo[::-1])            # the image's top row is +y


def test_the_command_line_writes_a_seed_that_loads_with_its_heightmap(tmp_path, capsys):
    from pytest_navscenario.cli import main
    from pytest_navscenario.scenario.loader import load_scenario

    img = (np.arange(17 * 17).reshape(17, 17) % 200).astype(np.uint8)
    Image.fromarray(img).save(tmp_path / "bumps.png")
    src = _world(tmp_path, _heightmap("bumps.png", size="8 8 0.5", pos="0 0 0", pose="10 0 0 0 0 0"))
    out = tmp_path / "seed" / "hills.yaml"
    assert main(["import", "sdf", str(src), "--start=0,0,0", "--goal=4,0,0", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "1 terrain element(s)" in printed and "robot.body: wheeled" in printed
    seed = load_scenario(out)
    (hf,) = seed.terrain
    assert hf.kind == "heightfield" and hf.digest and (out.parent / hf.file).is_file()
    assert seed.robot.body.kind == "wheeled"


def test_the_import_says_the_drive_the_seed_has(tmp_path, capsys):
    """#36: a world with terrain gets the wheeled body and drive: diff; the robot line printed must
    say diff, not the omni drive of the default robot it started from."""
    from pytest_navscenario.cli import main

    Image.fromarray((np.arange(17 * 17).reshape(17, 17) % 50).astype(np.uint8)).save(tmp_path / "low.png")
    src = _world(tmp_path, _heightmap("low.png", size="8 8 0.5", pos="0 0 0", pose="10 0 0 0 0 0"))
    assert main(["import", "sdf", str(src), "--start=0,0,0", "--goal=4,0,0", "-o", str(tmp_path / "s.yaml")]) == 0
    printed = capsys.readouterr().out
    robot_line = next(line for line in printed.splitlines() if "navscenario import: robot:" in line)
    assert "diff drive" in robot_line and "omni" not in robot_line


def test_a_model_heightmap_not_found_hints_at_model_path(tmp_path, capsys):
    """#36: a model:// heightmap that is not beside the world says where it looked and to pass
    --model-path with the folder holding the model, not only '(not imported)'."""
    from pytest_navscenario.cli import main

    src = _world(tmp_path, _heightmap("model://hills/materials/textures/hills.png", pose="0 0 0 0 0 0"))
    main(["import", "sdf", str(src), "--start=0,0,0", "--goal=4,0,0", "-o", str(tmp_path / "s.yaml")])
    err = capsys.readouterr().err
    assert "model://hills/materials/textures/hills.png" in err
    assert "--model-path" in err and "'hills'" in err


@pytest.mark.parametrize("how", ["absolute", "file", "model", "dotdot", "symlink"])
def test_a_heightmap_from_outside_the_worlds_folder_is_refused_as_a_mesh_is(tmp_path, how):
    from pytest_navscenario.ros.world_import import WorldImportError

    outside = tmp_path / "secret"
    outside.mkdir()
    Image.fromarray(np.full((9, 9), 7, dtype=np.uint8)).save(outside / "h.png")
    world = tmp_path / "a" / "b"
    world.mkdir(parents=True)
    if how == "symlink":
        (world / "h.png").symlink_to(outside / "h.png")
    uri = {"absolute": str(outside / "h.png"), "file": f"file://{outside / 'h.png'}",
           "model": "model://../../secret/h.png", "dotdot": "../../secret/h.png", "symlink": "h.png"}[how]
    for what, models in [("heightmap", _heightmap(uri)),
                         ("mesh", _heightmap(uri).replace("<heightmap>", "<mesh>").replace("</heightmap>", "</mesh>")
                          .replace("h.png", "h.stl"))]:
        if what == "mesh":
            (outside / "h.stl").write_text("solid s\nendsolid s\n")
            if how == "symlink":
                (world / "h.stl").symlink_to(outside / "h.stl")
        with pytest.raises(WorldImportError, match=f"{what} .* outside the world's folder"):
            sdf_obstacles(_world(world, models))


@pytest.mark.parametrize("uri", ["model://hills/materials/textures/hills.png", "media/hills.png"])
def test_a_heightmap_not_found_fails_the_import_and_names_model_path(tmp_path, capsys, uri):
    """#36 point 5: a heightmap that is not found must not give a flat seed with exit status 0:
    the import fails (non-zero), writes nothing, and names --model-path, for any uri form."""
    from pytest_navscenario.cli import main

    src = _world(tmp_path, _heightmap(uri, pose="0 0 0 0 0 0"))
    out = tmp_path / "s.yaml"
    assert main(["import", "sdf", str(src), "--start=0,0,0", "--goal=4,0,0", "-o", str(out)]) != 0
    err = capsys.readouterr().err
    assert uri in err and "--model-path" in err and "not found" in err
    assert not out.exists()
