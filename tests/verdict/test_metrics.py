"""Every metric on hand-computed trajectories (built with numpy, no simulation)."""
import math

import numpy as np
import pytest
import shapely

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.scenario.geometry import footprint_polygons, obstacle_polygons
from pytest_navscenario.verdict.metrics import compute_metrics, min_clearance
from pytest_navscenario.verdict.paths import path_through, shortest_path
from pytest_navscenario.sim.trajectory import Collision, Trajectory
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle, Footprint, Mission, Pose, Reference, Robot, Scenario

DT = 0.01


def scenario(*obstacles, footprint=Footprint(), goal=(0, 10, 90), reference=None, source=None):
    return Scenario(mission=Mission(start=Pose(0, 0, 90), goal=Pose(*goal)), obstacles=tuple(obstacles),
                    robot=Robot(footprint=footprint), reference=reference, source=source)


def trajectory(x, y, yaw, velocity=None):
    """Physics-rate trajectory at DT from position/yaw arrays (velocity: robot frame, or zeros)."""
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    n = len(x)
    t = np.arange(n) * DT
    yaw = np.broadcast_to(np.asarray(yaw, float), (n,))
    vel = np.zeros((n, 3)) if velocity is None else np.asarray(velocity, float)
    return Trajectory(t=t, pose=np.column_stack([x, y, yaw]), velocity=vel, tick_t=t[::10],
                      command=np.zeros((len(t[::10]), 3)), ranges=np.zeros((len(t[::10]), 4), np.float32),
                      angles=np.zeros(4))


def straight_north(x=0.0, length=10.0, speed=1.0, yaw=math.pi / 2):
    """From (x, 0) to (x, length) at `speed` m/s, heading `yaw`."""
    n = int(round(length / (speed * DT))) + 1
    y = np.linspace(0.0, length, n)
    return trajectory(np.full(n, x), y, yaw, velocity=np.tile([speed, 0.0, 0.0], (n, 1)))


def test_clearance_passing_a_box_sideways():
    # robot 0.9 x 0.5 heading north along x=0: its right side is at x=0.25; box face at x=0.5
    s = scenario(BoxObstacle("right_box", 1.0, 5.0, 1.0, 1.0), BoxObstacle("far", -5, 5, 1, 1))
    m = compute_metrics(s, straight_north())
    assert m.min_clearance == pytest.approx(0.25, abs=1e-12)
    assert m.min_clearance_obstacle == "right_box"
    # earliest moment of the minimum: the robot's front (y + 0.45) reaches the box (y = 4.5)
    assert m.min_clearance_time == pytest.approx(4.05, abs=DT)
    assert (m.min_clearance_x, m.min_clearance_y) == pytest.approx((0.0, 4.05), abs=DT)


def test_clearance_depends_on_the_heading_of_a_box_footprint():
    # same line, robot turned to face the box: its front is 0.45 from the centre
    s = scenario(BoxObstacle("right_box", 1.0, 5.0, 1.0, 1.0))
    assert compute_metrics(s, straight_north(yaw=0.0)).min_clearance == pytest.approx(0.05, abs=1e-12)


def test_clearance_of_a_circle_footprint_to_a_cylinder():
    s = scenario(CylinderObstacle("pillar", 1.0, 5.0, 0.2), footprint=Footprint(shape="circle", radius=0.3))
    m = compute_metrics(s, straight_north())
    assert m.min_clearance == pytest.approx(0.5, abs=1e-12)
    assert m.min_clearance_time == pytest.approx(5.0, abs=1e-9)
    assert m.min_clearance_obstacle == "pillar"


def test_clearance_of_a_box_footprint_to_a_cylinder():
    # the robot's flat side (x = 0.25, 0.9 m long) faces the cylinder's edge (x = 1 - 0.2) from
    # the moment its front passes the cylinder's centre (y + 0.45 = 5): earliest of the ties
    s = scenario(CylinderObstacle("pillar", 1.0, 5.0, 0.2))
    m = compute_metrics(s, straight_north())
    assert m.min_clearance == pytest.approx(0.55, abs=1e-12)
    assert m.min_clearance_time == pytest.approx(4.55, abs=DT)


