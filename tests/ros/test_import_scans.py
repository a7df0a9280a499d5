"""Issue 24, scans placed as they were taken: bags generated from a known world by a laser that
measures its beams one after another while the robot turns, stamped and declared as real drivers
do. Each beam is placed with the robot's pose at its own time, so a robot turning during every
scan imports as sharply as a still one; free space is carved, so what later beams cross is gone;
walls come out as few polygons."""
from __future__ import annotations

import math

import numpy as np
import pytest
from ros_synthetic import ScanTiming, World, robot_bag
from shapely.geometry import LineString, box

from pytest_navscenario.ros.bag_import import BagImportError, scenario_from_bag
from pytest_navscenario.scenario.geometry import obstacle_polygon
from pytest_navscenario.scenario.model import CylinderObstacle, PolygonObstacle

ROOM = World(pillars=[(2.5, 0.5, 0.2, 1.0), (-1.5, 2.5, 0.25, 1.0), (-2.0, -2.0, 0.2, 1.0), (1.0, -3.0, 0.3, 1.0)],
             boxes=[(0.0, 4.5, 9.0, 0.2, 0.0, 1.0), (0.0, -4.5, 9.0, 0.2, 0.0, 1.0),
                    (4.5, 0.0, 0.2, 9.0, 0.0, 1.0), (-4.5, 0.0, 0.2, 9.0, 0.0, 1.0)])
INC = 0.1 / 360          # a 10 Hz rotating lidar: 360 beams in 0.1 s
SPIN = 1.5               # rad/s: 8.6 degrees within one scan, 0.45 m across at 3 m


def _drive(rate: float) -> np.ndarray:
    """(80, 4) 8 s at 10 Hz: a slow sway across the room while turning at ``rate`` rad/s."""
    t = np.arange(80) * 0.1
    return np.stack([t, 0.3 * np.sin(0.3 * t), 0.2 * t - 0.8, rate * t], 1)


def _pillar_errors(seed) -> list[float]:
    """Per true pillar: centre distance plus radius difference of the nearest seed cylinder."""
    got = [o for o in seed.scenario.obstacles if isinstance(o, CylinderObstacle)]
    return [min((math.hypot(o.x - x, o.y - y) + abs(o.radius - r) for o in got), default=math.inf)
            for x, y, r, _ in ROOM.pillars]


def _timing_note(seed) -> str:
    return next(n for n in seed.notes if n.startswith("scan timing:"))


def _import(tmp_path, name: str, rate: float, timing: ScanTiming, **kwargs):
    return scenario_from_bag(robot_bag(tmp_path / name, ROOM, _drive(rate), timing=timing, tf_map=False), **kwargs)


def test_a_robot_turning_during_each_scan_imports_as_sharply_as_a_still_one(tmp_path):
    still = _import(tmp_path, "still", 0.0, ScanTiming(increment=INC))
    spin = _import(tmp_path, "spin", SPIN, ScanTiming(increment=INC))
    for seed in (still, spin):
        assert max(_pillar_errors(seed)) < 0.02, seed.scenario.obstacles
        assert len(seed.scenario.obstacles) == 5          # four pillars and the room's walls
        assert seed.fit.median_error <= 0.03 and seed.fit.blocked < 0.01 and seed.fit.missed < 0.01
        assert seed.fit.warnings == []
    note = _timing_note(spin)
    assert "time_increment 0.2778 ms" in note and "the stamp is the scan's start" in note
    assert "turned up to 8.6 deg" in note


def test_without_the_beams_timing_a_turning_robot_smears_and_the_fit_says_so(tmp_path):
    """The same robot and world, but the driver declares neither time_increment nor scan_time: every
    beam is taken at its scan's stamp (as laser_geometry would), the turn smears the pillars, and
    the fit figure warns that the seed disagrees with its own scans."""
    seed = _import(tmp_path, "undeclared", SPIN, ScanTiming(increment=INC, time_increment=0.0, scan_time=0.0))
    assert "time_increment and scan_time are 0" in _timing_note(seed)
    assert min(_pillar_errors(seed)) > 0.05
    assert seed.fit.blocked > 0.2 and any("disagrees with its own scans" in w for w in seed.fit.warnings)


