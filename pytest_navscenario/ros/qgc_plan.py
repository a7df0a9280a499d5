"""QGroundControl ``.plan`` mission files (JSON): the home position and the positional mission
items, converted to local metres around the home.

The conversion is PX4's own (``map_projection_project``: azimuthal equidistant around the home,
Earth radius 6 371 000 m), turned to the scenario's axes: x east, y north (ENU, as Gazebo and
Aerialist's obstacle positions are). Items without a position (camera, speed and other ``DO_``
commands) and complex items (surveys, corridor scans) are counted in the notes, never dropped
without a word.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from ..core.errors import NavScenarioError

EARTH_RADIUS = 6_371_000.0  # m, PX4's CONSTANTS_RADIUS_OF_EARTH
# MAV_CMD ids of mission items that fly to a position (params 5, 6, 7 = lat, lon, alt)
NAV_COMMANDS = {16: "WAYPOINT", 17: "LOITER_UNLIM", 18: "LOITER_TURNS", 19: "LOITER_TIME",
                21: "LAND", 22: "TAKEOFF", 31: "LOITER_TO_ALT"}
GLOBAL_FRAMES = (0, 3, 5, 6, 10, 11)  # MAV_FRAME_GLOBAL* (lat/lon in degrees, any altitude reference)


class PlanError(NavScenarioError):
    """A .plan file cannot be read (not JSON, not a QGroundControl plan, no home position)."""


@dataclass
class Plan:
    """The mission's positions in local metres (x east, y north) around ``home`` (lat, lon, alt)."""
    path: Path
    home: tuple[float, float, float]
    points: list[tuple[float, float, str]]        # x, y, item kind, in mission order
    notes: list[str] = field(default_factory=list)


def local_xy(lat: float, lon: float, lat0: float, lon0: float) -> tuple[float, float]:
    """(east, north) metres of ``lat, lon`` around ``lat0, lon0`` (PX4's azimuthal equidistant projection)."""
    la, lo, la0, lo0 = (math.radians(v) for v in (lat, lon, lat0, lon0))
    cos_dlon = math.cos(lo - lo0)
    arg = max(-1.0, min(1.0, math.sin(la0) * math.sin(la) + math.cos(la0) * math.cos(la) * cos_dlon))
    c = math.acos(arg)
    k = c / math.sin(c) if abs(c) > 1e-12 else 1.0
    north = k * (math.cos(la0) * math.sin(la) - math.sin(la0) * math.cos(la) * cos_dlon) * EARTH_RADIUS
    east = k * math.cos(la) * math.sin(lo - lo0) * EARTH_RADIUS
    return east, north


def read_plan(path: str | Path) -> Plan:
    """The home position and positional items of a QGroundControl plan; errors name file and line."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise PlanError(f"{path}:{exc.lineno}: not valid JSON ({exc.msg}); expected a QGroundControl .plan") from None
    except RecursionError:
        raise PlanError(f"{path}: not valid JSON (nested too deeply); expected a QGroundControl .plan") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PlanError(f"{path}: cannot read: {exc}") from None
    mission = doc.get("mission") if isinstance(doc, dict) else None
    if not isinstance(mission, dict) or doc.get("fileType") not in (None, "Plan"):
        raise PlanError(f"{path}: not a QGroundControl plan (expected \"fileType\": \"Plan\" and a \"mission\" object)")
    home = mission.get("plannedHomePosition")
    if not (isinstance(home, list) and len(home) >= 2 and all(_is_num(v) for v in home[:2])):
        raise PlanError(f"{path}: mission.plannedHomePosition must be [lat, lon, alt], got {home!r}")
    lat0, lon0 = float(home[0]), float(home[1])
    plan = Plan(path=path, home=(lat0, lon0, float(home[2]) if len(home) > 2 and _is_num(home[2]) else 0.0), points=[])
    skipped: dict[str, int] = {}
    for i, item in enumerate(mission.get("items") or []):
        kind = _position_item(item)
        if kind is None:
            label = (f"{item.get('complexItemType', 'complex')} item" if isinstance(item, dict)
                     and item.get("type") == "ComplexItem" else
                     f"command {item.get('command')}" if isinstance(item, dict) else "malformed item")
            skipped[label] = skipped.get(label, 0) + 1
            continue
        lat, lon = float(item["params"][4]), float(item["params"][5])
        x, y = local_xy(lat, lon, lat0, lon0)
        plan.points.append((x, y, kind))
    if skipped:
        plan.notes.append(f"{path.name}: mission items without a position not carried over: "
                          + ", ".join(f"{n} x {k}" for k, n in sorted(skipped.items())))
    return plan


def _position_item(item: object) -> str | None:
    """The kind of a SimpleItem that flies to a global position, else None."""
    if not isinstance(item, dict) or item.get("type") != "SimpleItem":
        return None
    kind = NAV_COMMANDS.get(item.get("command"))
    params = item.get("params")
    if kind is None or item.get("frame") not in GLOBAL_FRAMES or not isinstance(params, list) or len(params) < 6:
        return None
    if not (_is_num(params[4]) and _is_num(params[5])) or (params[4] == 0 and params[5] == 0):
        return None  # lat/lon 0, 0: "here" (PX4 takes off where it stands)
    return kind


def _is_num(v: object) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
