"""Issue 32 item 5: pictures a person reads. The side profile's angle axis in plain degrees (no
matplotlib offset text) with roll beside pitch, so that a tip-over by roll shows; at least three y
ticks on a wide, low map; legend entries inside the figure; the fall or tip-over marker not under
an "end" square; terrain names placed clear of the other labels and markers. Real episodes: a
robot that tips over the loading dock's edge (found by the search: tests/data/dock-tip.yaml) and
the ramp-levels seed."""
from __future__ import annotations

import math
from itertools import combinations
from pathlib import Path

import pytest

from pytest_navscenario import load_scenario, run_scenario
from pytest_navscenario.report.labels import text_boxes
from pytest_navscenario.report.plots import trajectory_figure

HERE = Path(__file__).resolve().parents[1]
SEEDS = HERE.parent / "scenarios"


@pytest.fixture(scope="module")
def dock():
    result = run_scenario(load_scenario(HERE / "data" / "dock-tip.yaml"), "dwa")
    fig = trajectory_figure(result)
    fig.canvas.draw()
    return result, fig


@pytest.fixture(scope="module")
def ramp():
    result = run_scenario(load_scenario(SEEDS / "ramp-levels.yaml"), "dwa")
    fig = trajectory_figure(result)
    fig.canvas.draw()
    return result, fig


def _map(fig):
    (ax,) = [ax for ax in fig.axes if ax.get_xlabel() == "x (m)"]
    return ax


def _angles(fig):
    (twin,) = [ax for ax in fig.axes if "roll" in ax.get_ylabel()]
    return twin


def test_the_profile_shows_roll_in_plain_degrees(dock):
    result, fig = dock
    twin = _angles(fig)
    assert twin.yaxis.get_offset_text().get_text() == ""
    (roll,) = [line for line in twin.get_lines() if line.get_label() == "roll"]
    assert max(abs(v) for v in roll.get_ydata()) == pytest.approx(result.metrics.max_roll, abs=0.5)
    assert result.metrics.max_roll > 30          # the robot rolls over the edge: the profile shows it
    lo, hi = twin.get_ylim()
    assert lo <= -5 and hi >= max(5.0, result.metrics.max_roll)


def test_a_wide_map_has_y_ticks(ramp):
    _, fig = ramp
    ax = _map(fig)
    lo, hi = ax.get_ylim()
    assert len([t for t in ax.get_yticks() if lo <= t <= hi]) >= 3


@pytest.mark.parametrize("which", ["dock", "ramp"])
def test_legend_entries_stay_inside_the_figure(which, request):
    _, fig = request.getfixturevalue(which)
    renderer = fig.canvas.get_renderer()
    width = fig.bbox.width
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    assert len(legends) == 2                     # the map's, right of it; the profile's, right of it
    for legend in legends:
        for text in legend.get_texts():
            assert text.get_window_extent(renderer).x1 <= width, text.get_text()


def test_the_event_marker_is_not_under_an_end_square(dock):
    result, fig = dock
    event = result.terrain_event
    assert event is not None
    squares = [line for line in _map(fig).get_lines() if line.get_marker() == "s"
               and any(math.hypot(x - event.x, y - event.y) < 0.5 for x, y in line.get_xydata())]
    assert squares == []


@pytest.mark.parametrize("which", ["dock", "ramp"])
def test_no_label_covers_another(which, request):
    _, fig = request.getfixturevalue(which)
    boxes = text_boxes(_map(fig))
    for (ta, a), (tb, b) in combinations(boxes, 2):
        w = min(a[2], b[2]) - max(a[0], b[0])
        h = min(a[3], b[3]) - max(a[1], b[1])
        assert not (w > 1 and h > 1), f"{ta!r} over {tb!r}"


STAIRS = """version: 1
name: stairs
robot:
  drive: diff
  body: {type: legged, max_step: 0.2, max_slope: 30, max_gap: 0.3}
  lidar: {mount_height: 1.0}
mission: {start: {x: 0, y: 0}, goal: {x: 9, y: 0}, timeout: 30}
terrain:
  - {type: steps, name: stairs, x: 5, y: 0, count: 5, rise: 0.17, run: 0.3, width: 2}
  - {type: platform, name: landing, x: 8.75, y: 0, length: 6, width: 8, height: 0.85}
"""


def test_a_terrain_name_is_not_written_over_the_goal():
    """The tutorial's stairs: "platform 'landing'" was written at the landing's centre, over the goal."""
    from pytest_navscenario import loads_scenario

    result = run_scenario(loads_scenario(STAIRS), "dwa")
    fig = trajectory_figure(result)
    fig.canvas.draw()
    ax = _map(fig)
    gx, gy = ax.transData.transform((9.0, 0.0))
    (box,) = [b for text, b in text_boxes(ax) if text == "platform 'landing'"]
    assert not (box[0] - 8 <= gx <= box[2] + 8 and box[1] - 8 <= gy <= box[3] + 8), box   # the star: 9 px


def test_the_time_slider_view_has_names_axes_and_a_scale(dock, tmp_path):
    """The HTML viewer had no axes, scale or names: the view now carries the obstacles' and the
    terrain elements' names and the roll, and report.js draws ticks in metres and a scale bar
    (looked at in headless chromium; here: the data and the drawing code the page carries)."""
    from pytest_navscenario.report.html import Entry, view_data, write_html
    from pytest_navscenario.report.results_file import make_record

    result, _ = dock
    view = view_data(result)
    assert view["on"] == ["pallet_a", "pallet_b"] and view["tn"] == ["platform 'dock'"]
    assert len(view["roll"]) == len(view["t"])
    record = make_record(result, nodeid="dock.yaml::dock", path="dock.yaml")
    out = tmp_path / "r.html"
    write_html(out, [Entry(record=record, view=view)], title="t")
    page = out.read_text()
    assert "function axes()" in page and "function scale()" in page and "x, y (m)" in page


def test_the_clearance_that_explains_a_stop_is_named(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch):
    """person-crossing (a frozen failure of its search, tests/data/person-stop.yaml): the safety
    stop is for the walker, the minimum clearance is to a wall; before, only the wall's was given."""
    import shutil

    from pytest_navscenario.verdict.metrics import culprit_clearance

    result = run_scenario(load_scenario(HERE / "data" / "person-stop.yaml"), "dwa")
    assert result.safety_stop.obstacle == "walker" and result.metrics.min_clearance_obstacle.startswith("wall")
    name, dist, _ = culprit_clearance(result)
    assert name == "walker" and 0 < dist < 1.0
    fig = trajectory_figure(result)
    texts = [t for t, _ in text_boxes(_map(fig))]
    assert any(t.startswith(f"clearance to walker {dist:.2f} m") for t in texts), texts
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    shutil.copy(HERE / "data" / "person-stop.yaml", pytester.path / "person-stop.yaml")
    out = pytester.runpytest("-p", "pytest_navscenario.plugin", "person-stop.yaml", "--nav-subject=dwa",
                             "--nav-plots=none").stdout.str()
    assert f"  clearance to 'walker': {dist:.3f} m at t=" in out and "(the safety stop was for it;" in out, out
