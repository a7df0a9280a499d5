"""Issue 17: at the end of ``navscenario from-bag`` the seed's picture beside the recorded path is
written next to the seed and its path printed, unless ``--no-plot``."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "ros"))
from ros_synthetic import World, robot_bag  # noqa: E402

from pytest_navscenario.cli import main  # noqa: E402
from pytest_navscenario.scenario.loader import load_scenario  # noqa: E402

WORLD = World(pillars=[(1.5, -0.8, 0.2, 1.0), (4.0, 4.0, 0.3, 1.0)])


def _bag(tmp_path):
    t = np.arange(60) * 0.1
    return robot_bag(tmp_path / "b", WORLD, np.stack([t, -1.0 + 0.6 * t, 0 * t, 0 * t], 1))


def test_the_picture_is_written_beside_the_seed_and_named(tmp_path, capsys):
    out = tmp_path / "seed.yaml"
    assert main(["from-bag", str(_bag(tmp_path)), "-o", str(out)]) == 0
    png = tmp_path / "seed.png"
    assert f"navscenario from-bag: the seed beside the recorded path: {png}" in capsys.readouterr().out
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    assert width > 1.5 * height and height > 300   # two panels side by side


def test_no_plot_writes_no_picture(tmp_path, capsys):
    out = tmp_path / "seed.yaml"
    assert main(["from-bag", str(_bag(tmp_path)), "-o", str(out), "--no-plot"]) == 0
    assert out.exists() and not (tmp_path / "seed.png").exists()
    assert "beside the recorded path" not in capsys.readouterr().out


def test_the_figure_shows_the_fixed_background_and_every_recorded_pose(tmp_path):
    from pytest_navscenario.report.seed_plot import seed_figure
    from pytest_navscenario.ros.bag_import import scenario_from_bag

    seed = scenario_from_bag(_bag(tmp_path))
    fig = seed_figure(seed.scenario, seed.path)
    left, right = fig.axes[0], fig.axes[1]
    hatched = [c for c in left.collections if c.get_label() == "fixed background (search: frozen)"]
    assert len(hatched) == 1 and len(hatched[0].get_paths()) == len(seed.scenario.search["frozen"]) == 1
    assert left.get_title() == "seed: 1 searchable, 1 fixed obstacles"
    poses = [c for c in right.collections if len(c.get_offsets()) == len(seed.path)]
    assert len(poses) == 1 and np.allclose(poses[0].get_offsets(), seed.path[:, 1:3])
    assert left.get_xlim() == right.get_xlim()   # the same window: side by side compares


def test_the_seed_loads_after_the_plot(tmp_path):
    out = tmp_path / "seed.yaml"
    assert main(["from-bag", str(_bag(tmp_path)), "-o", str(out)]) == 0
    assert load_scenario(out).search == {"frozen": ["pillar2"]}
