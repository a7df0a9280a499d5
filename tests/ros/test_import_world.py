"""``navscenario import`` (Aerialist test YAML, Gazebo SDF) and ``navscenario from-map``
(map_server YAML + PGM) on real files (tests/data, MIT, see LICENSES) and small hand-made ones."""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.geometry import box as shapely_box

from pytest_navscenario.cli import main
from pytest_navscenario.scenario.geometry import obstacle_polygon
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.ros.map_import import map_obstacles, merge_rectangles
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle
from pytest_navscenario.ros.world_import import aerialist_obstacles, sdf_obstacles

DATA = Path(__file__).resolve().parents[1] / "data"


# ------------------------------------------------------------------ Aerialist

def test_aerialist_mission1_gives_its_box(tmp_path, capsys):
    out = tmp_path / "m1.yaml"
    assert main(["import", "aerialist", str(DATA / "aerialist_mission1.yaml"), "-o", str(out)]) == 0
    assert "set --start/--goal" in capsys.readouterr().out
    s = load_scenario(out)
    assert s.obstacles == (BoxObstacle(name="box1", x=-8.0, y=3.0, length=5.0, width=5.0, yaw=0.0, height=5.0),)
    assert (s.mission.start.x, s.mission.start.y, s.mission.goal.y) == (0.0, 0.0, 10.0)


def test_aerialist_flat_list_encoding_with_yaw_in_degrees(tmp_path):
    text = (DATA / "aerialist_template.yaml").read_text().replace(
        "obstacles: [l,w,h, x,y,z, r]", "obstacles: [2, 1, 3, 4, 5, 0, 30, 1, 1, 1, -3, 2, 0.5, 0]")
    assert text != (DATA / "aerialist_template.yaml").read_text()
    src = tmp_path / "flat.yaml"
    src.write_text(text)
    boxes = aerialist_obstacles(src)
    assert boxes == [BoxObstacle("box1", 4.0, 5.0, 2.0, 1.0, 30.0, 3.0), BoxObstacle("box2", -3.0, 2.0, 1.0, 1.0, 0.0, 1.0)]
    # box centred on its position: the corners of the 2 x 1 box rotated 30 degrees about (4, 5)
    corners = np.asarray(obstacle_polygon(boxes[0]).exterior.coords)[:4]
    assert np.allclose(corners.mean(axis=0), (4.0, 5.0))
    assert math.hypot(*(corners[0] - corners[1])) in (pytest.approx(2.0), pytest.approx(1.0))


# ------------------------------------------------------------------ SDF

def test_barn_world_cylinders_at_their_sdf_positions(tmp_path, capsys):
    world = sdf_obstacles(DATA / "barn_world_0.world")
    assert world.warnings == [] and world.ignored_planes == 1
    root = ET.parse(DATA / "barn_world_0.world").getroot()
    expected = {}
    for model in root.find("world").findall("model"):
        if model.get("name").startswith("unit_cylinder"):
            x, y = (float(v) for v in model.find("pose").text.split()[:2])
            expected[model.get("name")] = (x, y)
    assert len(expected) == len(world.obstacles) > 100
    for obs in world.obstacles:
        assert isinstance(obs, CylinderObstacle) and obs.radius == 0.075
        assert (obs.x, obs.y) == pytest.approx(expected[obs.name], abs=1e-9)
    out = tmp_path / "barn.yaml"
    assert main(["import", "sdf", str(DATA / "barn_world_0.world"), "--start=-2.25,3,90",
                 "--goal=-2.25,13,90", "-o", str(out)]) == 0
    assert load_scenario(out).obstacles == tuple(world.obstacles)


