"""A seed's ``search:`` section: the failure search's space around the seed, declared like every
other section (``keys.py``) with a documented upper limit for every range and count. It is read
(``search_settings.py``) when the seed loads, so a plain run refuses ``motion_speed: [0.5, -0.5]``
too, with file and line, and again for settings given from Python (``SearchSpace(seed, overrides)``).

A range key (``obstacle_dx``) is an offset range [lo, hi] containing 0, or one number h >= 0
meaning [-h, h]; its ``target`` is the key whose value the offset moves, and the search keeps the
moved value within that key's range (search/space.py), so it never writes a scenario the loader
refuses. A fault range (``drift_per_metre``) may not reach beyond its target's span.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

from . import keys as K
from .keys import SCENARIO_LIMITS, Integer, Names, Number, Range, Rule, SizeRange, section
from .model import BOX, LIDAR, LOCALISATION, MOTION, POLYGON, POSE
from .terrain import RAMP, ROUGH, STEPS

RAMP_SLOPE = Number("slope", "deg", "a ramp's slope", ge=0, le=90.0)   # what terrain_slope moves

MAX_POSITION_OFFSET = 1000.0    # m: obstacle, start, goal, waypoint and corner offsets
MAX_SIZE_OFFSET = 100.0         # m
MAX_TIME_OFFSET = 3600.0        # s
MAX_SPEED_OFFSET = 100.0        # m/s
MAX_INSERT = 100                # inserted obstacles (each adds five parameters)
MAX_SIZE = 100.0                # m: min_size, insert_size
MAX_MARGIN = 1000.0             # m: insert_margin


def _span(key: K.Number) -> float:
    low, high = key.span
    return high - low


def _offset(name: str, unit: str, doc: str, default: tuple[float, float], limit: float, target: K.Key) -> Range:
    return Range(name, unit, doc, default=default, limit=limit, target=target)


_POSITION = "offsets drawn from [-h, h] or [lo, hi]"
RANGES = (
    _offset("obstacle_dx", "m", f"moves each obstacle along x ({_POSITION})", (-1.0, 1.0), MAX_POSITION_OFFSET,
            BOX["x"]),
    _offset("obstacle_dy", "m", "moves each obstacle along y", (-1.0, 1.0), MAX_POSITION_OFFSET, BOX["y"]),
    _offset("obstacle_size", "m", "added to box length and width and to twice a cylinder's radius",
            (-0.1, 0.3), MAX_SIZE_OFFSET, BOX["length"]),
    _offset("obstacle_yaw", "deg", "turns boxes, polygons and meshes", (-30.0, 30.0), 180.0, BOX["yaw"]),
    _offset("start_dx", "m", "moves the start along x (0: the start is not mutated)", (0.0, 0.0),
            MAX_POSITION_OFFSET, POSE["x"]),
    _offset("start_dy", "m", "moves the start along y", (0.0, 0.0), MAX_POSITION_OFFSET, POSE["y"]),
    _offset("start_yaw", "deg", "turns the start", (0.0, 0.0), 180.0, POSE["yaw"]),
    _offset("goal_dx", "m", "moves the goal along x", (0.0, 0.0), MAX_POSITION_OFFSET, POSE["x"]),
    _offset("goal_dy", "m", "moves the goal along y", (0.0, 0.0), MAX_POSITION_OFFSET, POSE["y"]),
    _offset("goal_yaw", "deg", "turns the goal", (0.0, 0.0), 180.0, POSE["yaw"]),
    _offset("waypoint_dx", "m", "moves each waypoint along x (each its own offset)", (0.0, 0.0),
            MAX_POSITION_OFFSET, POSE["x"]),
    _offset("waypoint_dy", "m", "moves each waypoint along y", (0.0, 0.0), MAX_POSITION_OFFSET, POSE["y"]),
    _offset("polygon_vertex", "m", "moves each polygon corner along x and y (0: off)", (0.0, 0.0),
            MAX_POSITION_OFFSET, POLYGON["x"]),
    _offset("motion_start", "s", "added to a moving obstacle's start time (never below 0)", (-5.0, 5.0),
            MAX_TIME_OFFSET, MOTION["start"]),
    _offset("motion_speed", "m/s", "added to a moving obstacle's speed (never below 0.1 m/s)", (-0.5, 0.5),
            MAX_SPEED_OFFSET, MOTION["speed"]),
    _offset("lidar_noise_per_metre", "m/m", "added to robot.lidar.noise_per_metre (0: off)", (0.0, 0.0),
            _span(LIDAR["noise_per_metre"]), LIDAR["noise_per_metre"]),
    _offset("lidar_dropout_at_max", "", "added to robot.lidar.dropout_at_max (0: off)", (0.0, 0.0),
            _span(LIDAR["dropout_at_max"]), LIDAR["dropout_at_max"]),
    _offset("lidar_spurious", "", "added to robot.lidar.spurious (0: off)", (0.0, 0.0),
            _span(LIDAR["spurious"]), LIDAR["spurious"]),
    _offset("drift_per_metre", "m/√m", "added to robot.localisation.drift_per_metre (0: off)", (0.0, 0.0),
            _span(LOCALISATION["drift_per_metre"]), LOCALISATION["drift_per_metre"]),
    _offset("drift_per_second", "m/√s", "added to robot.localisation.drift_per_second (0: off)", (0.0, 0.0),
            _span(LOCALISATION["drift_per_second"]), LOCALISATION["drift_per_second"]),
    _offset("yaw_drift_per_metre", "deg/√m", "added to robot.localisation.yaw_drift_per_metre (0: off)",
            (0.0, 0.0), _span(LOCALISATION["yaw_drift_per_metre"]), LOCALISATION["yaw_drift_per_metre"]),
    # terrain (issue 25): each element moved; by its kind steeper, higher or rougher
    _offset("terrain_dx", "m", "moves each terrain element along x (a platform's edge, a ramp's place)",
            (-1.0, 1.0), MAX_POSITION_OFFSET, RAMP["x"]),
    _offset("terrain_dy", "m", "moves each terrain element along y", (-1.0, 1.0), MAX_POSITION_OFFSET, RAMP["y"]),
    _offset("terrain_yaw", "deg", "turns each terrain element (0: off)", (0.0, 0.0), 180.0, RAMP["yaw"]),
    _offset("terrain_size", "m", "added to each terrain element's length and width (a flight of steps: its "
            "width; 0: off)", (0.0, 0.0), MAX_SIZE_OFFSET, RAMP["length"]),
    _offset("terrain_slope", "deg", "added to a ramp's slope, its high end kept where it is (between 1 and 80 deg)",
            (-5.0, 5.0), 80.0, RAMP_SLOPE),
    _offset("terrain_rise", "m", "added to a step's rise, a platform's height, a pit's depth (never below 5 mm)",
            (-0.05, 0.1), MAX_SIZE_OFFSET, STEPS["rise"]),
    _offset("terrain_roughness", "m", "added to rough ground's amplitude (never below 5 mm)", (-0.02, 0.05),
            MAX_SIZE_OFFSET, ROUGH["amplitude"]),
)
MAX_PARTS = int(2 * SCENARIO_LIMITS["max_obstacles"] + SCENARIO_LIMITS["max_waypoints"]) + 4

SEARCH = section(None, "search", "the failure search's space around this seed", [
    *RANGES,
    Number("min_size", "m", "sizes never shrink below this", gt=0, le=MAX_SIZE, default=0.05),
    Names("frozen", "", "parts the search leaves as they are: obstacle and terrain element names, start, "
          "goal, robot, waypoints, waypoints[i]", max=MAX_PARTS, default=()),
    Integer("insert", "", "at most this many new box obstacles (0: none)", ge=0, le=MAX_INSERT, default=2),
    SizeRange("insert_size", "m", "side length of an inserted box: [lo, hi] or one number", le=MAX_SIZE,
              default=(0.3, 1.0)),
    Number("insert_margin", "m", "inserted boxes lie in the route's bounding box grown by this", ge=0,
           le=MAX_MARGIN, default=1.0),
    Integer("remove", "", "at most this many of the seed's obstacles may be removed", ge=0,
            le=int(SCENARIO_LIMITS["max_obstacles"]), default=0),
], what="the search settings (a mapping)", rules=[
    Rule("frozen names parts of this seed; remove is at most its number of obstacles; its obstacles plus "
         "insert stay within the obstacle limit; insert_size is [lo, hi] with lo <= hi", None),
])


@dataclass(frozen=True)
class SearchSettings:
    """A ``search:`` section, checked, with its defaults: ``bounds`` by range key (lo, hi)."""
    bounds: Mapping[str, tuple[float, float]]
    frozen: frozenset
    min_size: float
    insert: int
    insert_size: tuple[float, float]
    insert_margin: float
    remove: int
