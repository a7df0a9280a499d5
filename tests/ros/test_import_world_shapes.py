"""``navscenario import sdf`` with the shapes of issue 12: polylines become polygon obstacles, STL/OBJ
meshes become mesh obstacles (the file copied beside the seed), models moved by plugins are imported
where they stand with a note, and slightly malformed world files are repaired and said so."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest
from shapely.geometry import Polygon

from pytest_navscenario.cli import main
from pytest_navscenario.ros.world_import import WorldImportError, sdf_obstacles
from pytest_navscenario.scenario.geometry import obstacle_polygon
from pytest_navscenario.scenario.loader import load_scenario

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "sim"))
from test_irregular import ELL, write_stl  # noqa: E402

POLYLINE = ("<model name='bench'><static>true</static><pose>2 3 0 0 0 1.5707963</pose><link name='l'>"
            "<collision name='c'><geometry><polyline><point>0 0</point><point>2 0</point><point>2 0.5</point>"
            "<point>0.5 0.5</point><point>0.5 2</point><point>0 2</point><height>0.9</height></polyline>"
            "</geometry></collision></link></model>")
MESH = ("<model name='lathe'><static>1</static><pose>-3 1 0 0 0 0</pose><link name='l'><collision name='c'>"
        "<geometry><mesh><uri>model://lathe/meshes/ell.stl</uri><scale>0.5 0.5 0.5</scale></mesh></geometry>"
        "</collision></link></model>")
MISSING = ("<model name='ghost'><static>1</static><link name='l'><collision name='c'><geometry><mesh>"
           "<uri>model://ghost/meshes/none.stl</uri></mesh></geometry></collision></link></model>")
DOOR = ("<model name='door'><pose>6 0 0 0 0 0</pose><plugin name='swing' filename='libdoor.so'/><link name='l'>"
        "<collision name='c'><geometry><box><size>0.1 1 2</size></box></geometry></collision></link></model>")


def world(folder: Path, models: str, tail: str = "") -> Path:
    src = folder / "w.world"
    src.write_text(f"<?xml version='1.0'?>\n<sdf version='1.9'><world name='w'>{models}</world></sdf>{tail}")
    return src


def test_polylines_meshes_and_plugin_models_are_imported(tmp_path, capsys):
    (tmp_path / "models" / "lathe" / "meshes").mkdir(parents=True)
    write_stl(tmp_path / "models" / "lathe" / "meshes" / "ell.stl", ELL)
    src = world(tmp_path, POLYLINE + MESH + MISSING + DOOR)
    got = sdf_obstacles(src)
    bench, lathe, door = got.obstacles
    assert bench.kind == "polygon" and bench.height == 0.9 and bench.yaw == pytest.approx(90.0)
    assert obstacle_polygon(bench).bounds == pytest.approx((0.0, 3.0, 2.0, 5.0), abs=1e-4)
    assert lathe.kind == "mesh" and lathe.file == "meshes/ell.stl" and lathe.scale == (0.5, 0.5, 0.5)
    assert lathe.height == pytest.approx(0.4) and Polygon(lathe.footprint).area == pytest.approx(1.75 / 4)
    assert door.kind == "box" and (door.x, door.y) == (6.0, 0.0)     # non-static, but moved by a plugin
    assert any("model door: plugin(s) swing (libdoor.so) may move or change it" in n and "not carried over" in n
               for n in got.notes)
    assert len(got.warnings) == 1 and "mesh model://ghost/meshes/none.stl: no such file" in got.warnings[0]

    out = tmp_path / "seed" / "w.yaml"
    assert main(["import", "sdf", str(src), "--start=0,-2,0", "--goal=8,-2,0", "-o", str(out)]) == 0
    printed = capsys.readouterr()
    assert "plugin(s) swing (libdoor.so)" in printed.out and "(not imported)" in printed.err
    seed = load_scenario(out)                      # the mesh was copied beside it
    assert (out.parent / "meshes" / "ell.stl").is_file()
    assert [o.name for o in seed.obstacles] == ["bench", "lathe", "door"]
    assert seed.obstacle("lathe").footprint == lathe.footprint


@pytest.mark.parametrize("models, tail, repaired", [
    ("<model name='a&b'><static>1</static><link name='l'><collision name='c'><geometry><box><size>1 1 1</size>"
     "</box></geometry></collision></link></model>", "", "escaped bare '&'"),
    ("<model name='m'><static>1</static><link name='l'><collision name='c'><geometry><box><size>1 1 1</size>"
     "</box></geometry></collision></link></model>", "\n<junk>left by an editor", "dropped the text after </sdf>"),
])
def test_slightly_malformed_worlds_are_repaired_and_said_so(tmp_path, models, tail, repaired):
    got = sdf_obstacles(world(tmp_path, models, tail))
    assert len(got.obstacles) == 1
    assert "not well-formed XML" in got.warnings[0] and repaired in got.warnings[0]


def test_a_world_that_cannot_be_repaired_is_an_error_naming_the_line(tmp_path):
    src = tmp_path / "w.world"
    src.write_text("<sdf version='1.9'>\n<world name='w'>\n<model name='m'></world>\n</sdf>\n")
    with pytest.raises(WorldImportError, match=r"w.world:3: not an SDF world: not well-formed XML"):
        sdf_obstacles(src)
