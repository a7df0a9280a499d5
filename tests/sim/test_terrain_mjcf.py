"""The user's own MJCF robot (tests/data/mjcf/cart.xml, a small differential-drive cart) driven by a
controller of theirs (tests/sim/cart_controller.py): it rides the terrain (up a ramp, off a dock),
meets obstacles, and a file that MuJoCo cannot load, a model without a free base, a controller that
cannot be found or breaks the protocol are clear errors naming the file and the field."""
import math
import re
import shutil
import time
import sys
from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.scenario.model import content_hash
from pytest_navscenario.sim.bodies.mjcf import BodyControllerError
from pytest_navscenario.sim.episode import simulate

sys.path.insert(0, str(Path(__file__).parents[1] / "search"))
from straight_planner import Straight  # noqa: E402

CART = Path(__file__).parents[1] / "data" / "mjcf" / "cart.xml"


def write(folder: Path, body: str, terrain: str = "", obstacles: str = "", goal: str = "{x: 9, y: 0}") -> Path:
    shutil.copy(CART, folder / "cart.xml")
    path = folder / "scene.yaml"
    path.write_text(f"""version: 1
mission: {{start: {{x: 0, y: 0}}, goal: {goal}, timeout: 20}}
robot:
  drive: diff
  safety: {{enabled: false}}
  body: {body}
{terrain}
{obstacles}
""")
    return path


RAMP = """terrain:
  - {type: ramp, name: ramp, x: 4.5, y: 0, length: 3.0, width: 3.0, rise: 0.53}
  - {type: platform, name: top, x: 9.0, y: 0, length: 6.0, width: 3.0, height: 0.53}"""
CART_BODY = '{type: mjcf, file: cart.xml, controller: "cart_controller:Cart"}'


def test_the_users_cart_climbs_a_10_degree_ramp_on_its_own_wheels(tmp_path):
    res = simulate(load_scenario(write(tmp_path, CART_BODY, RAMP)), Straight(), 0)
    assert res.end == "goal"
    traj = res.trajectory
    assert traj.z[0] == pytest.approx(0.002, abs=1e-6)                # its wheels on the ground at the start
    assert traj.z[-1] == pytest.approx(0.53, abs=0.01)                 # on the upper level
    on_ramp = (traj.pose[:, 0] > 3.6) & (traj.pose[:, 0] < 5.4)
    assert 8.0 < math.degrees(-traj.pitch[on_ramp].mean()) < 14.0


def test_it_falls_off_a_dock_and_its_wheels_hit_an_obstacle(tmp_path):
    dock = write(tmp_path, CART_BODY, "terrain:\n  - {type: platform, name: dock, x: 0, y: 0, length: 6.0, "
                                      "width: 4.0, height: 1.2}")
    res = simulate(load_scenario(dock), Straight(), 0)
    assert res.end == "fell" and res.terrain_event.element == "off platform 'dock'"
    assert res.terrain_event.drop == pytest.approx(1.2)
    crate = write(tmp_path, CART_BODY, obstacles="obstacles:\n  - {type: box, name: crate, x: 5, y: 0.2, "
                                                 "length: 0.4, width: 0.1, height: 0.15}")
    res = simulate(load_scenario(crate), Straight(), 0)
    assert res.end == "collision" and res.collision.obstacle == "crate"


def test_a_controller_writing_ctrl_itself_drives_the_same_bits(tmp_path):
    a = simulate(load_scenario(write(tmp_path, CART_BODY, RAMP)), Straight(), 0)
    b = simulate(load_scenario(write(tmp_path, CART_BODY.replace("Cart", "WritesCtrl"), RAMP)), Straight(), 0)
    for name in ("pose", "velocity", "z", "roll", "pitch"):
        assert getattr(a.trajectory, name).tobytes() == getattr(b.trajectory, name).tobytes()


