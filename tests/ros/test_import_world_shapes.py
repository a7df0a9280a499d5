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
from pytest_navscenario.scenario.model import BoxObstacle

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
    # a model moved by a plugin is a warning (issue 24), not a note: it will not stand there
    assert any("model door: plugin(s) swing (libdoor.so) may move or change it" in n and "not carried over" in n
               for n in got.warnings)
    assert len(got.warnings) == 2 and "mesh model://ghost/meshes/none.stl: no such file" in got.warnings[0]

    out = tmp_path / "seed" / "w.yaml"
    assert main(["import", "sdf", str(src), "--start=0,-2,0", "--goal=8,-2,0", "-o", str(out)]) == 0
    printed = capsys.readouterr()
    assert "plugin(s) swing (libdoor.so)" in printed.err and "(not imported)" in printed.err
    seed = load_scenario(out)                      # the mesh was copied beside it
    assert (out.parent / "meshes" / "ell.stl").is_file()
    assert [o.name for o in seed.obstacles] == ["bench", "lathe", "door"]
    assert seed.obstacle("lathe").footprint == lathe.footprint


@pytest.mark.parametrize("models, tail, repaired", [
    ("<model name='a&b'><static>1</static><link name='l'><collision name='c'><geometry><box><size>1 1 1</size>"
     "</box></geometry></collision></link></model>", "", "EntityRef: expecting ';'"),
    ("<model name='m'><static>1</static><link name='l'><collision name='c'><geometry><box><size>1 1 1</size>"
     "</box></geometry></collision></link></model>", "\n<junk>left by an editor",
     "Extra content at the end of the document"),
])
def test_slightly_malformed_worlds_are_repaired_and_said_so(tmp_path, models, tail, repaired):
    got = sdf_obstacles(world(tmp_path, models, tail))
    assert len(got.obstacles) == 1
    # each repair with its line (lxml's recovering parser, as Gazebo's tolerant one reads it)
    assert "not well-formed XML" in got.warnings[0] and repaired in got.warnings[0] and got.warnings[0][0].isdigit()


def test_a_world_that_cannot_be_repaired_is_an_error_naming_the_line(tmp_path):
    src = tmp_path / "w.world"
    src.write_text("<sdf version='1.9'>\n<world name='w'>\n<model name='m'></world>\n</sdf>\n")
    with pytest.raises(WorldImportError, match=r"w.world:3: not an SDF world: not well-formed XML"):
        sdf_obstacles(src)


# ------------------------------------------------------------------ issue 24: the files other tools write

DYNABARN = Path(__file__).resolve().parents[1] / "data" / "dynabarn_world_1.world"


def test_a_barn_dynamic_world_is_recovered_with_every_repair_listed(tmp_path, capsys):
    """DynaBARN world 1 (MIT), which a strict XML parser refuses (``<pose frame=>``): read as Gazebo
    classic reads it, each repair with its line, the plugin-moved cylinders a warning each, their
    pile at one spot imported once and said so, the three walls where they stand."""
    import xml.etree.ElementTree as ET
    with pytest.raises(ET.ParseError):
        ET.parse(DYNABARN)
    got = sdf_obstacles(DYNABARN)
    repairs = [w for w in got.warnings if "not well-formed XML" in w]
    assert [w.split(":")[0] for w in repairs] == ["348", "389", "427"]
    assert all("repaired and read as Gazebo would" in w for w in repairs)
    pile = [w for w in got.warnings if "identical models stand at one spot" in w]
    assert len(pile) == 1 and pile[0].startswith("6 identical models stand at one spot (-0.225, 0.075)")
    assert [w for w in got.warnings if "easylibobs_66: plugin(s)" in w]
    walls = {o.name: (o.x, o.y, o.length, o.width) for o in got.obstacles if isinstance(o, BoxObstacle)}
    assert walls == {"back_wall": (-10.0, 0.0, 0.5, 20.0), "top_wall": (0.0, 10.0, 20.0, 0.5),
                     "bottom_wall": (0.0, -10.0, 20.0, 0.5)}
    assert len(got.obstacles) == 4
    out = tmp_path / "dyn.yaml"
    assert main(["import", "sdf", str(DYNABARN), "--start=-2.25,3,90", "--goal=-2,-8,0", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"warning: {DYNABARN}:348: not well-formed XML" in err
    assert len(load_scenario(out).obstacles) == 4


def test_a_recovered_world_without_a_world_is_an_error(tmp_path):
    src = tmp_path / "w.world"
    src.write_text("<sdf version='1.6'>\n<wrld name=>\n<model name='m'/>\n</wrld>\n</sdf>\n")
    with pytest.raises(WorldImportError, match=r"not an SDF world: expected <sdf><world>\.\.\., found <sdf> with "
                                               r"<wrld> in it \(even after repairing its XML: 1 repair\(s\), the first "
                                               r"at line 2: not well-formed XML"):
        sdf_obstacles(src)


@pytest.mark.parametrize("uri", ["file://{outside}/ell.stl", "model://../outside/ell.stl"])
def test_a_mesh_from_outside_the_worlds_folder_is_refused(tmp_path, uri, capsys):
    """Issue 26.13: the docs say meshes are found beside the world, and the loader refuses paths
    outside a scenario's folder; before, the importer copied any file:// or model://../.. mesh."""
    outside = tmp_path / "outside"
    outside.mkdir()
    write_stl(outside / "ell.stl", ELL)
    folder = tmp_path / "w"
    folder.mkdir()
    mesh = MESH.replace("model://lathe/meshes/ell.stl", uri.format(outside=outside))
    src = world(folder, mesh)
    with pytest.raises(WorldImportError, match=r"outside the world's folder .*copy it there, or name its folder "
                                               r"with --model-path"):
        sdf_obstacles(src)
    out = tmp_path / "seed" / "w.yaml"
    assert main(["import", "sdf", str(src), "--start=0,-2,0", "--goal=8,-2,0", "-o", str(out)]) == 2
    assert "outside the world's folder" in capsys.readouterr().err and not out.exists()
    allowed = sdf_obstacles(src, model_path=(outside,)) if uri.startswith("file") else \
        sdf_obstacles(src, model_path=(tmp_path,))
    assert [o.kind for o in allowed.obstacles] == ["mesh"]