def test_clearance_is_zero_on_contact_and_a_collision_overrides_it():
    s = scenario(BoxObstacle("in_the_way", 0.3, 5.0, 1.0, 1.0))
    m = compute_metrics(s, straight_north())
    assert (m.min_clearance, m.min_clearance_obstacle) == (0.0, "in_the_way")
    assert m.min_clearance_time == pytest.approx(4.05, abs=DT)
    hit = Collision(time=4.2, obstacle="in_the_way", x=0.1, y=4.6, depth=0.01)
    m = compute_metrics(s, straight_north(), collision=hit)
    assert (m.min_clearance, m.min_clearance_time) == (0.0, 4.2)
    assert (m.min_clearance_x, m.min_clearance_y) == pytest.approx((0.0, 4.2))


def test_clearance_is_exact_at_every_physics_step():
    # a wiggly, turning run among rotated boxes: the coarse-to-fine search must find the same
    # minimum as shapely over every pose
    rng = np.random.default_rng(0)
    n = 1001
    x = 0.3 * np.sin(np.linspace(0, 12, n))
    yaw = np.pi / 2 + 0.4 * np.sin(np.linspace(0, 30, n))
    tr = trajectory(x, np.linspace(0, 10, n), yaw)
    obstacles = [BoxObstacle(f"b{i}", rng.choice([-1, 1]) * rng.uniform(0.8, 2), rng.uniform(0, 10),
                             *rng.uniform(0.2, 1.5, 2), rng.uniform(-90, 90)) for i in range(10)]
    s = scenario(*obstacles)
    feet = footprint_polygons(s.robot.footprint, tr.pose)
    dist = shapely.distance(feet[:, None], np.array(obstacle_polygons(s))[None])
    i, k = np.unravel_index(np.argmin(dist), dist.shape)
    m = compute_metrics(s, tr)
    assert m.min_clearance == pytest.approx(dist.min(), abs=1e-12)
    assert (m.min_clearance_obstacle, m.min_clearance_time) == (f"b{k}", pytest.approx(tr.t[i]))
    assert min_clearance(s, tr.t, tr.pose[::7])[0] >= m.min_clearance


def test_no_obstacles():
    m = compute_metrics(scenario(), straight_north())
    assert (m.min_clearance, m.min_clearance_obstacle) == (math.inf, "")
    assert (m.min_obstacle_gap, m.min_gap_obstacles) == (math.inf, "")


def test_path_length_efficiency_and_deviation_of_a_detour():
    # no obstacles: the shortest path is the line x=0; the robot bulges out to (1, 5) and back
    n = 1001
    y = np.linspace(0, 10, n)
    x = 1.0 - np.abs(y - 5.0) / 5.0
    m = compute_metrics(scenario(), trajectory(x, y, np.pi / 2))
    driven = 2 * math.hypot(1.0, 5.0)
    assert m.path_length == pytest.approx(driven)
    assert m.shortest_path_length == pytest.approx(10.0)
    assert m.path_efficiency == pytest.approx(10.0 / driven)
    assert m.max_deviation == pytest.approx(1.0)
    assert m.mean_deviation == pytest.approx(0.5, abs=1e-3)
    assert m.duration == pytest.approx(10.0)
    assert m.mean_speed == pytest.approx(driven / 10.0)


def test_stopping_inside_the_goal_tolerance_is_still_optimal():
    # the run ends 0.25 m short of the goal: efficiency completes it with a straight line
    m = compute_metrics(scenario(), straight_north(length=9.75))
    assert m.path_length == pytest.approx(9.75)
    assert m.goal_position_error == pytest.approx(0.25)
    assert m.path_efficiency == pytest.approx(1.0)


def test_a_run_that_stops_in_front_of_a_box_is_charged_the_detour_still_to_go():
    s = scenario(BoxObstacle("box", 0, 5, 1, 1))
    m = compute_metrics(s, straight_north(length=3.5))
    to_go = path_through(s, [(0.0, 3.5), (0.0, 10.0)]).length
    assert to_go > 6.5 + 0.1                     # around the box, not through it
    assert m.path_efficiency == pytest.approx(m.shortest_path_length / (3.5 + to_go))
    assert m.path_efficiency < 1.0


