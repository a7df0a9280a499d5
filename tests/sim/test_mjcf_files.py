"""Every file MuJoCo opens for the user's MJCF robot follows ``robot.body.file``'s rules (issue 38,
part 4): an ``<include>``, the compiler's meshdir/texturedir/assetdir and asset files from outside
the scenario's folder (absolute, ``..``, a link out) are refused at the line of ``file:``; a FIFO is
refused without hanging; every one of them is hashed into the content, and one edited after the
scenario was loaded does not run under the old hash."""
import os
import shutil
import sys
from pathlib import Path

import pytest

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.scenario.model import content_hash
from pytest_navscenario.sim.episode import simulate

sys.path.insert(0, str(Path(__file__).parents[1] / "search"))
from straight_planner import Straight  # noqa: E402

CART = (Path(__file__).parents[1] / "data" / "mjcf" / "cart.xml").read_text()
SCENE = """version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 2, y: 0}, timeout: 5}
robot:
  drive: diff
  safety: {enabled: false}
  body: {type: mjcf, file: robot/cart.xml, controller: "cart_controller:Cart"}
"""
OPTION = '<mujoco><option timestep="0.002"/></mujoco>'


def scene(tmp_path: Path, head: str = "", extra: dict | None = None) -> Path:
    """The cart in tmp/scene/robot/cart.xml with ``head`` put after <mujoco ...>, the files of
    ``extra`` (path relative to tmp -> text) written, the scenario tmp/scene/scene.yaml."""
    (tmp_path / "scene" / "robot").mkdir(parents=True, exist_ok=True)
    (tmp_path / "scene" / "robot" / "cart.xml").write_text(CART.replace('<mujoco model="cart">',
                                                                        '<mujoco model="cart">' + head))
    for rel, text in (extra or {}).items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text)
    path = tmp_path / "scene" / "scene.yaml"
    path.write_text(SCENE)
    return path


@pytest.mark.parametrize("head,extra,says", [
    ('<include file="../../outside.xml"/>', {"outside.xml": OPTION}, "outside the scenario's folder"),
    ('<include file="{tmp}/outside.xml"/>', {"outside.xml": OPTION}, "absolute path"),
    ('<include file="file:///etc/hostname"/>', {}, "absolute path or a URL"),
    ('<compiler meshdir="/etc"/>', {}, "<compiler meshdir> of cart.xml '/etc' is an absolute path"),
    ('<compiler texturedir="../.."/>', {}, "<compiler texturedir> of cart.xml"),
    ('<asset><mesh name="m" file="../../m.stl"/></asset>', {"m.stl": "solid\nendsolid\n"}, "<mesh file>"),
    ('<compiler meshdir="meshes"/><asset><mesh name="m" file="../../../m.stl"/></asset>',
     {"m.stl": "solid\nendsolid\n"}, "<mesh file>"),
    ('<asset><texture name="t" type="cube" fileright="/etc/hostname"/></asset>', {}, "<texture fileright>"),
    ('<include file="inc.xml"/>', {"scene/robot/inc.xml": '<mujoco><include file="../../x.xml"/></mujoco>',
                                   "x.xml": OPTION}, "<include file> of inc.xml"),
])
def test_files_muJoCo_would_open_outside_the_folder_are_refused_at_load(tmp_path, head, extra, says):
    path = scene(tmp_path, head.replace("{tmp}", str(tmp_path)), extra)
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert err.value.field == "robot.body.file" and err.value.line == 6
    assert says in str(err.value) and "fix: keep the robot's" in str(err.value)


def test_a_link_out_of_the_folder_is_refused(tmp_path):
    path = scene(tmp_path, '<include file="inc.xml"/>', {"outside.xml": OPTION})
    (tmp_path / "scene" / "robot" / "inc.xml").symlink_to(tmp_path / "outside.xml")
    with pytest.raises(ScenarioError, match="outside the scenario's folder"):
        load_scenario(path)


def test_an_included_fifo_is_refused_without_hanging(tmp_path):
    path = scene(tmp_path, '<include file="pipe.xml"/>')
    os.mkfifo(tmp_path / "scene" / "robot" / "pipe.xml")
    with pytest.raises(ScenarioError, match="pipe.xml is not a regular file"):
        load_scenario(path)


def test_included_and_asset_files_are_content_and_an_edit_after_load_is_refused(tmp_path):
    path = scene(tmp_path, '<include file="inc.xml"/>', {"scene/robot/inc.xml": OPTION})
    first = load_scenario(path)
    (tmp_path / "scene" / "robot" / "inc.xml").write_text(OPTION.replace("0.002", "0.004"))
    second = load_scenario(path)
    assert content_hash(second) != content_hash(first)            # the included file is content
    (tmp_path / "scene" / "robot" / "inc.xml").write_text(OPTION)
    assert content_hash(load_scenario(path)) == content_hash(first)
    (tmp_path / "scene" / "robot" / "inc.xml").write_text(OPTION.replace("0.002", "0.003"))   # after load
    with pytest.raises(ScenarioError, match="changed after the scenario was loaded"):
        simulate(first, Straight(), 0)
    (tmp_path / "scene" / "robot" / "cart.xml").write_text(CART.replace('mass="20"', 'mass="25"'))
    with pytest.raises(ScenarioError, match="changed after the scenario was loaded"):
        simulate(second, Straight(), 0)


def test_a_robot_whose_files_stay_inside_runs_and_a_lone_file_hashes_as_before(tmp_path):
    import hashlib
    path = scene(tmp_path)
    loaded = load_scenario(path)
    assert loaded.robot.body.digest == hashlib.sha256((tmp_path / "scene/robot/cart.xml").read_bytes()).hexdigest()[:16]
    assert simulate(loaded, Straight(), 0).end in ("goal", "timeout")
    shutil.rmtree(tmp_path / "scene")
    path = scene(tmp_path, '<include file="inc.xml"/>', {"scene/robot/inc.xml": OPTION})
    assert simulate(load_scenario(path), Straight(), 0).end in ("goal", "timeout")


def test_the_robot_files_contact_options_survive_in_the_compiled_model(tmp_path):
    """Issue #36 point 2: the file's <option cone impratio> concern the robot's contacts; they are
    kept (a quadruped sagged 0.20 m without them), the scenario's timestep and gravity still rule."""
    import mujoco
    from pytest_navscenario.sim.body_world import compiled_body_world
    path = scene(tmp_path, '<option cone="elliptic" impratio="100" timestep="0.01" gravity="0 0 -1"/>')
    loaded = load_scenario(path)
    model = compiled_body_world(loaded).model
    assert model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert model.opt.impratio == 100
    assert model.opt.timestep == loaded.simulation.timestep
    assert model.opt.gravity[2] < -9