def test_the_file_is_content_by_its_bytes_not_its_path(tmp_path):
    first = load_scenario(write(tmp_path, CART_BODY))
    (tmp_path / "robots").mkdir()
    shutil.copy(CART, tmp_path / "robots" / "same.xml")
    moved = load_scenario(write(tmp_path, CART_BODY.replace("cart.xml", "robots/same.xml")))
    assert content_hash(moved) == content_hash(first)
    (tmp_path / "robots" / "same.xml").write_text(CART.read_text().replace('mass="20"', 'mass="25"'))
    assert content_hash(load_scenario(tmp_path / "scene.yaml")) != content_hash(first)


def test_a_file_outside_the_folder_or_missing_is_refused_at_load_with_its_line(tmp_path):
    with pytest.raises(ScenarioError) as err:
        load_scenario(write(tmp_path, CART_BODY.replace("cart.xml", "../cart.xml")))
    assert err.value.field == "robot.body.file" and err.value.line == 6 and "leaves the scenario's folder" in str(err.value)
    with pytest.raises(ScenarioError, match="robot.body.file: .*nothere.xml does not exist"):
        load_scenario(write(tmp_path, CART_BODY.replace("cart.xml", "nothere.xml")))


def test_mujocos_own_message_for_a_file_it_cannot_load_and_a_model_without_a_free_base(tmp_path):
    path = write(tmp_path, CART_BODY)
    (tmp_path / "cart.xml").write_text(CART.read_text().replace("<freejoint", "<frejoint"))
    with pytest.raises(ScenarioError) as err:
        simulate(load_scenario(path), Straight(), 0)
    text = str(err.value)
    assert text.startswith(f"{path}:6: robot.body.file: MuJoCo cannot load {tmp_path / 'cart.xml'}: ")
    assert "frejoint" in text                                          # MuJoCo's own words
    (tmp_path / "cart.xml").write_text(CART.read_text().replace('<freejoint name="root"/>', ""))
    with pytest.raises(ScenarioError, match="has no body with a free joint .*fix: give the robot's base body"):
        simulate(load_scenario(path), Straight(), 0)
    shutil.copy(CART, tmp_path / "cart.xml")
    with pytest.raises(ScenarioError, match="robot.body.base: .*has no body named 'chasis' .*chassis"):
        simulate(load_scenario(write(tmp_path, CART_BODY[:-1] + ", base: chasis}")), Straight(), 0)
    with pytest.raises(ScenarioError, match="robot.body.base: body 'left_wheel' .*has no free joint"):
        simulate(load_scenario(write(tmp_path, CART_BODY[:-1] + ", base: left_wheel}")), Straight(), 0)


def test_a_controller_that_cannot_be_found_or_breaks_the_protocol(tmp_path):
    with pytest.raises(ScenarioError, match=r"robot.body.controller: body controller 'no_such_mod:Cart': cannot "
                                            r"import module 'no_such_mod'"):
        simulate(load_scenario(write(tmp_path, CART_BODY.replace("cart_controller", "no_such_mod"))), Straight(), 0)
    for name, message in [("TooFew", r"'cart_controller:TooFew' returned 1 controls \(the model has 2"),
                          ("Raises", "raised RuntimeError: motor driver offline"),
                          ("ReturnsText", r"'cart_controller:ReturnsText' returned 'full ahead' \(a str\)")]:
        res = simulate(load_scenario(write(tmp_path, CART_BODY.replace("Cart", name))), Straight(), 0)
        assert res.end == "subject-error"                 # a subject error of its episode, as a planner's
        assert re.search(message, res.subject_failure.message)
    assert "motor driver offline" in simulate(load_scenario(write(tmp_path, CART_BODY.replace("Cart", "Raises"))),
                                              Straight(), 0).subject_failure.traceback


def test_a_controller_calling_sys_exit_ends_its_episode_not_the_run(tmp_path):
    res = simulate(load_scenario(write(tmp_path, CART_BODY.replace("Cart", "Exits"))), Straight(), 0)
    assert res.end == "subject-error"
    assert "'cart_controller:Exits' raised SystemExit: 3" in res.subject_failure.message
    res = simulate(load_scenario(write(tmp_path, CART_BODY.replace("Cart", "Interrupts"))), Straight(), 0)
    assert "raised KeyboardInterrupt: my own" in res.subject_failure.message