def test_a_driver_that_stamps_the_end_of_its_scans(tmp_path):
    seed = _import(tmp_path, "end", SPIN, ScanTiming(increment=INC, stamp="end"))
    assert "sooner than the scan takes (0.0997 s): the stamp is the scan's end" in _timing_note(seed)
    assert max(_pillar_errors(seed)) < 0.02
    forced = _import(tmp_path, "end2", SPIN, ScanTiming(increment=INC, stamp="end"), scan_stamp="start")
    assert "(--scan-stamp start)" in _timing_note(forced)
    assert forced.fit.warnings and min(_pillar_errors(forced)) > 0.02


def test_scan_time_alone_is_read_when_it_gives_the_sharper_map(tmp_path):
    """time_increment 0 with a scan_time: every beam at once (laser_geometry's reading) or spread over
    the scan; for a turning rotating lidar the spread one is far sharper and is used."""
    seed = _import(tmp_path, "st", SPIN, ScanTiming(increment=INC, time_increment=0.0))
    note = _timing_note(seed)
    assert "beams spread over scan_time 0.1 s" in note and "the sharpest map of" in note
    assert max(_pillar_errors(seed)) < 0.02


def test_a_simulated_instantaneous_scan_stays_instantaneous(tmp_path):
    """A simulator writes scan_time (the time between scans) but measures every beam at once: the
    default reading, every beam at the stamp, stays (the spread one is blurrier)."""
    seed = _import(tmp_path, "sim", SPIN, ScanTiming(increment=0.0, time_increment=0.0, scan_time=0.1))
    assert _timing_note(seed).startswith("scan timing: every beam at its scan's stamp (time_increment is 0, "
                                         "scan_time 0.1 s")
    assert max(_pillar_errors(seed)) < 0.02


def test_a_time_offset_fixes_a_driver_that_stamps_late(tmp_path):
    """Stamps 0.3 s late (a driver's clock off; the bag received each scan before its stamp): the
    receive times do not tell, the seed smears; --scan-time-offset -0.3 places the scans right."""
    timing = ScanTiming(increment=INC, stamp_error=0.3)
    late = _import(tmp_path, "late", SPIN, timing)
    assert "the bag's receive times do not tell" in _timing_note(late)
    assert late.fit.warnings and min(_pillar_errors(late)) > 0.05
    fixed = _import(tmp_path, "late2", SPIN, timing, scan_offset=-0.3)
    assert "stamps moved by -0.3 s (--scan-time-offset)" in _timing_note(fixed)
    assert max(_pillar_errors(fixed)) < 0.02 and fixed.fit.warnings == []


def test_a_negative_time_increment_is_a_warning_and_used_as_written(tmp_path):
    """A laser that measures its array from the last beam to the first declares a negative
    time_increment: a warning says so, and the beams are placed that way (sharp)."""
    seed = _import(tmp_path, "neg", SPIN, ScanTiming(increment=-INC))
    warn = [n for n in seed.notes if "time_increment is negative" in n]
    assert len(warn) == 1 and warn[0].startswith("warning: ") and "from the last in the array to the first" in warn[0]
    assert max(_pillar_errors(seed)) < 0.02


def test_a_time_increment_longer_than_the_period_is_a_warning(tmp_path):
    """time_increment x beams = 1 s for scans 0.1 s apart cannot be: the beams are spread over the
    period instead, and the warning says so."""
    seed = _import(tmp_path, "long", SPIN, ScanTiming(increment=INC, time_increment=10 * INC))
    warn = [n for n in seed.notes if "longer than the scans' period" in n]
    assert len(warn) == 1 and "spread over the period instead" in warn[0]
    assert max(_pillar_errors(seed)) < 0.03


def test_scans_without_odometry_around_them_are_skipped_with_a_warning(tmp_path):
    """The odometry stops for 2 s (3.05..5.05 s) while the laser goes on: those scans have no pose
    to be placed with; they are left out, and the warning gives how many and when."""
    path = robot_bag(tmp_path / "gap", ROOM, _drive(0.3), timing=ScanTiming(increment=INC), tf_map=False,
                     odom_keep=lambda t: not 3.05 < t < 5.05)
    seed = scenario_from_bag(path)
    warn = [n for n in seed.notes if "the odometry has gaps" in n]
    assert len(warn) == 1 and warn[0].startswith("warning: ") and "t=3.0..5.0 s" in warn[0], seed.notes
    assert max(_pillar_errors(seed)) < 0.02


