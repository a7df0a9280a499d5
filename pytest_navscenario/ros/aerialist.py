"""Aerialist test definitions (the UAV test bench the reference paper extends) as scenario parts.

Carried over: ``simulation.obstacles`` in both encodings (``{size: {l, w, h}, position: {x, y, z,
r}, shape}`` mappings or a flat ``[l, w, h, x, y, z, r, ...]`` list); boxes are centred on their
position, the rotation is ``r`` (Aerialist also writes it as ``angle``; ``yaw`` is read too) in
degrees; ``shape: TREE`` becomes a cylinder (radius half the smaller of l and w, or 0.5 m).
The start, goal and waypoints come from the QGroundControl ``.plan`` named by
``robot.mission_file`` (``drone.mission_file`` in older tests), looked up beside the test.
Every other key is listed with its file and line as not carried over, with the reason.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..core.errors import NavScenarioError
from ..scenario.model import BoxObstacle, CylinderObstacle, Obstacle, Pose

ROTATION_KEYS = ("r", "angle", "yaw")
BOX_SHAPES = ("BOX", "APARTMENT")
TREE_RADIUS = 0.5  # m, a tree without a size: a pine trunk with its lower branches
# keys with a known meaning in Aerialist that have none in a 2D ground scenario, and why
NOT_CARRIED = {
    "port": "the PX4 connection", "params_file": "PX4 parameters are not simulated",
    "simulator": "the simulation here is MuJoCo", "speed": "simulation speed", "headless": "GUI setting",
    "home_position": "a geographic position, and no mission plan to place it against", "wind": "wind is not simulated",
    "commands_file": "runtime commands are not replayed", "log_file": "the reference flight log (.ulg) is not read",
    "variable": "the compared flight variable", "agent": "test execution settings",
}


class AerialistError(NavScenarioError):
    """An Aerialist test file cannot be imported (not YAML, not a test, bad value)."""


@dataclass
class AerialistTest:
    """What an Aerialist test carries over, and what it does not (``file:line: key: why`` lines)."""
    obstacles: list[Obstacle]
    mission_file: Path | None = None          # the .plan, resolved (None when absent or not found)
    mission_key: str = ""                     # "robot.mission_file" with its line, for messages
    home_position: tuple[float, float] | None = None   # simulation.home_position lat, lon: where the drone starts
    home_key: str = ""                        # "file:line: simulation.home_position", for messages
    dropped: list[str] = field(default_factory=list)


class _Doc:
    """A parsed YAML file with the line of every node, for messages."""

    def __init__(self, path: Path):
        import yaml

        self.path = path
        self.dropped: list[str] = []   # "file:line: key: not carried over (why)"
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise AerialistError(f"{path}: no such file") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise AerialistError(f"{path}: cannot read: {exc}") from None
        try:
            self.node = yaml.compose(text)
            self.data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            where = f":{mark.line + 1}" if mark else ""
            raise AerialistError(f"{path}{where}: not valid YAML ({getattr(exc, 'problem', exc)})") from None

    def at(self, *keys: Any) -> str:
        """``path:line`` of the node at ``keys`` (``path`` alone when it is not there)."""
        import yaml

        cur = self.node
        for key in keys:
            if isinstance(cur, yaml.MappingNode):
                cur = next((v for k, v in cur.value if k.value == key), None)
            elif isinstance(cur, yaml.SequenceNode) and isinstance(key, int) and key < len(cur.value):
                cur = cur.value[key]
            else:
                cur = None
            if cur is None:
                return str(self.path)
        return f"{self.path}:{cur.start_mark.line + 1}"

    def number(self, value: Any, name: str, *keys: Any) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise AerialistError(f"{self.at(*keys)}: {name}: expected a number, got {value!r}"
                                 + (" (a template placeholder?)" if isinstance(value, str) else ""))
        return float(value)


def read_aerialist(path: str | Path) -> AerialistTest:
    """Obstacles, the mission file and the list of keys not carried over of an Aerialist test."""
    doc = _Doc(Path(path))
    data = doc.data
    if not isinstance(data, dict) or not isinstance(data.get("simulation"), dict):
        raise AerialistError(f"{doc.path}: not an Aerialist test: no 'simulation' mapping "
                             f"(expected simulation.obstacles)")
    obstacles = data["simulation"].get("obstacles")
    test = AerialistTest(obstacles=_obstacles(doc, obstacles) if obstacles is not None else [],
                         dropped=doc.dropped)
    for section, value in data.items():
        if not isinstance(value, dict) or section not in ("robot", "drone", "simulation", "mission", "assertion"):
            test.dropped.append(f"{doc.at(section)}: {section}: not carried over "
                                f"({NOT_CARRIED.get(section, 'no meaning in a 2D ground scenario')})")
            continue
        for key in value:
            if (section, key) == ("simulation", "obstacles"):
                continue
            if (section, key) == ("simulation", "home_position") and _lat_lon(value[key]) is not None:
                test.home_position = _lat_lon(value[key])
                test.home_key = f"{doc.at(section, key)}: simulation.home_position"
                continue
            if key == "mission_file" and section in ("robot", "drone"):
                test.mission_key = f"{doc.at(section, key)}: {section}.mission_file"
                test.mission_file = _find_plan(doc.path, value[key])
                continue
            test.dropped.append(f"{doc.at(section, key)}: {section}.{key}: not carried over "
                                f"({NOT_CARRIED.get(key, 'no meaning in a 2D ground scenario')})")
    return test


def _lat_lon(value: Any) -> tuple[float, float] | None:
    """(lat, lon) of a ``[lat, lon, alt]`` list of numbers, else None (e.g. a template placeholder)."""
    if isinstance(value, list) and len(value) >= 2 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value[:2]):
        return float(value[0]), float(value[1])
    return None


def _find_plan(test_path: Path, value: Any) -> Path | None:
    """The mission file: as written relative to the test, else its name beside the test."""
    if not isinstance(value, str) or not value.strip():
        return None
    written = Path(value)
    for candidate in (test_path.parent / written, test_path.parent / written.name, written):
        if candidate.is_file():
            return candidate
    return None


def aerialist_obstacles(path: str | Path) -> list[Obstacle]:
    """The obstacles of an Aerialist test YAML (both encodings); errors name file, line and field."""
    return read_aerialist(path).obstacles


def _obstacles(doc: _Doc, obstacles: Any) -> list[Obstacle]:
    if not isinstance(obstacles, list):
        raise AerialistError(f"{doc.at('simulation', 'obstacles')}: simulation.obstacles must be a list")
    if obstacles and not isinstance(obstacles[0], dict):
        if len(obstacles) % 7:
            raise AerialistError(f"{doc.at('simulation', 'obstacles')}: simulation.obstacles as a flat list "
                                 f"needs 7 numbers per box (l,w,h,x,y,z,r), got {len(obstacles)} values")
        out = []
        for i in range(0, len(obstacles), 7):
            vals = [doc.number(v, f"simulation.obstacles[{i + j}]", "simulation", "obstacles", i + j)
                    for j, v in enumerate(obstacles[i:i + 7])]
            out.append(_obstacle(doc, len(out), *vals, shape="BOX"))
        return out
    return [_mapping_obstacle(doc, i, ob) for i, ob in enumerate(obstacles)]


def _mapping_obstacle(doc: _Doc, i: int, ob: Any) -> Obstacle:
    keys = ("simulation", "obstacles", i)
    where = f"simulation.obstacles[{i}]"
    if not isinstance(ob, dict) or not isinstance(ob.get("position"), dict) or \
            not isinstance(ob.get("size", {}), dict):
        raise AerialistError(f"{doc.at(*keys)}: {where}: expected {{size: {{l, w, h}}, position: {{x, y, z, r}}}}")
    shape = str(ob.get("shape", "BOX")).upper()
    size, pos = ob.get("size", {}), ob["position"]
    if "size" not in ob and shape not in ("TREE",):
        raise AerialistError(f"{doc.at(*keys)}: {where}.size is missing")
    for k in ob:
        if k not in ("size", "position", "shape"):
            doc.dropped.append(f"{doc.at(*keys, k)}: {where}.{k}: not carried over (unknown obstacle key)")
    for part, src, known in (("size", size, ("l", "w", "h")), ("position", pos, ("x", "y", "z") + ROTATION_KEYS)):
        for k in src:
            if k not in known:
                doc.dropped.append(f"{doc.at(*keys, part, k)}: {where}.{part}.{k}: not carried over (unknown key)")
    rot = [k for k in ROTATION_KEYS if k in pos]
    if len(rot) > 1:
        raise AerialistError(f"{doc.at(*keys, 'position')}: {where}.position: the rotation is given twice "
                             f"({' and '.join(rot)}); keep one")
    vals = []
    for part, src, name in (("size", size, "l"), ("size", size, "w"), ("size", size, "h"),
                            ("position", pos, "x"), ("position", pos, "y"), ("position", pos, "z"),
                            ("position", pos, rot[0] if rot else "r")):
        if name not in src:
            if name in ("z", "r") or shape == "TREE":
                vals.append(math.nan if part == "size" else 0.0)
                continue
            raise AerialistError(f"{doc.at(*keys, part)}: {where}.{part}.{name} is missing")
        vals.append(doc.number(src[name], f"{where}.{part}.{name}", *keys, part, name))
    if vals[5] != 0:
        doc.dropped.append(f"{doc.at(*keys, 'position', 'z')}: {where}.position.z = {vals[5]:g}: not carried "
                               f"over (obstacles stand on the ground here)")
    if shape not in BOX_SHAPES + ("TREE",):
        raise AerialistError(f"{doc.at(*keys, 'shape')}: {where}.shape: {ob.get('shape')!r} is not an Aerialist "
                             f"shape (BOX, APARTMENT, TREE)")
    return _obstacle(doc, i, *vals, shape=shape)


def _obstacle(doc: _Doc, i: int, l: float, w: float, h: float, x: float, y: float, z: float, r: float,
              shape: str) -> Obstacle:
    if shape == "TREE":
        sizes = [v for v in (l, w) if math.isfinite(v) and v > 0]
        radius = min(sizes) / 2 if sizes else TREE_RADIUS
        height = h if math.isfinite(h) and h > 0 else None
        return CylinderObstacle(name=f"tree{i + 1}", x=_num(x), y=_num(y), radius=_num(radius),
                                **({"height": _num(height)} if height else {}))
    if l <= 0 or w <= 0 or h <= 0:
        raise AerialistError(f"{doc.path}: simulation.obstacles[{i}]: size must be > 0, got l={l} w={w} h={h}")
    return BoxObstacle(name=f"box{i + 1}", x=_num(x), y=_num(y), length=_num(l), width=_num(w),
                       yaw=_num(r), height=_num(h))


def mission_from_plan(plan_points: list[tuple[float, float, str]], min_step: float = 0.5,
                      start: tuple[float, float] = (0.0, 0.0)) -> tuple[Pose, Pose, tuple[Pose, ...]] | None:
    """Start at ``start`` (the plan's home, the local origin, unless the test moves it), waypoints,
    goal at the last position of the plan; points closer than ``min_step`` to the previous one are
    merged. None when the plan goes nowhere."""
    pts = [(float(start[0]), float(start[1]))]
    for x, y, _ in plan_points:
        if math.hypot(x - pts[-1][0], y - pts[-1][1]) >= min_step:
            pts.append((x, y))
    if len(pts) < 2:
        return None

    def heading(a, b) -> float:
        return _num(math.degrees(math.atan2(b[1] - a[1], b[0] - a[0])), 2)

    first = Pose(_num(pts[0][0]), _num(pts[0][1]), heading(pts[0], pts[1]))
    goal = Pose(_num(pts[-1][0]), _num(pts[-1][1]), heading(pts[-2], pts[-1]))
    return first, goal, tuple(Pose(_num(x), _num(y)) for x, y in pts[1:-1])


def _num(v: float, nd: int = 4) -> float:
    return float(round(float(v), nd)) + 0.0