def test_driving_the_detour_around_a_box_is_optimal():
    s = scenario(BoxObstacle("box", 0, 5, 1, 1))
    sp = shortest_path(s)
    seg = np.hypot(*np.diff(sp.points, axis=0).T)
    along = np.linspace(0, seg.sum(), 1001)
    cum = np.concatenate([[0], np.cumsum(seg)])
    x, y = np.interp(along, cum, sp.points[:, 0]), np.interp(along, cum, sp.points[:, 1])
    m = compute_metrics(s, trajectory(x, y, np.pi / 2))
    assert m.shortest_path_length > 10.0
    assert m.path_efficiency == pytest.approx(1.0)
    assert m.max_deviation == pytest.approx(0.0, abs=1e-9)
    straight = compute_metrics(s, straight_north(x=0.75))
    assert straight.max_deviation > 0.1 and straight.min_clearance == pytest.approx(0.0, abs=1e-12)


def test_a_robot_that_did_not_move():
    m = compute_metrics(scenario(), trajectory(np.zeros(101), np.zeros(101), np.pi / 2))
    assert m.path_length == 0.0 and m.mean_speed == 0.0
    assert math.isnan(m.path_efficiency)
    assert m.goal_position_error == pytest.approx(10.0)


def test_goal_errors_wrap_the_yaw():
    # final pose (0.3, 9.6) heading -179 deg; goal (0, 10) heading 179 deg: 0.5 m and 2 deg off
    tr = trajectory([0.0, 0.3], [0.0, 9.6], [0.0, math.radians(-179.0)])
    m = compute_metrics(scenario(goal=(0, 10, 179)), tr)
    assert m.goal_position_error == pytest.approx(0.5)
    assert m.goal_yaw_error == pytest.approx(2.0)


def test_jerk_of_a_known_profile():
    # v(t) = j t^2 / 2 along the heading: constant jerk j, whatever the heading
    n, jerk = 201, 3.0
    t = np.arange(n) * DT
    for heading in (0.0, math.pi / 2, 2.5):
        vel = np.column_stack([0.5 * jerk * t ** 2, np.zeros(n), np.zeros(n)])
        m = compute_metrics(scenario(), trajectory(np.zeros(n), np.zeros(n), heading, velocity=vel))
        assert m.smoothness == pytest.approx(jerk, rel=1e-9)
        assert m.angular_smoothness == 0.0


def test_jerk_of_a_circle_is_v_omega_squared_and_angular_acceleration_of_a_ramp():
    # constant 1 m/s forward while turning at 0.5 rad/s: |jerk| = v w^2 = 0.25 m/s^3
    n, v, w = 1001, 1.0, 0.5
    t = np.arange(n) * DT
    vel = np.column_stack([np.full(n, v), np.zeros(n), np.full(n, w)])
    m = compute_metrics(scenario(), trajectory(np.zeros(n), np.zeros(n), w * t, velocity=vel))
    assert m.smoothness == pytest.approx(v * w * w, rel=1e-3)
    assert m.angular_smoothness == pytest.approx(0.0, abs=1e-12)
    ramp = np.column_stack([np.zeros(n), np.zeros(n), 0.7 * t])   # wz grows at 0.7 rad/s^2
    m = compute_metrics(scenario(), trajectory(np.zeros(n), np.zeros(n), 0.35 * t ** 2, velocity=ramp))
    assert m.angular_smoothness == pytest.approx(0.7)


def test_reference_deviation_of_a_known_offset_inline():
    # reference 0.2 m to the east of the simulated line, sampled every second, one point
    # after the end of the run (ignored: outside the simulated time span)
    points = tuple((float(t), 0.2, float(t)) for t in range(12))
    m = compute_metrics(scenario(reference=Reference(points=points)), straight_north())
    assert m.reference_mean_deviation == pytest.approx(0.2)
    assert m.reference_max_deviation == pytest.approx(0.2)
    plain = compute_metrics(scenario(), straight_north())
    assert math.isnan(plain.reference_mean_deviation) and math.isnan(plain.reference_max_deviation)