SDF = """<?xml version="1.0"?>
<sdf version="1.6"><world name="w">
  <include><uri>model://sun</uri></include>
  <model name="ground"><static>1</static><link name="l"><collision name="c">
    <geometry><plane><normal>0 0 1</normal></plane></geometry></collision></link></model>
  <model name="block"><static>true</static><pose>1 2 0 0 0 1.5707963267948966</pose>
    <link name="l"><pose>1 0 0 0 0 0</pose>
      <collision name="c"><pose>0 0.5 0.5 0 0 0.5235987755982988</pose>
        <geometry><box><size>2 1 1</size></box></geometry></collision>
      <collision name="pipe"><pose>0 0 0 1.5707963 0 0</pose>
        <geometry><cylinder><radius>0.1</radius><length>3</length></cylinder></geometry></collision>
      <collision name="ball"><geometry><sphere><radius>0.3</radius></sphere></geometry></collision>
    </link></model>
  <model name="post"><static>1</static><pose degrees="true">-1 -1 0 0 0 45</pose><link name="l"><collision name="c">
    <geometry><cylinder><radius>0.2</radius><length>2</length></cylinder></geometry></collision></link></model>
  <model name="cart"><link name="l"><collision name="c">
    <geometry><box><size>1 1 1</size></box></geometry></collision></link></model>
  <state world_name="w"><model name="post"><pose>-1 -3 0 0 0 0</pose></model></state>
</world></sdf>
"""


def sdf_obstacles_of(folder: Path, models: str):
    src = folder / "one.sdf"
    src.write_text(f"<sdf version='1.9'><world name='w'>{models}</world></sdf>")
    return sdf_obstacles(src)


