"""Pictures on terrain: the map shaded by the ground's height (with a height scale), the elements
named, where the robot fell marked; a side profile of the route under the map (the ground under it,
the base's height, its pitch); the HTML time-slider carries the shading, the outlines, height and
pitch; a flat scenario's pictures are as before (no profile, the same size)."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.report.html import view_data
from pytest_navscenario.report.plots import comparison_figure, trajectory_figure
from pytest_navscenario.report.terrain_plot import route_profile
from pytest_navscenario.scenario.loader import loads_scenario

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "sim"))
from test_sensors_riding import PIT, RAMP, Straight  # noqa: E402


@pytest.fixture(scope="module")
def runs():
    fall = run_scenario(loads_scenario(PIT.replace("LIDAR3D", "")), Straight())
    stop = run_scenario(loads_scenario(PIT.replace("LIDAR3D", "lidar3d: {}")), Straight())
    ramp = run_scenario(loads_scenario(RAMP), Straight(speed=0.5))
    flat = run_scenario(loads_scenario("version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 3, y: 0}}\n"), "dwa")
    return fall, stop, ramp, flat


def _scales(fig):
    """The height scales: insets of the map panels."""
    return [c for ax in fig.axes for c in ax.child_axes if c.get_ylabel() == "ground (m)"]


def _texts(fig):
    return [t.get_text() for ax in fig.axes for t in ax.texts] + \
           [t.get_text() for leg in fig.legends for t in leg.get_texts()]


def test_a_fall_on_the_map_and_in_the_profile(runs):
    fall, _, _, flat = runs
    fig = trajectory_figure(fall)
    labels = " | ".join(_texts(fig))
    # the time of the fall is the episode's (6.6 s under MuJoCo 4.0.0, 6.7 s under 4.0.1): the label
    # carries it, whatever the patch release
    assert fall.terrain_event.time == pytest.approx(6.6, abs=0.3)
    assert "pit 'hole'" in labels and f"fell into pit 'hole' t={fall.terrain_event.time:.1f} s, 1.00 m drop" in labels
    maps = [ax for ax in fig.axes if ax.get_xlabel() == "x (m)"]
    assert len(maps) == 1 and len(maps[0].images) == 1                  # the height shading
    assert len(_scales(fig)) == 1                                       # its scale
    profile = [ax for ax in fig.axes if ax.get_xlabel() == "distance driven (m)"]
    assert len(profile) == 1
    plain = trajectory_figure(flat)
    assert not any(ax.get_xlabel() == "distance driven (m)" for ax in plain.axes)
    assert fig.get_size_inches()[1] > plain.get_size_inches()[1]       # the profile's room


def test_the_profile_reads_the_route(runs):
    fall, _, ramp, _ = runs
    prof = route_profile(ramp)
    up = prof["s"] > 3.0
    # on the 10 degree ramp the base climbs with the ground, nose up
    assert np.all(np.abs(prof["z"][up & (prof["s"] < 5.0)] - prof["ground"][up & (prof["s"] < 5.0)]) < 0.05)
    assert np.median(prof["pitch"][up & (prof["s"] < 5.0)]) > 9.0
    end = route_profile(fall)
    assert end["z"][-1] < -0.1 and end["ground"][-1] == pytest.approx(-1.0)   # over the pit, falling


def test_side_by_side_shares_the_profile(runs):
    fall, stop, _, _ = runs
    fig = comparison_figure(fall, stop, labels=("2D", "3D"))
    (profile,) = [ax for ax in fig.axes if ax.get_xlabel() == "distance driven (m)"]
    names = [t.get_text() for t in profile.get_legend().get_texts()]
    assert "2D: base height" in names and "3D: base height" in names and "2D: fell" in names
    assert len(_scales(fig)) == 1                                        # one height scale


def test_the_time_slider_carries_the_terrain(runs):
    fall, _, _, flat = runs
    view = view_data(fall)
    assert view["gnd"]["png"].startswith("data:image/png;base64,") and len(view["ter"]) == 1
    assert len(view["z"]) == len(view["pitch"]) == len(view["t"])
    assert view["ev"]["kind"] == "fell"
    assert not {"gnd", "ter", "z", "pitch", "ev"} & set(view_data(flat))
