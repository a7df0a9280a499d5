"""The warp batch engine (sim/batching/warp_engine.py, warp_worlds.py, warp_loop.py): a batch's episodes as
the worlds of MuJoCo Warp models, run here on Warp's CPU kernels, agree with the CPU engine within
harness.agreement.AGREE (same outcomes, positions and headings close at every physics step) for
every feature it claims: static obstacles of every kind, several layouts in one device model,
moving obstacles, lidar noise, sensor faults, collisions; and it refuses what it does not simulate,
which then runs alone on the CPU with the reason in the batching line (issue 27).

The tests that run MuJoCo Warp are heavy (its kernels load in seconds on the CPU, compile in about
a minute and a half the first time) and are skipped, with the reason, when the optional extra
pytest-navscenario[gpu] is not installed."""
from __future__ import annotations

import dataclasses
import os

import pytest

from pytest_navscenario.harness.agreement import AGREE, Tolerance, compare
from pytest_navscenario.harness.batch import Batching, run_batch
from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.scenario.model import BoxObstacle, Mission, Pose, Robot, Scenario
from pytest_navscenario.scenario.terrain import Lidar3D, Ramp, WheeledBody
from pytest_navscenario.sim.batching.batch import BatchEpisode, batch_engine, simulate_batch
from pytest_navscenario.sim.batching.warp_engine import WarpEngine, missing
from pytest_navscenario.subjects.protocol import Command

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
NEEDS_WARP = pytest.mark.skipif(missing() is not None, reason=f"the warp engine's extra is missing: {missing()}")


def seed(name: str) -> Scenario:
    return load_scenario(os.path.join(ROOT, "scenarios", f"{name}.yaml"))


def planar() -> Scenario:
    return Scenario(mission=Mission(start=Pose(0.0, 0.0, 0.0), goal=Pose(4.0, 0.0), timeout=6.0),
                    obstacles=(BoxObstacle(name="wall", x=2.0, y=0.0, length=0.4, width=2.0),))


# ---------------------------------------------------------------- without MuJoCo Warp

def test_warp_engine_refuses_terrain_riding_bodies_and_3d_lidars_and_says_why():
    engine = WarpEngine()
    base = planar()
    assert engine.unsupported(base) is None
    wheeled = dataclasses.replace(base, robot=Robot(drive="diff", body=WheeledBody(clearance=0.1)))
    assert "rides the ground" in engine.unsupported(wheeled)
    ramp = dataclasses.replace(base, terrain=(Ramp(name="ramp", x=1.0, y=0.0, length=1.0, width=1.0, rise=0.1),))
    assert "terrain" in engine.unsupported(ramp)
    cloud = dataclasses.replace(base, robot=dataclasses.replace(base.robot, lidar3d=Lidar3D()))
    assert "3D lidar" in engine.unsupported(cloud)


def test_an_unknown_batch_engine_lists_the_known_ones():
    with pytest.raises(ValueError, match="unknown batch engine 'gpu'; available: cpu, warp"):
        batch_engine("gpu")


def test_the_warp_engine_without_its_extra_says_how_to_install_it(monkeypatch):
    import importlib.util

    from pytest_navscenario.sim.batching import batch as batch_module

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "mujoco_warp" else real(name, *a))
    monkeypatch.setattr(batch_module, "_ENGINES", {})
    with pytest.raises(ValueError, match=r"mujoco-warp not installed: pip install \"pytest-navscenario\[gpu\]\""):
        batch_engine("warp")


# ---------------------------------------------------------------- on Warp's CPU kernels

class Straight:
    """A batch planner that drives every robot straight ahead at 1 m/s."""

    def reset_batch(self, scenarios):
        pass

    def act_batch(self, ids, observations):
        return [Command(1.0, 0.0, 0.0)] * len(ids)


def both(requests, planner_factory):
    """The CPU engine's and the warp engine's results of the same requests."""
    cpu = simulate_batch(requests, planner_factory(), batch_engine("cpu"))
    warp = simulate_batch(requests, planner_factory(), WarpEngine("cpu"))
    return cpu, warp