def test_a_smear_that_later_beams_cross_is_gone(tmp_path):
    """For the first 0.5 s a return lands where nothing is (a reflection, a person who walked on):
    the beams of the next 7 s pass through it, so the occupancy grid carves it free."""
    ghost = World(pillars=[*ROOM.pillars, (0.8, 1.6, 0.15, 1.0)], boxes=ROOM.boxes)
    path = robot_bag(tmp_path / "ghost", ROOM, _drive(0.5), timing=ScanTiming(increment=INC), tf_map=False,
                     world_at=lambda t: ghost if t < 0.5 else ROOM)
    seed = scenario_from_bag(path)
    assert not [o for o in seed.scenario.obstacles if math.hypot(o.x - 0.8, o.y - 1.6) < 0.5]
    assert any("crossed by later beams more often than hit" in n for n in seed.notes)
    assert max(_pillar_errors(seed)) < 0.05


CORRIDOR = World(pillars=[(6.0, 0.9, 0.15, 1.0)],                                 # a bin by the wall
                 boxes=[(5.0, 1.4, 10.0, 0.2, 0.0, 1.0),                           # north wall
                        (2.0, -1.4, 4.0, 0.2, 0.0, 1.0), (7.5, -1.4, 5.0, 0.2, 0.0, 1.0),   # south, a door at 4..5
                        (3.0, 1.0, 0.6, 0.4, 0.0, 1.0)])                           # a cabinet


def test_a_corridor_is_its_walls_doorway_and_objects_not_slivers(tmp_path):
    t = np.arange(120) * 0.1
    drive = np.stack([t, 0.5 + 0.75 * t, 0.1 * np.sin(0.5 * t), 0.05 * np.cos(0.5 * t)], 1)
    seed = scenario_from_bag(robot_bag(tmp_path / "corridor", CORRIDOR, drive, timing=ScanTiming(increment=INC),
                                       tf_map=False))
    obs = seed.scenario.obstacles
    walls = [o for o in obs if isinstance(o, PolygonObstacle)]
    assert len(obs) <= 5, obs     # two south walls, the north wall with its cabinet, the bin
    north = [w for w in walls if obstacle_polygon(w).intersects(LineString([(1, 1.35), (9, 1.35)]))]
    south = [w for w in walls if obstacle_polygon(w).intersects(LineString([(0.5, -1.35), (9.5, -1.35)]))]
    assert len(north) == 1 and len(south) == 2
    door = box(4.1, -1.5, 4.9, -1.3)
    assert not any(obstacle_polygon(w).intersects(door) for w in south)      # the doorway stays open
    for w in walls:
        assert len(w.points) <= 32
    # the bin and the wall 0.2 m behind it are one outline (the robot cannot pass between): the beams
    # that did pass between them are the seed's few blocked ones
    assert seed.fit.median_error < 0.03 and seed.fit.blocked < 0.03 and seed.fit.warnings == []


def test_every_scan_unusable_is_an_error_naming_why(tmp_path):
    from ros_synthetic import BagOut, pose_msg, stamp

    path = tmp_path / "nan_angles"
    with BagOut(path) as bag:
        for i in range(20):
            t = 1.0 + 0.1 * i
            bag.write("/odom", "nav_msgs/msg/Odometry", t, {"header": {"stamp": stamp(t), "frame_id": "odom"},
                                                           "child_frame_id": "base_link",
                                                           "pose": {"pose": pose_msg(0.1 * i, 0.0, 0.0)}})
            bag.write("/scan", "sensor_msgs/msg/LaserScan", t, {
                "header": {"stamp": stamp(t), "frame_id": "laser"}, "angle_min": 0.0, "angle_increment": math.nan,
                "range_min": 0.05, "range_max": 10.0, "ranges": np.full(90, 2.0, np.float32)})
    with pytest.raises(BagImportError, match="every scan read on /scan is unusable: angle_min 0.0 / angle_increment "
                                             "nan is not a number"):
        scenario_from_bag(path)