def test_sdf_poses_composed_and_unrepresentable_listed(tmp_path, capsys):
    src = tmp_path / "w.world"
    src.write_text(SDF)
    world = sdf_obstacles(src)
    block, post = world.obstacles
    # model (1, 2, yaw 90) * link (1, 0) -> (1, 3); * collision (0, 0.5) rotated 90 -> (0.5, 3)
    assert (block.x, block.y) == pytest.approx((0.5, 3.0))
    assert block.yaw == pytest.approx(120.0) and (block.length, block.width, block.height) == (2.0, 1.0, 1.0)
    assert (post.x, post.y, post.radius) == (-1.0, -3.0, 0.2)  # the <state> pose wins, as in Gazebo
    (bar,) = sdf_obstacles_of(tmp_path, "<model name='bar'><static>1</static><pose degrees='true'>0 0 0 0 0 45</pose>"
                                        "<link name='l'><collision name='c'><geometry><box><size>2 1 1</size></box>"
                                        "</geometry></collision></link></model>").obstacles
    assert bar.yaw == pytest.approx(45.0)  # SDF 1.9 <pose degrees="true">
    odd = sdf_obstacles_of(tmp_path, "<actor name='walker'/><model name='m'><include><uri>model://x</uri>"
                                     "</include></model>")
    assert odd.obstacles == [] and len(odd.warnings) == 2
    assert "<actor> walker" in odd.warnings[0] and "model m: <include> model://x" in odd.warnings[1]
    assert world.ignored_planes == 1
    text = "\n".join(world.warnings)
    for what in ("model://sun", "collision pipe: cylinder tilted", "collision ball: sphere",
                 "model cart link l collision c: box of a non-static model"):
        assert what in text
    assert len(world.warnings) == 4
    out = tmp_path / "w.yaml"
    assert main(["import", "sdf", str(src), "--start=3,-3,0", "--goal=4,-3,0", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "warning: 4 warning(s) about" in err and err.count("(not imported)") == 4


# ------------------------------------------------------------------ map_server

def write_map(folder: Path, img: np.ndarray, *, negate: int = 0, origin=(-1.0, -2.0, 0.0),
              ascii_pgm: bool = False) -> Path:
    h, w = img.shape
    if ascii_pgm:
        body = "\n".join(" ".join(str(int(v)) for v in row) for row in img)
        (folder / "m.pgm").write_text(f"P2\n# made by a test\n{w} {h}\n255\n{body}\n")
    else:
        (folder / "m.pgm").write_bytes(f"P5\n# made by a test\n{w} {h}\n255\n".encode() + img.astype(np.uint8).tobytes())
    path = folder / "map.yaml"
    path.write_text(f"image: m.pgm\nresolution: 0.1\norigin: [{origin[0]}, {origin[1]}, {origin[2]}]\n"
                    f"occupied_thresh: 0.65\nfree_thresh: 0.196\nnegate: {negate}\n")
    return path


def room(h: int = 40, w: int = 60) -> np.ndarray:
    img = np.full((h, w), 254, np.uint8)
    img[0, :] = img[-1, :] = img[:, 0] = img[:, -1] = 0
    img[10:20, 25:30] = 0          # a 0.5 x 1.0 m block
    img[30, 40] = 100              # p = 0.61 < 0.65: free
    img[5, 5] = 205                # unknown in map_server's trinary mode: not an obstacle
    return img


@pytest.mark.parametrize("ascii_pgm", [False, True])
def test_map_boxes_cover_exactly_the_occupied_cells(tmp_path, ascii_pgm):
    img = room()
    boxes, info, cells = map_obstacles(write_map(tmp_path, img, ascii_pgm=ascii_pgm))
    assert cells == int((img == 0).sum()) and len(boxes) == 5
    union = shapely.union_all([obstacle_polygon(b) for b in boxes])
    assert union.area == pytest.approx(cells * 0.01)
    # image row 0 is the top: the block (rows 10-19, cols 25-29) in map coordinates
    h = img.shape[0]
    block = shapely_box(-1.0 + 2.5, -2.0 + (h - 20) * 0.1, -1.0 + 3.0, -2.0 + (h - 10) * 0.1)
    assert any(obstacle_polygon(b).equals_exact(block, 1e-9) or obstacle_polygon(b).symmetric_difference(block).area < 1e-9
               for b in boxes)


def test_map_negate_and_origin_yaw(tmp_path):
    img = np.zeros((10, 10), np.uint8)
    img[0:2, 0:3] = 255   # with negate: 1, white is occupied
    boxes, _, cells = map_obstacles(write_map(tmp_path, img, negate=1, origin=(1.0, 1.0, math.pi / 2)))
    assert cells == 6 and len(boxes) == 1
    b = boxes[0]
    # local centre (0.15, 0.9) rotated 90 degrees about the origin (1, 1) -> (0.1, 1.15)
    assert (b.x, b.y, b.yaw) == pytest.approx((0.1, 1.15, 90.0))
    assert (b.length, b.width) == pytest.approx((0.3, 0.2))


def test_map_raw_mode_reads_occupancy_percent(tmp_path):
    img = np.zeros((3, 4), np.uint8)
    img[0, 0], img[1, 1], img[2, 2] = 100, 60, 255   # occupied, below 0.65, unknown
    path = write_map(tmp_path, img)
    path.write_text(path.read_text() + "mode: raw\n")
    boxes, _, cells = map_obstacles(path)
    assert cells == 1 and len(boxes) == 1


def test_merge_rectangles_modest_count_on_a_maze():
    rng = np.random.default_rng(3)
    mask = np.zeros((200, 200), bool)
    for _ in range(40):
        r, c = rng.integers(0, 190, 2)
        if rng.random() < 0.5:
            mask[r, c:c + rng.integers(10, 60)] = True
        else:
            mask[r:r + rng.integers(10, 60), c] = True
    rects = merge_rectangles(mask)
    cover = np.zeros_like(mask, int)
    for r, c, nr, nc in rects:
        cover[r:r + nr, c:c + nc] += 1
    assert (cover == mask).all()          # covers every occupied cell once, nothing else
    assert len(rects) < mask.sum() / 5    # merged: far fewer boxes than cells


def test_from_map_cli_writes_a_loadable_scenario(tmp_path, capsys):
    out = tmp_path / "map_seed.yaml"
    assert main(["from-map", str(write_map(tmp_path, room())), "--start=0,0,0", "--goal=3,0,0",
                 "-o", str(out)]) == 0
    assert "-> 5 boxes" in capsys.readouterr().out
    s = load_scenario(out)
    assert len(s.obstacles) == 5 and (s.mission.goal.x, s.mission.goal.y) == (3.0, 0.0)