@pytest.mark.parametrize("spec,why", [
    ("os:fork", "not a class or function"), ("os:abort", "not a class or function"),
    ("signal:pause", "not a class or function"), ("cart_controller:fork", "not a class or function"),
    ("shutil:rmtree", "the standard library, an installed package"),
    ("cart_controller:rmtree", "the standard library, an installed package"),
    ("subprocess:Popen", "the standard library, an installed package"),
    ("numpy:ndarray", "not a class or function"),   # a C class: not Python code of the user's
    ("pytest:main", "the standard library, an installed package")])
def test_a_controller_must_be_a_class_or_function_of_the_users_own_code(tmp_path, spec, why):
    path = write(tmp_path, CART_BODY.replace("cart_controller:Cart", spec))
    with pytest.raises(ScenarioError) as err:
        simulate(load_scenario(path), Straight(), 0)
    assert err.value.field == "robot.body.controller" and err.value.line == 6
    assert why in str(err.value) or "is defined in" in str(err.value)
    assert "fix: name a class or function of your own module" in str(err.value)


def test_a_factory_function_of_the_users_module_is_a_controller(tmp_path):
    res = simulate(load_scenario(write(tmp_path, CART_BODY.replace("Cart", "make_cart"), RAMP)), Straight(), 0)
    assert res.end == "goal"


def test_a_controller_that_sleeps_is_bounded_by_the_tick_limit(tmp_path):
    t0 = time.monotonic()
    res = simulate(load_scenario(write(tmp_path, CART_BODY.replace("Cart", "Sleeps"))), Straight(), 0, tick_limit=0.2)
    assert time.monotonic() - t0 < 10
    assert res.end == "subject-error"
    assert "per-tick limit of 0.2 s" in res.subject_failure.message and "control()" in res.subject_failure.message


def test_mujocos_fatal_error_ends_the_episode_with_the_cause_and_the_size_memory_that_fixes_it(tmp_path):
    # an arena too small for the model's contacts (as a 20000-body robot overflows the default one:
    # mj_stackAlloc in mj_step1): a SimulationFatalError, not a raw mujoco.FatalError traceback
    from pytest_navscenario.core.errors import SimulationFatalError

    path = write(tmp_path, CART_BODY)
    small = CART.read_text().replace('<mujoco model="cart">', '<mujoco model="cart"><size memory="2K"/>')
    (tmp_path / "cart.xml").write_text(small)
    with pytest.raises(SimulationFatalError) as err:
        simulate(load_scenario(path), Straight(), 0)
    text = str(err.value)
    assert f"MuJoCo stopped scenario scene ({path}) at t=0.000 s" in text
    assert "needs more memory than MuJoCo's arena of 2 KB: mj_stackAlloc: out of memory" in text
    assert text.endswith('(fix: add <size memory="1M"/> to the robot\'s MJCF file cart.xml (robot.body.file), '
                         'or simplify it)')
    (tmp_path / "cart.xml").write_text(small.replace('"2K"', '"1M"'))     # the fix it gives works
    assert simulate(load_scenario(path), Straight(), 0).end == "goal"


def test_the_robots_geoms_are_hidden_from_the_lidar_and_the_model_saves(tmp_path):
    from pytest_navscenario.sim.body_world import compiled_body_world, model_xml
    from pytest_navscenario.sim.bodies.base import ROBOT_GROUP

    sc = load_scenario(write(tmp_path, CART_BODY, RAMP))
    world = compiled_body_world(sc)
    assert {int(world.model.geom_group[g]) for g in world.body.robot_geoms} == {ROBOT_GROUP}
    assert world.body.ground_offset == pytest.approx(0.2)             # its base 0.2 m above its wheels' contact
    res = simulate(sc, Straight(), 0, max_ticks=5)
    assert np.all(res.trajectory.ranges[0] > 1.0)                       # it does not see itself
    xml = model_xml(sc)
    assert '<body name="chassis"' in xml and 'name="left"' in xml        # the user's names, kept