def dwa():
    from pytest_navscenario.harness.batch import batch_planner_of
    from pytest_navscenario.subjects.loading import make_planner
    return batch_planner_of(make_planner("dwa")[0])


def assert_agree(cpu, warp, names, tol: Tolerance = AGREE):
    for name, a, b in zip(names, cpu, warp):
        assert not isinstance(a, Exception), f"{name}: {a!r}"
        assert not isinstance(b, Exception), f"{name}: {b!r}"
        agreement = compare(a, b, name)
        assert agreement.within(tol), agreement.describe()
        assert (a.end, a.ticks) == (b.end, b.ticks) or a.end == b.end, agreement.describe()


@pytest.mark.heavy
@NEEDS_WARP
def test_shipped_seeds_agree_with_the_cpu_engine_for_every_obstacle_kind():
    # boxes1 and boxes2 share one device model (their boxes stand elsewhere: per-world fields);
    # cylinders, polygons and meshes (convex parts collide, the prism is what the lidar sees),
    # glass the lidar does not see, moving people
    names = ["boxes1", "boxes2", "cylinders", "workshop-irregular", "glass-door", "person-crossing"]
    requests = [BatchEpisode(seed(n), seed(n).simulation.seed, max_ticks=25) for n in names]
    cpu, warp = both(requests, dwa)
    assert_agree(cpu, warp, names)
    for a, b in zip(cpu, warp):        # what the planner saw: the same scans, up to single precision
        assert abs(a.trajectory.ranges - b.trajectory.ranges).max() < 1e-3


@pytest.mark.heavy
@NEEDS_WARP
def test_a_collision_ends_the_episode_at_the_same_step_with_the_same_obstacle():
    sc = planar()
    sc = dataclasses.replace(sc, robot=dataclasses.replace(sc.robot, safety=dataclasses.replace(sc.robot.safety, enabled=False)))
    cpu, warp = both([BatchEpisode(sc, 0), BatchEpisode(dataclasses.replace(sc, name="other"), 1)], Straight)
    for a, b in zip(cpu, warp):
        assert a.end == b.end == "collision"
        assert b.collision.obstacle == a.collision.obstacle == "wall"
        assert abs(b.collision.time - a.collision.time) <= 2 * sc.simulation.timestep
        assert abs(b.collision.x - a.collision.x) < 0.02
    assert_agree(cpu, warp, ["wall", "wall again"])


@pytest.mark.heavy
@NEEDS_WARP
def test_lidar_noise_and_sensor_faults_run_on_the_host_with_the_episode_seed():
    sc = seed("boxes1")
    robot = sc.robot
    noisy = dataclasses.replace(sc, robot=dataclasses.replace(
        robot, lidar=dataclasses.replace(robot.lidar, noise_sigma=0.02, dropout=0.05),
        latency=dataclasses.replace(robot.latency, command=0.1)))
    requests = [BatchEpisode(noisy, s, max_ticks=20) for s in (3, 4)]
    cpu, warp = both(requests, dwa)
    assert_agree(cpu, warp, ["noisy 3", "noisy 4"])
    for a, b in zip(cpu, warp):     # the same draws: dropouts where the CPU has them
        assert ((a.trajectory.ranges == robot.lidar.range_max) == (b.trajectory.ranges == robot.lidar.range_max)).mean() > 0.99
        assert abs(a.trajectory.ranges - b.trajectory.ranges).max() < 1e-3
    assert (cpu[0].trajectory.ranges != cpu[1].trajectory.ranges).any()


@pytest.mark.heavy
@NEEDS_WARP
def test_run_batch_on_the_warp_engine_runs_alone_what_it_refuses_and_says_why():
    wheeled = Scenario(mission=Mission(start=Pose(0.0, 0.0, 0.0), goal=Pose(3.0, 0.0), timeout=3.0),
                       robot=Robot(drive="diff", body=WheeledBody(clearance=0.1)))
    batching = Batching()
    results = run_batch([planar(), wheeled, planar()], Straight, batching=batching, engine=WarpEngine("cpu"),
                        seeds=[0, 0, 0])
    assert [type(r).__name__ for r in results] == ["EpisodeResult"] * 3
    assert (batching.batched, batching.batches, batching.alone) == (2, 1, 1)
    assert "rides the ground, which the warp engine does not simulate" in batching.describe()