def test_reference_from_a_csv_file_next_to_the_scenario(tmp_path):
    (tmp_path / "logs").mkdir()
    rows = "\n".join(f"{t / 2},{0.0},{t / 2 + (0.5 if t == 6 else 0.0)}" for t in range(21))
    (tmp_path / "logs" / "run.csv").write_text("t,x,y\n" + rows + "\n")
    s = scenario(reference=Reference(file="logs/run.csv"), source=str(tmp_path / "case.yaml"))
    m = compute_metrics(s, straight_north())
    assert m.reference_max_deviation == pytest.approx(0.5)
    assert m.reference_mean_deviation == pytest.approx(0.5 / 21)


def test_missing_reference_file_names_the_scenario_and_the_path(tmp_path):
    s = scenario(reference=Reference(file="logs/missing.csv"), source=str(tmp_path / "case.yaml"))
    with pytest.raises(ScenarioError) as err:
        compute_metrics(s, straight_north())
    text = str(err.value)
    assert "case.yaml" in text and "logs/missing.csv" in text and "reference.file" in text


def test_reference_file_with_a_wrong_header_says_how_to_fix_it(tmp_path):
    (tmp_path / "run.csv").write_text("time,px,py\n0,0,0\n")
    s = scenario(reference=Reference(file="run.csv"), source=str(tmp_path / "case.yaml"))
    with pytest.raises(ScenarioError, match="t,x,y"):
        compute_metrics(s, straight_north())
    (tmp_path / "run.csv").write_text("t,x,y\n0,0,0\n1,oops,0\n")
    with pytest.raises(ScenarioError, match=r"run.csv:3"):
        compute_metrics(s, straight_north())


def test_metrics_are_deterministic():
    s = scenario(BoxObstacle("a", 1, 5, 1, 1), CylinderObstacle("b", -1.2, 3, 0.4))
    tr = straight_north(x=0.1)
    first, second = compute_metrics(s, tr).as_dict(), compute_metrics(s, tr).as_dict()
    assert repr(first) == repr(second)
    assert first["min_gap_obstacles"] == "a|b"


def test_mismatched_trajectory_arrays_are_named():
    tr = straight_north()
    tr.velocity = tr.velocity[:-5]
    with pytest.raises(ValueError, match=r"t has 1001 samples, pose 1001, velocity 996"):
        compute_metrics(scenario(), tr)


def _slow_same_way():
    """The recorded run: the same line north, but at a third of the speed and with a 0.1 m bulge."""
    t = np.arange(0.0, 30.05, 0.5)
    y = t / 3.0
    return tuple((float(a), 0.1 if 4.0 <= b <= 6.0 else 0.0, float(b)) for a, b in zip(t, y))


def test_path_comparison_is_blind_to_the_pace():
    """A run that took the recorded way three times faster: far off at the same times (compare:
    time), within the 0.1 m bulge along the way (compare: path)."""
    points = _slow_same_way()
    timed = compute_metrics(scenario(reference=Reference(points=points)), straight_north())
    assert timed.reference_max_deviation == pytest.approx(10.0 - 10.0 / 3.0, abs=0.05)
    spatial = compute_metrics(scenario(reference=Reference(points=points, compare="path")), straight_north())
    assert spatial.reference_max_deviation == pytest.approx(0.1, abs=1e-9)
    assert 0 < spatial.reference_mean_deviation < 0.1


def test_path_comparison_sees_a_run_that_left_the_way_or_stopped_short():
    points = tuple((float(t), 0.0, float(t)) for t in range(11))            # north along x = 0, 10 m
    off = compute_metrics(scenario(reference=Reference(points=points, compare="path")), straight_north(x=0.7))
    assert off.reference_max_deviation == pytest.approx(0.7) and off.reference_mean_deviation == pytest.approx(0.7)
    short = compute_metrics(scenario(reference=Reference(points=points, compare="path")), straight_north(length=4.0))
    # every simulated pose lies on the recorded way, but the recorded way goes 6 m further
    assert short.reference_mean_deviation == pytest.approx(0.0) and short.reference_max_deviation == pytest.approx(6.0)