def test_a_frozen_failure_carries_its_robot_and_the_files_it_names(tmp_path):
    """A failure frozen away from its seed (navsearch's output folder) has the MJCF robot and its
    mesh copied beside it, loads, and runs."""
    from pytest_navscenario.search.freeze import save_standalone, standalone_scenario

    seed_dir = tmp_path / "seeds"
    (seed_dir / "robot" / "parts").mkdir(parents=True)
    mesh = Path(__file__).parents[2] / "scenarios" / "meshes" / "lathe.stl"
    shutil.copy(mesh, seed_dir / "robot" / "parts" / "mast.stl")
    (seed_dir / "robot" / "cart.xml").write_text(CART.read_text().replace(
        "<default>", '<compiler meshdir="parts"/>\n  <asset><mesh name="mast" file="mast.stl" scale="0.01 0.01 0.01"/>'
                     '</asset>\n  <default>', 1).replace(
        '<geom name="mast" type="cylinder" size="0.03 0.15" pos="0 0 0.25"',
        '<geom name="mast" type="mesh" mesh="mast" pos="0 0 0.15"'))
    seed = load_scenario(write(seed_dir, CART_BODY.replace("cart.xml", "robot/cart.xml"), RAMP))
    frozen = standalone_scenario(seed, seed, name="frozen-1", description="a frozen failure", provenance={})
    out = tmp_path / "navsearch" / "seed" / "frozen-1.yaml"
    save_standalone(frozen, seed, out)
    again = load_scenario(out)
    assert again.robot.body.file.startswith("bodies/cart-") and again.robot.body.digest == seed.robot.body.digest
    copied = out.parent / again.robot.body.file
    assert copied.is_file() and (copied.parent / "parts" / "mast.stl").is_file()
    assert simulate(again, Straight(), 0, max_ticks=3).ticks == 3


def menagerie_style(folder: Path) -> None:
    """The cart as MuJoCo Menagerie writes its robots (the Clearpath Jackal's jackal.xml, for one):
    every geom contype 0, conaffinity 1 (no self-collisions; the scene's floor, default bits, meets
    them), options of its own and a model name that is also the scenario's."""
    text = CART.read_text().replace('<mujoco model="cart">', '<mujoco model="scene">\n  <option timestep="0.005" '
                                     'iterations="5" integrator="Euler"/>')
    text = text.replace('<geom name="body"', '<geom contype="0" conaffinity="1" name="body"')
    text = text.replace('<geom type="sphere"', '<geom contype="0" conaffinity="1" type="sphere"')
    text = text.replace('mass="1"/>', 'mass="1" contype="0" conaffinity="1"/>')
    (folder / "cart.xml").write_text(text)


def test_a_menagerie_style_robot_whose_geoms_have_contype_0_rides_the_terrain_and_meets_obstacles(tmp_path, capfd):
    path = write(tmp_path, CART_BODY, RAMP)
    menagerie_style(tmp_path)
    res = simulate(load_scenario(path), Straight(), 0)
    assert res.end == "goal" and res.trajectory.z[-1] == pytest.approx(0.53, abs=0.01)   # up the ramp, not through it
    path = write(tmp_path, CART_BODY, obstacles="obstacles:\n  - {type: box, name: crate, x: 5, y: 0.2, "
                                                "length: 0.4, width: 0.1, height: 0.15}")
    menagerie_style(tmp_path)
    res = simulate(load_scenario(path), Straight(), 0)
    assert res.end == "collision" and res.collision.obstacle == "crate"
    out, err = capfd.readouterr()
    assert "conflict" not in out + err and "parent has" not in out + err   # its options and name: no noise