# ---------------------------------------------------------------- the options that choose it

def test_nav_batch_engine_accepts_cpu_and_warp_only(pytester):
    pytester.makefile(".yaml", boxes="version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1, y: 0}, timeout: 5}\n")
    result = pytester.runpytest("--nav-batch-engine=gpu", "-p", "no:cacheprovider")
    result.stderr.fnmatch_lines(["*--nav-batch-engine*expected cpu or warp, got 'gpu' (e.g. --nav-batch-engine=warp)*"])
    assert result.ret != 0


def test_a_serial_suite_says_that_it_did_not_use_the_batch_options_it_was_given(pytester):
    # a serial suite runs its items one at a time: --nav-batch-engine warp (or --nav-batch 4) had no
    # effect, and nothing said so
    pytester.makefile(".yaml", boxes="version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1, y: 0}, timeout: 5}\n")
    used = "*navscenario: --nav-batch 4 not used: a suite without workers runs its items one at a time, each " \
           "on the CPU (batches need -n N, --nav-workers N, --nav-ray or --nav-isolate)*"
    result = pytester.runpytest("--nav-batch=4", "-p", "no:cacheprovider")
    result.stdout.fnmatch_lines([used])
    assert "not used" not in pytester.runpytest("-p", "no:cacheprovider").stdout.str()
    assert "not used" not in pytester.runpytest("--nav-batch=off", "-p", "no:cacheprovider").stdout.str()
    if missing() is None:
        result = pytester.runpytest("--nav-batch-engine=warp", "-p", "no:cacheprovider")
        result.stdout.fnmatch_lines([used.replace("--nav-batch 4", "--nav-batch-engine warp")])


def test_navscenario_run_with_an_unknown_or_missing_engine_says_so(capsys, monkeypatch):
    from pytest_navscenario import cli

    files = [os.path.join(ROOT, "scenarios", f"{n}.yaml") for n in ("boxes1", "boxes2")]
    with pytest.raises(SystemExit):
        cli.main(["run", *files, "--batch-engine", "gpu"])
    assert "invalid choice: 'gpu'" in capsys.readouterr().err
    from pytest_navscenario.sim.batching import batch as batch_module
    from pytest_navscenario.sim.batching import warp_engine

    monkeypatch.setattr(batch_module, "_ENGINES", {})
    monkeypatch.setattr(warp_engine, "missing", lambda: "mujoco-warp not installed: " + warp_engine.INSTALL_HINT)
    assert cli.main(["run", *files, "--batch-engine", "warp"]) == 2
    assert "--batch-engine warp: the warp batch engine cannot run: mujoco-warp not installed" in capsys.readouterr().err
    # one file too: it ran on the CPU without a word, whatever --batch-engine said
    assert cli.main(["run", files[0], "--batch-engine", "warp"]) == 2
    assert "--batch-engine warp: the warp batch engine cannot run: mujoco-warp not installed" in capsys.readouterr().err


@pytest.mark.heavy
@NEEDS_WARP
def test_navscenario_run_on_the_warp_engine_gives_the_cpu_outcomes(capsys):
    from pytest_navscenario import cli

    files = [os.path.join(ROOT, "scenarios", f"{n}.yaml") for n in ("boxes1", "boxes2")]
    assert cli.main(["run", *files, "--seed", "0", "--batch-engine", "warp"]) == 0
    out = capsys.readouterr().out
    assert out.count("outcome: success") == 2
    assert out.rstrip().endswith("2 scenario(s): 2 passed, 0 failed; batches (--batch auto, --batch-engine warp): "
                                 "2 episode(s) in 1 batch(es)")
    assert cli.main(["run", files[0], "--seed", "0", "--batch-engine", "warp"]) == 0
    assert capsys.readouterr().out.rstrip().endswith("1 scenario(s): 1 passed, 0 failed; batches (--batch auto, "
                                                     "--batch-engine warp): 1 episode(s) in 1 batch(es)")
