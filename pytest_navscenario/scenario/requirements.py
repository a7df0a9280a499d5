"""Requirements (issue 34): the team's own rules in signal temporal logic, and the signals they name.

A scenario (or a shared requirements file, ``--nav-requirements``) holds two sections, declared
here in ``keys.py`` form so the loader, the dump and the JSON Schema know them::

    signals:
      - {name: d_walker, distance_to: walker}              # footprint to obstacle 'walker', m
      - {name: dock, inside: {x: 8, y: 0, radius: 1}}     # signed distance, > 0 inside, m
    requirements:
      - {name: keep-away-from-people, spec: "always (d_walker >= 0.8)"}
      - {name: slow-near-people, spec: "always ((d_walker < 1.5) implies (speed <= 0.3))", scale: 0.5}

A formula is RTAMT's discrete-time STL (``pytest_navscenario.stl``); its intervals are seconds.
It may name the built-in signals (``BUILTIN_SIGNALS``, computed every control tick by
``verdict/signals.py``), ``d_waypoint1`` .. ``d_waypointN`` for the mission's waypoints, and the
scenario's declared signals. Formulas are parsed when the file loads (``requirement_reading.py``).
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

from .keys import Listed, Names, Number, Points, Rule, Sub, Text, section

#: name -> (unit, what it is); sampled at every control tick of the recorded trajectory.
BUILTIN_SIGNALS: Mapping[str, tuple[str, str]] = MappingProxyType({
    "time": ("s", "the tick's time since the start"),
    "x": ("m", "the robot's position along x (world frame)"),
    "y": ("m", "the robot's position along y"),
    "heading": ("deg", "the robot's yaw, -180 to 180"),
    "speed": ("m/s", "the robot's planar speed (measured)"),
    "yaw_rate": ("deg/s", "the robot's turn rate, signed (measured)"),
    "acceleration": ("m/s²", "the planar speed's rate of change"),
    "command_speed": ("m/s", "the planar speed the planner commanded (after the drive's limits)"),
    "clearance": ("m", "the footprint's distance to the nearest obstacle (0 on contact; moving ones "
                  "where they are at the tick)"),
    "d_goal": ("m", "the robot centre's distance to the goal"),
    "pitch": ("deg", "the chassis' pitch (0 for the planar body)"),
    "roll": ("deg", "the chassis' roll (0 for the planar body)"),
    "height": ("m", "the base's height above its start (0 for the planar body)"),
    "lidar_min": ("m", "the lidar's shortest range at the tick, as the planner saw it"),
})
WAYPOINT_SIGNAL = "d_waypoint"      # d_waypoint1 .. d_waypointN: distance to each waypoint, m


def waypoint_signals(count: int) -> tuple[str, ...]:
    return tuple(f"{WAYPOINT_SIGNAL}{i}" for i in range(1, count + 1))


@dataclass(frozen=True)
class Region:
    """A circle (``radius``) around (x, y), or a polygon (``points``, world coordinates)."""
    x: float = 0.0
    y: float = 0.0
    radius: float | None = None
    points: tuple[tuple[float, float], ...] = ()


REGION = section(Region, "signals[].inside", "a circle (x, y, radius) or a polygon (points)", [
    Number("x", "m", "the circle's centre along x", default=0.0),
    Number("y", "m", "the circle's centre along y", default=0.0),
    Number("radius", "m", "the circle's radius (a circle)", gt=0, nullable=True, default=None),
    Points("points", "m", "three or more corners [x, y] in world coordinates (a polygon)", min=3, max=1000,
           default=()),
], rules=[Rule("exactly one of radius and points", None)])


@dataclass(frozen=True)
class Signal:
    """A declared signal: exactly one of the four ways of computing it is set."""
    name: str
    distance_to: tuple[str, ...] = ()       # obstacle names or shell patterns (person*): the nearest, m
    inside: Region | None = None            # signed distance of the robot centre, > 0 inside, m
    speed_toward: str = ""                  # closing speed on an obstacle (pattern: the nearest), m/s
    function: str = ""                      # "pkg.module:function" (trajectory, scenario, tick_t) -> values

    @property
    def kind(self) -> str:
        for kind in ("distance_to", "inside", "speed_toward", "function"):
            if getattr(self, kind):
                return kind
        return ""


SIGNAL_KINDS = ("distance_to", "inside", "speed_toward", "function")

SIGNAL = section(Signal, "signals[]", "a signal a requirement may name", [
    Text("name", "", "the name formulas use: letters, digits and '_', not starting with a digit, not a "
         "built-in signal's name", example="name: d_walker"),
    Names("distance_to", "m", "the footprint's distance to the nearest of these obstacles (names, or "
          "patterns such as person*)", max=5000, default=()),
    Sub("inside", "m", "signed distance of the robot centre to a region: > 0 inside, < 0 outside",
        section=REGION, default=None),
    Text("speed_toward", "m/s", "the robot's speed toward this obstacle (the nearest, for a pattern): "
         "> 0 approaching", default=""),
    Text("function", "", "a Python function 'pkg.module:function' of (trajectory, scenario, tick_t) "
         "returning one value per tick (looked up like planners)", default=""),
], what="a signal (a mapping)",
    rules=[Rule("exactly one of distance_to, inside, speed_toward, function", None)])


@dataclass(frozen=True)
class Requirement:
    """One rule: ``spec`` is an STL formula (its canonical text once loaded); ``scale``: how much
    robustness counts as far from violated, for the search's graded fitness (None: the
    signal's range in the seed episode)."""
    name: str
    spec: str
    scale: float | None = None
    source: str = ""        # where it was written (a shared file's path; "" for the scenario's own)


REQUIREMENT = section(Requirement, "requirements[]", "a rule every episode is checked against", [
    Text("name", "", "names the requirement in messages, reports and cause signatures", name_rules=True,
         example="name: keep-away-from-people"),
    Text("spec", "", "an STL formula in RTAMT's syntax over the signals; intervals in seconds",
         example='spec: "always (clearance >= 0.3)"'),
    Number("scale", "", "robustness this large counts as far from violated (the search's graded "
           "fitness; in the formula's units)", gt=0, nullable=True, default=None),
], what="a requirement (a mapping)")

MAX_REQUIREMENTS = 100
MAX_SIGNALS = 100
SIGNALS = Listed("signals", "", "signals the requirements name, beside the built-in ones", section=SIGNAL,
                 max=MAX_SIGNALS, what="signals", default=())
REQUIREMENTS = Listed("requirements", "", "rules in signal temporal logic every episode is checked against",
                      section=REQUIREMENT, max=MAX_REQUIREMENTS, what="requirements", default=())