def test_a_robot_using_a_name_of_the_worlds_own_or_of_an_obstacle_is_an_error_at_its_file(tmp_path):
    # was "MuJoCo could not build the model: Error: repeated name 'floor' in body", no field or line
    path = write(tmp_path, CART_BODY)
    (tmp_path / "cart.xml").write_text(CART.read_text().replace('<body name="front_caster"', '<body name="floor"'))
    with pytest.raises(ScenarioError) as err:
        simulate(load_scenario(path), Straight(), 0)
    assert err.value.field == "robot.body.file" and err.value.line == 6
    assert f"{tmp_path / 'cart.xml'} has a body named 'floor', a name the scenario's world already gives its " \
           f"own floor" in str(err.value)
    assert err.value.hint == "rename the body 'floor' in the MJCF file, and where your controller names it"
    shutil.copy(CART, tmp_path / "cart.xml")          # the cart's chassis geom is named 'body'
    crate = write(tmp_path, CART_BODY, obstacles="obstacles:\n  - {type: box, name: body, x: 5, y: 3, "
                                                 "length: 0.4, width: 0.4}")
    with pytest.raises(ScenarioError) as err:
        simulate(load_scenario(crate), Straight(), 0)
    assert err.value.field == "robot.body.file" and "has a geom named 'body', a name the scenario's world " \
                                                     "already gives obstacle 'body' (obstacles[0])" in str(err.value)
    assert err.value.hint == "rename obstacles[0] in the scenario, or the geom in the MJCF file"


def test_a_cart_held_still_on_a_flat_floor_did_not_move_and_is_not_stuck_on_terrain(tmp_path):
    """Issue 36.2a: its wheels and casters touch the floor, its chassis is 0.1 m up: only the
    chassis (the base's own geoms) can be high-centred, and on a flat floor the terrain holds
    nothing: the robot did not move (a timeout that says so), not "stuck on terrain"."""
    from pytest_navscenario.harness.runner import run_scenario
    held = load_scenario(write(tmp_path, '{type: mjcf, file: cart.xml, controller: "cart_controller:HoldsStill"}'))
    res = run_scenario(held, Straight())
    assert res.outcome.value == "timeout"
    assert "high-centred" not in res.message and "stuck on terrain" not in res.message, res.message
    assert "did not move" in res.message and re.search(r"at \(-?0.00, -?0.00\)", res.message), res.message
    flat = run_scenario(load_scenario(write(tmp_path, CART_BODY)), Straight())
    assert flat.outcome.value == "success", flat.message


def test_a_chassis_resting_on_a_sill_is_high_centred(tmp_path):
    """The other side of the rule: a cart whose chassis (0.1 m up) rests on a 0.15 m bar between
    its wheels is high-centred on it, whatever its wheels touch."""
    from pytest_navscenario.harness.runner import run_scenario
    sill = write(tmp_path, CART_BODY, "terrain:\n  - {type: platform, name: sill, x: 0.0, y: 0, "
                                      "length: 0.3, width: 0.3, height: 0.13}")
    res = run_scenario(load_scenario(sill), Straight())
    assert "high-centred" in res.message and "sill" in res.message, res.message


def test_a_chassis_in_a_body_fixed_to_the_base_is_the_chassis_too(tmp_path):
    """A model whose base holds no geom and whose chassis box hangs on a child body without a joint
    (a common MJCF layout): that box is the chassis; the wheels on their hinges are not."""
    from pytest_navscenario.harness.runner import run_scenario
    sill = write(tmp_path, CART_BODY, "terrain:\n  - {type: platform, name: sill, x: 0.0, y: 0, "
                                      "length: 0.3, width: 0.3, height: 0.13}")
    xml = (tmp_path / "cart.xml").read_text()
    box = '<geom name="body" type="box" size="0.45 0.25 0.1" mass="20" rgba="0.8 0.5 0.1 1"/>'
    assert box in xml
    (tmp_path / "cart.xml").write_text(xml.replace(box, f'<body name="deck">{box}</body>'))
    res = run_scenario(load_scenario(sill), Straight())
    assert "high-centred" in res.message and "sill" in res.message, res.message
    held = write(tmp_path, '{type: mjcf, file: cart.xml, controller: "cart_controller:HoldsStill"}')
    (tmp_path / "cart.xml").write_text(xml.replace(box, f'<body name="deck">{box}</body>'))
    assert "did not move" in run_scenario(load_scenario(held), Straight()).message
