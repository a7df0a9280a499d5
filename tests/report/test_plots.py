"""plots.py: each picture is produced, has the expected size and is not blank.

The episodes here are built by hand (a known trajectory through a known layout), so the tests
check the drawing alone and run in well under a second each; the pictures from real MuJoCo
episodes are made by benchmarks/make_pictures.py and checked by looking at them.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from pytest_navscenario.sim.trajectory import Collision, SafetyStop, Trajectory
from pytest_navscenario.verdict.result import EpisodeResult, Metrics, Outcome
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle, Mission, Pose, Scenario


def make_episode(outcome: str = "collision", *, subject: str = "dwa", bend: float = 0.6,
                 name: str = "boxes1", family: str = "seeds") -> EpisodeResult:
    """A 10 m run through a 2 m gap between two boxes, bending by ``bend`` m, 8 s long."""
    scenario = Scenario(
        mission=Mission(start=Pose(0, 0, 90), goal=Pose(0, 10, 90), waypoints=(Pose(0.5, 3),)),
        obstacles=(BoxObstacle("box_left", -1.5, 5, 1, 1), BoxObstacle("box_right", 1.5, 5, 1, 1),
                   CylinderObstacle("pillar", 0.8, 7.5, 0.3)),
        name=name, family=family)
    t = np.linspace(0.0, 8.0, 801)
    y = 10 * t / 8 * (1.0 if outcome == "success" else 0.9)
    x = bend * np.sin(t / 8 * 2 * math.pi)
    pose = np.stack([x, y, np.full_like(t, math.pi / 2)], axis=1)
    vel = np.zeros((len(t), 3))
    vel[1:, 0] = np.hypot(np.diff(x), np.diff(y)) / np.diff(t) * (1 - 0.5 * np.sin(t[1:]) ** 2)
    traj = Trajectory(t=t, pose=pose, velocity=vel, tick_t=t[::10], command=vel[::10],
                      ranges=np.zeros((81, 8), np.float32), angles=np.linspace(0, 6, 8))
    i = 400
    metrics = Metrics(
        min_clearance=0.84, min_clearance_obstacle="box_right", min_clearance_time=float(t[i]),
        min_clearance_x=float(x[i]), min_clearance_y=float(y[i]), min_obstacle_gap=2.0,
        min_gap_obstacles="box_left|box_right", path_length=10.3, shortest_path_length=10.0,
        path_efficiency=0.97, max_deviation=0.6, mean_deviation=0.35, duration=8.0, mean_speed=1.2,
        goal_position_error=0.5, goal_yaw_error=0.0, smoothness=0.1, angular_smoothness=0.1)
    events: dict = {}
    message = "success in 8.0 s"
    if outcome == "collision":
        events["collision"] = Collision(time=8.0, obstacle="pillar", x=float(x[-1]), y=float(y[-1]), depth=0.01)
        message = "collision with 'pillar' at t=8.00 s (depth 10 mm)"
    elif outcome == "safety-stop":
        events["safety_stop"] = SafetyStop(time=7.9, obstacle="pillar", speed=0.8)
        message = "safety stop at t=7.90 s: predicted to hit 'pillar' at 0.80 m/s"
    return EpisodeResult(scenario=scenario, outcome=Outcome(outcome), metrics=metrics, trajectory=traj,
                         seed=0, subject=subject, message=message, **events)


def read_png(path):
    from matplotlib.image import imread
    return imread(str(path))


def assert_picture(path, min_size=(300, 300)):
    img = read_png(path)
    h, w = img.shape[:2]
    assert w >= min_size[0] and h >= min_size[1], (w, h)
    # not blank: many distinct colours and real variance across the image
    assert float(img[..., :3].std()) > 0.05
    assert len(np.unique((img[..., :3] * 255).astype(np.uint8).reshape(-1, 3), axis=0)) > 50
    return img


def test_trajectory_plot_size_and_content(tmp_path):
    from pytest_navscenario.report.plots import _figsize, save_figure, trajectory_figure

    result = make_episode("collision")
    fig = trajectory_figure(result)
    img = assert_picture(save_figure(fig, tmp_path / "sub" / "traj.png"))
    w_in, h_in = _figsize([result], 1)
    assert img.shape[:2] == (round(h_in * 100), round(w_in * 100))
    # the picture shows what the issue asks for
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.texts]
    assert {"box_left", "box_right", "pillar"} <= set(texts)
    assert any(t.startswith("min clearance 0.84 m") for t in texts)
    assert "gap 2.00 m" in texts
    assert "COLLISION" in ax.get_title() and "pillar" in ax.get_title()
    assert ax.get_aspect() == 1.0 and ax.xaxis.get_gridlines()[0].get_visible()
    assert any(a.get_label() == "speed (m/s)" or a.get_xlabel() == "speed (m/s)" for a in fig.axes[1:])
    outlines = [c for c in ax.collections if c.get_label().startswith("footprint every")]
    assert len(outlines[0].get_paths()) == 17   # an outline to scale every 0.5 s of the 8 s run
    assert outlines[0].get_paths()[0].get_extents().height == pytest.approx(0.9)  # 0.9 m long, heading +y


def test_names_with_dollar_signs_are_drawn_as_written(tmp_path):
    # matplotlib reads '$...$' as mathtext: a scenario named 'cost $5 and $x' lost its dollars and went
    # italic, and an obstacle named 'x$\\frac{$y' made the plot fail ("could not draw ...: ValueError")
    import dataclasses
    from pytest_navscenario.report.plots import comparison_figure, save_figure, trajectory_figure

    result = make_episode("collision", name="cost $5 and $x")
    odd = BoxObstacle("x$\\frac{$y", 1.5, 5, 1, 1)
    result.scenario = dataclasses.replace(result.scenario, obstacles=(result.scenario.obstacles[0], odd,
                                                                      result.scenario.obstacles[2]))
    for fig in (trajectory_figure(result), comparison_figure(result, result)):
        assert_picture(save_figure(fig, tmp_path / "odd.png"))
        texts = [t for ax in fig.axes for t in (*ax.texts, ax.title)] + list(fig.texts)
        assert any(t.get_text() == "x$\\frac{$y" for t in texts)
        assert any("cost $5 and $x" in t.get_text() for t in texts)
        assert not any(t.get_parse_math() and "$" in t.get_text() for t in texts)


def test_plot_without_trajectory_still_shows_the_layout(tmp_path):
    """Results rebuilt without a trajectory (not requested) still plot the scene and markers."""
    from pytest_navscenario.sim.trajectory import Trajectory
    from pytest_navscenario.report.plots import save_trajectory

    result = make_episode("timeout")
    result.trajectory = Trajectory.empty()
    assert_picture(save_trajectory(result, tmp_path / "t.png"))


def test_side_by_side_comparison(tmp_path):
    from pytest_navscenario.report.plots import comparison_figure, save_figure

    a = make_episode("collision", subject="dwa")
    b = make_episode("success", subject="potential-field", bend=-0.3)
    fig = comparison_figure(a, b)
    img = assert_picture(save_figure(fig, tmp_path / "cmp.png"), min_size=(800, 500))
    assert img.shape[1] > img.shape[0]
    titles = [ax.get_title() for ax in fig.axes[:2]]
    assert titles[0].startswith("A: boxes1") and "COLLISION" in titles[0]
    assert titles[1].startswith("B: boxes1") and "SUCCESS" in titles[1]
    assert fig.axes[0].get_xlim() == fig.axes[1].get_xlim()


def test_bar_chart_from_a_comparison(tmp_path):
    from pytest_navscenario.report.compare import compare_records
    from pytest_navscenario.report.plots import bars_figure, save_figure
    from test_compare import BASE, suite

    changed = dict(BASE, **{"scenarios/boxes/b2.yaml::b2": "safety-stop",
                            "scenarios/corridor/c1.yaml::c1": "success"})
    cmp = compare_records(suite(BASE), suite(changed, subject="new"))
    fig = bars_figure(cmp)
    assert_picture(save_figure(fig, tmp_path / "bars.png"), min_size=(500, 400))
    ax = fig.axes[0]
    heights = sorted(round(p.get_height()) for p in ax.patches)
    # per family (boxes, corridor, all) x (A, B) x (success up; safety-stop, timeout, collision down)
    assert len(ax.patches) == 24
    assert heights[0] == -50 and heights[-1] == 67   # corridor A safety-stop, boxes success
    assert [t.get_text().split("\n")[0] for t in ax.get_xticklabels()] == ["boxes", "corridor", "(all)"]


def test_cli_plot_option(tmp_path, capsys):
    from pytest_navscenario.cli import main
    from pytest_navscenario.report.results_file import write_results
    from test_compare import BASE, suite

    write_results(tmp_path / "a.jsonl", suite(BASE))
    write_results(tmp_path / "b.jsonl", suite(BASE, subject="new"))
    assert main(["compare", str(tmp_path / "a.jsonl"), str(tmp_path / "b.jsonl"),
                 "--plot", str(tmp_path / "bars.png")]) == 0
    assert_picture(tmp_path / "bars.png")
    assert "bar chart written to" in capsys.readouterr().out


@pytest.mark.parametrize("raw, step", [(0.3, 0.5), (1.0, 1.0), (1.2, 2.0), (3.1, 5.0), (0.0, 1.0)])
def test_nice_grid_steps(raw, step):
    from pytest_navscenario.report.plots import _nice_step
    assert _nice_step(raw) == step


def test_bar_chart_says_when_nothing_could_be_compared():
    from pytest_navscenario.report.compare import compare_records
    from pytest_navscenario.report.plots import bars_figure
    from test_compare import BASE, rec, suite

    cmp = compare_records(suite(BASE), [rec("scenarios/x/new.yaml::new", "success")])
    ax = bars_figure(cmp).axes[0]
    assert not ax.patches and "no comparable scenario pairs" in ax.texts[0].get_text()


def test_bar_chart_shows_timeouts_and_every_other_way_of_failing():
    """Issue 23 item 11: a family whose runs all timed out under A showed as 0 % / 0 %."""
    from pytest_navscenario.report.compare import compare_records
    from pytest_navscenario.report.plots import bars_figure
    from test_compare import rec

    nodes = [f"scenarios/corridor/c{i}.yaml::c{i}" for i in range(4)]
    a = [rec(n, "timeout") for n in nodes]
    b = [rec(n, "success", subject="new") for n in nodes[:3]] + [rec(nodes[3], "collision", subject="new")]
    ax = bars_figure(compare_records(a, b)).axes[0]
    hatched = {(p.get_hatch(), round(p.get_height())) for p in ax.patches if p.get_hatch()}
    assert ("..", -100) in hatched            # A: all four timed out
    assert ("xx", -25) in hatched             # B: one collision
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "timeout" in legend and "collision" in legend
    texts = [t.get_text() for t in ax.texts]
    assert "100%" in texts and "25%" in texts


def dwelling_timeout() -> EpisodeResult:
    """Drives 3 m up in 3 s, then circles 0.3 m around one spot for 27 s, and times out there
    (a moving person's way ends beside the gap between the two boxes, whose name labels sit
    near the gap's label)."""
    from pytest_navscenario.scenario.model import Motion

    scenario = Scenario(
        mission=Mission(start=Pose(0, 0, 90), goal=Pose(0, 10, 90), timeout=30.0),
        obstacles=(BoxObstacle("box_left", -1.0, 5.2, 0.6, 0.6), BoxObstacle("box_right", 1.0, 5.2, 0.6, 0.6),
                   BoxObstacle("navsearch_inserted_1", 0.0, 4.55, 0.3, 0.3),
                   CylinderObstacle("walker", -3.0, 5.0, 0.25,
                                    motion=Motion(path=((-3.0, 5.0), (0.3, 5.0)), speed=1.0))),
        name="dwell", family="tests")
    t = np.linspace(0.0, 30.0, 3001)
    y = np.where(t < 3, t, 3.0 + 0.3 * np.sin((t - 3) * 0.9))
    x = np.where(t < 3, 0.0, 0.3 * (1 - np.cos((t - 3) * 0.9)))
    pose = np.stack([x, y, np.full_like(t, math.pi / 2)], axis=1)
    vel = np.zeros((len(t), 3))
    vel[1:, 0] = np.hypot(np.diff(x), np.diff(y)) / np.diff(t)
    traj = Trajectory(t=t, pose=pose, velocity=vel, tick_t=t[::10], command=vel[::10],
                      ranges=np.zeros((301, 8), np.float32), angles=np.linspace(0, 6, 8))
    metrics = Metrics(
        min_clearance=0.6, min_clearance_obstacle="navsearch_inserted_1", min_clearance_time=20.0,
        min_clearance_x=float(x[2000]), min_clearance_y=float(y[2000]), min_obstacle_gap=1.4,
        min_gap_obstacles="box_left|box_right", path_length=30.0, shortest_path_length=10.0,
        path_efficiency=0.1, max_deviation=0.6, mean_deviation=0.3, duration=30.0, mean_speed=0.5,
        goal_position_error=6.7, goal_yaw_error=0.0, smoothness=0.1, angular_smoothness=0.1)
    return EpisodeResult(scenario=scenario, outcome=Outcome("timeout"), metrics=metrics, trajectory=traj,
                         seed=0, subject="dwa", message="timeout after 30.0 s, 6.70 m from the goal")


def test_a_timeout_marks_where_the_robot_ended():
    from pytest_navscenario.report.plots import trajectory_figure

    result = dwelling_timeout()
    ax = trajectory_figure(result).axes[0]
    ends = [line for line in ax.get_lines() if line.get_label().startswith("end: timeout at t=30.0 s")]
    assert len(ends) == 1
    assert (ends[0].get_xdata()[0], ends[0].get_ydata()[0]) == pytest.approx(tuple(result.trajectory.pose[-1, :2]))


def test_time_labels_do_not_pile_up_where_the_robot_dwells():
    import re

    from pytest_navscenario.report.plots import trajectory_figure

    ax = trajectory_figure(dwelling_timeout()).axes[0]
    stamps = [t.get_text() for t in ax.texts if re.fullmatch(r"\d+(\.\d+)?s", t.get_text())]
    assert len(stamps) <= 2, stamps          # one while driving up, at most one where it circled
    dots = [line for line in ax.get_lines() if line.get_marker() == "o" and line.get_markersize() == 2.5]
    assert len(dots) == len(stamps)          # no stamp without its dot, no dot without its stamp


def _overlap(a, b) -> float:
    w = min(a[2], b[2]) - max(a[0], b[0])
    h = min(a[3], b[3]) - max(a[1], b[1])
    return w * h if w > 0 and h > 0 else 0.0


@pytest.mark.parametrize("make", [dwelling_timeout, lambda: make_episode("collision"),
                                  lambda: make_episode("safety-stop")])
def test_labels_overlap_neither_each_other_nor_the_markers(make):
    """"gap 1.40 m" over an inserted box's name or a person's end disc, a moving obstacle's time
    over the minimum clearance, a stamp over the end marker: the placer keeps every label clear."""
    from pytest_navscenario.report.labels import text_boxes
    from pytest_navscenario.report.plots import trajectory_figure

    result = make()
    ax = trajectory_figure(result).axes[0]
    boxes = text_boxes(ax)
    assert any(text.startswith("gap ") for text, _ in boxes)
    for i, (ta, a) in enumerate(boxes):
        for tb, b in boxes[i + 1:]:
            assert _overlap(a, b) < 1.0, (ta, tb)
    markers = [line for line in ax.get_lines() if line.get_marker() in ("s", "X", "8", "*", "o")
               and line.get_markersize() >= 8]
    assert markers
    for line in markers:
        px, py = ax.transData.transform((line.get_xdata()[0], line.get_ydata()[0]))
        r = line.get_markersize() / 2
        for text, box in boxes:
            assert _overlap(box, (px - r, py - r, px + r, py + r)) < 1.0, (text, line.get_label())
