"""Scenario YAML: load and validate, with file:line errors (writing is in dump.py).

    load_scenario(path)                 -> Scenario   name/family default to file stem / folder name
    loads_scenario(text, source=None, *, name=None, family=None) -> Scenario
    scenario_from_dict(data, source=None) -> Scenario
    check_scenario(scenario)                          semantic checks only (for generated scenarios)
    looks_like_scenario(text_or_mapping) -> bool      cheap test for collectors
    SCENARIO_LIMITS                                   the documented limits for hostile files

Every problem raises ``ScenarioError`` naming the file, the line, the dotted field and a fix.
Parsing has ``yaml.safe_load`` semantics (see ``yaml_tree``), plus one convenience: an unquoted
number in exponent form that YAML 1.1 reads as a string (``1e-3``, ``2.5e3``) is accepted where a
number is expected.
"""
from __future__ import annotations

import codecs
import difflib
import math
import numbers
import os
import re
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping


from ..core.errors import ScenarioError
from . import keys as K
from .format import SCENARIO, SUPPORTED_VERSIONS, key_homes
from .keys import SCENARIO_LIMITS
from .model import (  # noqa: F401  (DRIVES ... PERSON_SPEED: re-exported, they used to live here)
    DRIVES,
    FOOTPRINT,
    LATENCY,
    LIDAR,
    LIMITS,
    LOCALISATION,
    MAX_POLYGON_POINTS,
    MISSION,
    MOTION,
    MOTION_MODES,
    OBSTACLES,
    PERSON_HEIGHT,
    PERSON_RADIUS,
    PERSON_SPEED,
    POSE,
    REFERENCE,
    REFERENCE_COMPARE,
    ROBOT,
    SAFETY,
    SCHEMA_VERSION,
    SHAPES,
    SIMULATION,
    GOAL_TOLERANCE,
    Mark,
    MeshObstacle,
    Mission,
    Motion,
    Obstacle,
    Pose,
    Reference,
    Robot,
    Scenario,
    Simulation,
)
from .yaml_tree import YMap, YNode, YScalar, YSeq, describe, from_plain, parse_yaml, to_plain

_MAX_ABS = float(SCENARIO_LIMITS["max_abs_value"])
_LIST_LIMITS = {"obstacles": (int(SCENARIO_LIMITS["max_obstacles"]), "obstacles")}  # refused while parsing
_REQUIRED = K.REQUIRED
_NUMBER_WORD = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+")  # 1e-3: a string in YAML 1.1
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")

# The keys of each section, as declared (model.py, format.py); kept under their old names.
TOP_KEYS = SCENARIO.names
ROBOT_KEYS = ROBOT.names
FOOTPRINT_KEYS = FOOTPRINT.names
LIMITS_KEYS = LIMITS.names
LIDAR_KEYS = LIDAR.names
LOCALISATION_KEYS = LOCALISATION.names
LATENCY_KEYS = LATENCY.names
SAFETY_KEYS = SAFETY.names
MISSION_KEYS = MISSION.names
POSE_KEYS = POSE.names
TOLERANCE_KEYS = GOAL_TOLERANCE.names
MOTION_KEYS = MOTION.names
SIMULATION_KEYS = SIMULATION.names
REFERENCE_KEYS = REFERENCE.names
OBSTACLE_TYPES = OBSTACLES.type_names
TYPE_KEYS = {e.type: ("type",) + e.section.names for e in OBSTACLES.types}
_KEY_HOMES = key_homes()
_ALIASES = {  # common synonyms -> the spelling the format uses (for the hint)
    "omnidirectional": "omni", "holonomic": "omni", "differential": "diff", "diff-drive": "diff",
    "rectangle": "box", "rect": "box", "cuboid": "box", "square": "box", "cyl": "cylinder",
    "circle": "cylinder", "disc": "cylinder", "disk": "cylinder", "round": "circle",
}


# --------------------------------------------------------------------------- reading helpers

class _Ctx:
    """Where we are: the source file (for messages) and the line of every field read."""

    def __init__(self, source: str | None):
        self.source = source
        self.lines: dict[str, int | None] = {}

    def fail(self, message: str, field: str | None, line: int | None, hint: str | None = None) -> ScenarioError:
        return ScenarioError(message, path=self.source, line=line, field=field, hint=hint)


def _did_you_mean(word: Any, options: tuple[str, ...]) -> str:
    text = str(word)
    alias = _ALIASES.get(text.lower())
    if alias in options:
        return f"did you mean '{alias}'?"
    match = difflib.get_close_matches(text.lower(), options, n=1, cutoff=0.6)
    if match:
        return f"did you mean '{match[0]}'?"
    return "use one of: " + ", ".join(options)


def _unknown_key_hint(key: Any, keys: tuple[str, ...], path: str) -> str:
    """Did-you-mean among this section's keys, else where the key belongs if it is known elsewhere."""
    text = str(key)
    if not difflib.get_close_matches(text.lower(), keys, n=1, cutoff=0.6):
        homes = [home for home, section_keys in _KEY_HOMES
                 if text in section_keys and home != path and not (home == "obstacles[]" and path.startswith("obstacles["))]
        if homes:
            return f"'{text}' belongs under '{homes[0]}'" + (f" (or '{homes[1]}')" if len(homes) > 1 else "")
    return _did_you_mean(key, keys)


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


class _Section:
    """A YAML mapping with a known set of keys; typed getters that raise located errors."""

    def __init__(self, ctx: _Ctx, node: YNode | None, path: str, keys: tuple[str, ...], *,
                 line: int | None = None, what: str = "a mapping"):
        self.ctx, self.path, self.keys = ctx, path, keys
        if not isinstance(node, YMap):
            raise ctx.fail(f"expected {what}, got {describe(node) if node is not None else 'nothing'}",
                           path or None, line if line is not None else (node.line if node is not None else None),
                           f"write it as 'key: value' lines with keys from: {', '.join(keys)}")   # the key's own line
        self.node = node
        self.line = line if line is not None else node.line
        for key, (key_line, _) in node.items.items():
            if key not in keys:
                raise ctx.fail(f"unknown key {str(key)!r}", _join(path, str(key)), key_line,
                               _unknown_key_hint(key, keys, path))

    def has(self, key: str) -> bool:
        return key in self.node.items

    def get(self, key: str) -> YNode | None:
        item = self.node.items.get(key)
        if item is None:
            return None
        field = _join(self.path, key)
        self.ctx.lines[field] = item[0] if item[0] is not None else item[1].line
        return item[1]

    def line_of(self, key: str) -> int | None:
        item = self.node.items.get(key)
        if item is None:
            return self.line
        return item[0] if item[0] is not None else item[1].line

    def missing(self, key: str, example: str) -> ScenarioError:
        return self.ctx.fail(f"missing required field '{key}'", _join(self.path, key), self.line,
                             f"add '{example}'" + (f" under '{self.path}'" if self.path else ""))

    def number(self, key: str, default: Any = _REQUIRED, *, low: float | None = None,
               low_open: bool = False, high: float | None = None, example: str | None = None) -> float:
        item = self.node.items.get(key)    # get() and line_of() in one look-up: the loader's commonest call
        node = None if item is None else item[1]
        if node is None or (isinstance(node, YScalar) and node.value is None and default is None):
            if item is not None:
                self.ctx.lines[_join(self.path, key)] = item[0] if item[0] is not None else node.line
            if default is _REQUIRED:
                raise self.missing(key, example or f"{key}: <number>")
            return default
        field = _join(self.path, key)
        line = item[0] if item[0] is not None else node.line
        self.ctx.lines[field] = line
        return _number(self.ctx, node, field, line, low=low, low_open=low_open, high=high)

    def integer(self, key: str, default: Any, *, low: int, high: int) -> int:
        node = self.get(key)
        if node is None:
            if default is _REQUIRED:
                raise self.missing(key, f"{key}: <whole number>")
            return default
        field, line = _join(self.path, key), self.line_of(key)
        value = node.value if isinstance(node, YScalar) else None
        if isinstance(value, numbers.Real) and not isinstance(value, numbers.Integral) and math.isfinite(value) \
                and float(value).is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise self.ctx.fail(f"expected a whole number, got {describe(node)}", field, line,
                                f"write a whole number between {low} and {high}")
        if not low <= value <= high:
            raise self.ctx.fail(f"must be between {low} and {high}, got {value}", field, line,
                                f"write a whole number from {low} to {high}")
        return int(value)

    def string(self, key: str, default: Any, *, nonempty: bool = True) -> str:
        node = self.get(key)
        if node is None or (isinstance(node, YScalar) and node.value is None):  # 'description:' = absent
            return default
        field, line = _join(self.path, key), self.line_of(key)
        value = node.value if isinstance(node, YScalar) else None
        if not isinstance(value, str):
            raise self.ctx.fail(f"expected a string, got {describe(node)}", field, line,
                                "quote it, e.g. " + f"{key}: \"text\"")
        if nonempty and not value.strip():
            raise self.ctx.fail("must not be empty", field, line, f"write a {key} or remove the line")
        return value

    def boolean(self, key: str, default: bool) -> bool:
        node = self.get(key)
        if node is None:
            return default
        value = node.value if isinstance(node, YScalar) else None
        if not isinstance(value, bool):
            raise self.ctx.fail(f"expected true or false, got {describe(node)}", _join(self.path, key),
                                self.line_of(key), "write true or false")
        return value

    def choice(self, key: str, options: tuple[str, ...], default: Any) -> str:
        node = self.get(key)
        if node is None:
            if default is _REQUIRED:
                raise self.missing(key, f"{key}: {options[0]}")
            return default
        value = node.value if isinstance(node, YScalar) else None
        if value not in options:
            raise self.ctx.fail(f"unknown {key} {describe(node)}", _join(self.path, key), self.line_of(key),
                                _did_you_mean(value if value is not None else "", options))
        return value

    def section(self, key: str, keys: tuple[str, ...], what: str) -> _Section | None:
        node = self.get(key)
        if node is None or (isinstance(node, YScalar) and node.value is None):
            return None
        return _Section(self.ctx, node, _join(self.path, key), keys, line=self.line_of(key), what=what)

    def sequence(self, key: str, limit: int, what: str) -> list[YNode]:
        node = self.get(key)
        if node is None or (isinstance(node, YScalar) and node.value is None):
            return []
        field, line = _join(self.path, key), self.line_of(key)
        if not isinstance(node, YSeq):
            raise self.ctx.fail(f"expected a list of {what}, got {describe(node)}", field, line,
                                "write one '- ...' entry per item")
        if len(node.items) > limit:
            raise self.ctx.fail(f"{len(node.items)} {what} is more than the limit of {limit}", field, line,
                                "split the scenario, or thin it out (see SCENARIO_LIMITS)")
        return node.items


def _number(ctx: _Ctx, node: YNode, field: str, line: int | None, *, low: float | None = None,
            low_open: bool = False, high: float | None = None) -> float:
    """A finite float from a YAML number (ints allowed, bools refused), within bounds."""
    line = node.line if node.line is not None else line
    value = node.value if isinstance(node, YScalar) else None
    if type(value) is float and -_MAX_ABS <= value <= _MAX_ABS:   # the common case, checked as below
        if (low is None or (value > low if low_open else value >= low)) and (high is None or value <= high):
            return value
    if isinstance(value, str) and isinstance(node, YScalar) and node.plain and _NUMBER_WORD.fullmatch(value):
        value = float(value)
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ctx.fail(f"expected a number, got {describe(node)}", field, line,
                       "write a plain number such as 1.5 (no quotes, no units)")
    bound = SCENARIO_LIMITS["max_abs_value"]
    if isinstance(value, numbers.Integral) and abs(value) > bound:  # also ints too big for a float
        shown = str(value) if len(str(value)) < 30 else f"a {len(str(abs(value)))}-digit number"
        raise ctx.fail(f"{shown} is beyond the supported magnitude of {bound:g}", field, line,
                       "scenario values are metres, seconds and degrees of a ground robot; check the value")
    number = float(value)
    if not math.isfinite(number):
        raise ctx.fail(f"must be a finite number, got {describe(YScalar(number, line))}", field, line,
                       "write an ordinary number")
    if abs(number) > bound:
        raise ctx.fail(f"{number!r} is beyond the supported magnitude of {bound:g}", field, line,
                       "scenario values are metres, seconds and degrees of a ground robot; check the value")
    if low is not None and (number < low or (low_open and number == low)):
        need = f"> {low:g}" if low_open else f">= {low:g}"
        raise ctx.fail(f"must be {need}, got {number!r}", field, line,
                       "sizes, times and rates must be positive" if low_open else f"write a value {need}")
    if high is not None and number > high:
        raise ctx.fail(f"must be <= {high:g}, got {number!r}", field, line,
                       f"write a value from {low:g} to {high:g}" if low is not None else f"write at most {high:g}")
    return number


# --------------------------------------------------------------------------- reading by declaration

def _read(ctx: _Ctx, sec: _Section, decl: K.Section, values: dict[str, Any] | None = None) -> dict[str, Any]:
    """The values of ``decl``'s keys (by dataclass field), each read and checked as declared, then
    the section's rules. Keys already in ``values`` are not read again."""
    values = {} if values is None else values
    for key in decl.keys:
        if key.field not in values:
            values[key.field] = _READ[key.kind](ctx, sec, key)
    for rule in decl.rules:
        if rule.check is not None:
            problem = rule.check(values, sec.node.items)
            if problem is not None:
                key, message, fix = problem
                raise ctx.fail(message, _join(sec.path, key) if key else (sec.path or None),
                               sec.line_of(key) if key else sec.line, fix)
    return values


def _build_section(ctx: _Ctx, sec: _Section, decl: K.Section) -> Any:
    return decl.cls(**_read(ctx, sec, decl))


def _read_number(ctx: _Ctx, sec: _Section, key: K.Number) -> Any:
    return sec.number(key.name, key.default, low=key.low, low_open=key.low_open, high=key.le,
                      example=key.example or None)


def _read_integer(ctx: _Ctx, sec: _Section, key: K.Integer) -> Any:
    return sec.integer(key.name, key.default, low=key.ge, high=key.le)


def _read_text(ctx: _Ctx, sec: _Section, key: K.Text) -> Any:
    value = sec.string(key.name, key.default, nonempty=key.nonempty)
    if value is _REQUIRED:
        raise sec.missing(key.name, key.example or f"{key.name}: <text>")
    if isinstance(value, str) and value is not key.default:
        field, line = _join(sec.path, key.name), sec.line_of(key.name)
        if key.name_rules:
            _check_name(ctx, value, field, line, file_name=key.file_name)
        if key.path and "\x00" in value:
            raise ctx.fail(f"{value!r} holds a NUL byte (\\x00), which no file name can", field, line,
                           "remove the \\0 (or the escape that wrote it) from the path")
    return value


def _read_flag(ctx: _Ctx, sec: _Section, key: K.Flag) -> Any:
    return sec.boolean(key.name, key.default)


def _read_choice(ctx: _Ctx, sec: _Section, key: K.Choice) -> Any:
    return sec.choice(key.name, key.options, key.default)


def _read_sub(ctx: _Ctx, sec: _Section, key: K.Sub) -> Any:
    decl = key.section
    sub = sec.section(key.name, decl.names, decl.what)
    if sub is None:
        if key.default is _REQUIRED:
            raise sec.missing(key.name, key.example)
        return key.default
    return _build_section(ctx, sub, decl)


def _read_point(ctx: _Ctx, sec: _Section, key: K.Point) -> Any:
    node = sec.get(key.name)
    if node is None or (key.nullable and isinstance(node, YScalar) and node.value is None):
        if key.default is _REQUIRED:
            raise sec.missing(key.name, key.example or f"{key.name}: [0.0, 0.0]")
        return key.default
    return _point(ctx, node, _join(sec.path, key.name), sec.line_of(key.name))


def _read_points(ctx: _Ctx, sec: _Section, key: K.Points) -> Any:
    node = sec.get(key.name)
    field, line = _join(sec.path, key.name), sec.line_of(key.name)
    if node is None or (isinstance(node, YScalar) and node.value is None):
        if key.default is _REQUIRED:
            raise sec.missing(key.name, key.example or f"{key.name}: [[0, 0], [1, 0]]")
        return key.default
    if not isinstance(node, YSeq):
        raise ctx.fail(f"expected a list of points [x, y], got {describe(node)}", field, line,
                       f"write e.g. {key.example or key.name + ': [[0, 0], [1, 0]]'}")
    if len(node.items) > key.max:
        raise ctx.fail(f"{len(node.items)} points is more than the limit of {key.max}", field, line,
                       "thin the points out")
    if len(node.items) < key.min:
        raise ctx.fail(f"needs at least {key.min} points, got {len(node.items)}", field, node.line or line,
                       f"write e.g. {key.example or key.name + ': [[0, 0], [1, 0]]'}")
    return tuple(_point(ctx, p, f"{field}[{k}]", p.line or line) for k, p in enumerate(node.items))


def _read_rows(ctx: _Ctx, sec: _Section, key: K.Rows) -> Any:
    """Rows of numbers such as the reference's [t, x, y], the first column strictly increasing."""
    if not sec.has(key.name):
        return key.default
    rows = sec.sequence(key.name, key.max, "reference points" if key.name == "points" else key.name)
    width, shown = len(key.columns), ", ".join(key.columns)
    out = []
    last_t = -math.inf
    for i, row in enumerate(rows):
        field = f"{_join(sec.path, key.name)}[{i}]"
        line = row.line or sec.line_of(key.name)
        if not isinstance(row, YSeq) or len(row.items) != width:
            raise ctx.fail(f"expected a row [{shown}], got {describe(row)}"
                           + (f" with {len(row.items)} values" if isinstance(row, YSeq) else ""), field, line,
                           f"write each point as [{shown}] ({key.unit.replace('s', 'seconds', 1).replace('m', 'metres')})")
        values = tuple(_number(ctx, v, f"{field}[{j}]", line) for j, v in enumerate(row.items))
        t = values[0]
        if t <= last_t:
            raise ctx.fail(f"time {t!r} s does not increase (previous point at {last_t!r} s)", f"{field}[0]",
                           line, "sort the points by time; times must be strictly increasing")
        last_t = t
        out.append(values)
    return tuple(out)


def _read_scale(ctx: _Ctx, sec: _Section, key: K.Scale) -> Any:
    node = sec.get(key.name)
    field, line = _join(sec.path, key.name), sec.line_of(key.name)
    if node is None:
        return key.default
    if isinstance(node, YSeq):
        if len(node.items) != 3:
            raise ctx.fail(f"expected one number or three [sx, sy, sz], got {describe(node)}", field, line,
                           "write e.g. scale: 0.001 (millimetres to metres)")
        return tuple(_number(ctx, n, f"{field}[{k}]", line, low=0, low_open=True, high=key.le)
                     for k, n in enumerate(node.items))
    value = _number(ctx, node, field, line, low=0, low_open=True, high=key.le)
    return (value, value, value)


def _read_free(ctx: _Ctx, sec: _Section, key: K.Free) -> Any:
    return _mapping(ctx, sec, key.name)


_READ = {"number": _read_number, "integer": _read_integer, "text": _read_text, "flag": _read_flag,
         "choice": _read_choice, "sub": _read_sub, "point": _read_point, "points": _read_points,
         "rows": _read_rows, "scale": _read_scale, "free": _read_free}


# --------------------------------------------------------------------------- sections

def _robot(ctx: _Ctx, top: _Section) -> Robot:
    return _read_sub(ctx, top, SCENARIO["robot"])


def _pose(ctx: _Ctx, node: YNode | None, path: str, line: int | None, what: str) -> Pose:
    sec = _Section(ctx, node, path, POSE.names, line=line, what=f"{what} as a mapping {{x, y, yaw}}")
    return _build_section(ctx, sec, POSE)


def _mission(ctx: _Ctx, top: _Section) -> Mission:
    decl = MISSION
    if not top.has("mission"):
        raise top.missing("mission", SCENARIO["mission"].example)
    sec = top.section("mission", decl.names, decl.what)
    if sec is None:
        raise ctx.fail("the mission is empty", "mission", top.line_of("mission"),
                       "give at least start and goal poses")
    values: dict[str, Any] = {}
    for key in ("start", "goal"):
        if not sec.has(key):
            raise sec.missing(key, decl[key].example)
        values[key] = _pose(ctx, sec.get(key), f"mission.{key}", sec.line_of(key), f"the {key} pose")
    waypoints = []
    listed = decl["waypoints"]
    items = sec.sequence("waypoints", listed.max, listed.what)
    for i, item in enumerate(items):
        ctx.lines[f"mission.waypoints[{i}]"] = item.line
        waypoints.append(_pose(ctx, item, f"mission.waypoints[{i}]", item.line or sec.line_of("waypoints"),
                               "a waypoint"))
    values["waypoints"] = tuple(waypoints)
    return Mission(**_read(ctx, sec, decl, values))


def _obstacles(ctx: _Ctx, top: _Section) -> tuple[Obstacle, ...]:
    items = top.sequence("obstacles", OBSTACLES.max, OBSTACLES.what)
    given: dict[str, int] = {}
    parsed: list[tuple[K.Element, _Section, str | None]] = []
    for i, item in enumerate(items):
        path = f"obstacles[{i}]"
        line = item.line or top.line_of("obstacles")
        if not isinstance(item, YMap):
            raise ctx.fail(f"expected an obstacle mapping, got {describe(item)}", path, line,
                           "write '- {type: box, x: 1.0, y: 2.0, length: 1.0, width: 1.0}'")
        type_item = item.items.get("type")
        if type_item is None:
            raise ctx.fail("missing required field 'type'", f"{path}.type", line,
                           "add 'type: box' or 'type: cylinder'")
        kind = type_item[1].value if isinstance(type_item[1], YScalar) else None
        element = OBSTACLES.element(kind) if isinstance(kind, str) else None
        if element is None:
            raise ctx.fail(f"unknown obstacle type {describe(type_item[1])}", f"{path}.type",
                           type_item[0] or line, _did_you_mean(kind if kind is not None else "", OBSTACLE_TYPES))
        keys = TYPE_KEYS[kind]
        for key, (key_line, _) in item.items.items():
            if key in keys:
                continue
            other = next((t for t, t_keys in TYPE_KEYS.items() if key in t_keys), None)
            if other is not None:
                raise ctx.fail(f"'{key}' does not apply to type: {kind} (it is a {other} key)", f"{path}.{key}",
                               key_line or line, f"remove '{key}', or set type: {other}")
        sec = _Section(ctx, item, path, keys, line=line)
        name = _read_text(ctx, sec, element.section["name"])
        if name is not None:
            if name in given:
                first = given[name]
                raise ctx.fail(f"name {name!r} is already used by obstacles[{first}]", f"{path}.name",
                               sec.line_of("name"), "obstacle names must be unique; rename one of them")
            given[name] = i
        parsed.append((element, sec, name))
    taken = set(given)
    counters = dict.fromkeys(OBSTACLE_TYPES, 0)
    result: list[Obstacle] = []
    for element, sec, name in parsed:
        if name is None:  # generated: box1, box2, cyl1, person1 ... skipping names already given
            while True:
                counters[element.type] += 1
                name = f"{element.prefix}{counters[element.type]}"
                if name not in taken:
                    break
            taken.add(name)
        result.append(_obstacle(ctx, sec, element, name))
    return tuple(result)


def _obstacle(ctx: _Ctx, sec: _Section, element: K.Element, name: str) -> Obstacle:
    """One obstacle: its motion first (a path places it), then its keys as declared."""
    decl = element.section
    motion = _motion(ctx, sec, decl["motion"].section)
    if motion is not None and motion.path:
        for key in ("x", "y"):
            if sec.has(key):
                raise ctx.fail(f"'{key}' is given by the motion's path (the obstacle starts at its "
                               f"first point)", _join(sec.path, key), sec.line_of(key),
                               f"remove '{key}', or make it the path's first point")
        x, y = motion.path[0]
    else:
        x, y = _read_number(ctx, sec, decl["x"]), _read_number(ctx, sec, decl["y"])
    values: dict[str, Any] = {"name": name, "x": x, "y": y, "motion": motion}
    if element.type == "mesh":
        return _mesh(ctx, sec, decl, values)
    if element.type == "polygon":
        values["points"] = _polygon_points(ctx, sec)
    return decl.cls(**_read(ctx, sec, decl, values))


def _polygon_points(ctx: _Ctx, sec: _Section) -> tuple[tuple[float, float], ...]:
    """A polygon's ``points``: three or more [x, y], a simple polygon (no crossing edges)."""
    from .geometry import polygon_problem

    node = sec.get("points")
    field, line = _join(sec.path, "points"), sec.line_of("points")
    if node is None:
        raise sec.missing("points", "points: [[0, 0], [2, 0], [2, 1], [0, 1]]")
    if not isinstance(node, YSeq):
        raise ctx.fail(f"expected a list of points [x, y], got {describe(node)}", field, line,
                       "write e.g. points: [[0, 0], [2, 0], [2, 1], [0, 1]]")
    if len(node.items) > MAX_POLYGON_POINTS:
        raise ctx.fail(f"{len(node.items)} points is more than the limit of {MAX_POLYGON_POINTS}", field,
                       line, "simplify the outline")
    points = tuple(_point(ctx, p, f"{field}[{k}]", p.line or line) for k, p in enumerate(node.items))
    if len(points) > 3 and points[0] == points[-1]:
        points = points[:-1]          # a closed ring written out: the first point once
    problem = polygon_problem(points)
    if problem is not None:
        raise ctx.fail(problem, field, node.line or line,
                       "list the corners in order around the outline, without edges crossing each other")
    return points


def _mesh(ctx: _Ctx, sec: _Section, decl: K.Section, values: dict[str, Any]) -> Obstacle:
    """A mesh obstacle: its file (beside the scenario) read now, so a bad file is an error here."""
    from .mesh import MeshError, mesh_outline, read_mesh, resolve_mesh_path

    file = _read_text(ctx, sec, decl["file"])
    scale = _read_scale(ctx, sec, decl["scale"])
    folder = Path(ctx.source).parent if ctx.source else Path.cwd()
    try:
        path = resolve_mesh_path(folder, file)
        verts, tris = read_mesh(path)
        outline, height = mesh_outline(verts, tris, scale, Path(file).name)
    except MeshError as exc:
        raise ctx.fail(str(exc), _join(sec.path, "file"), sec.line_of("file"),
                       "fix the file or the path (relative to the scenario's folder)") from None
    values.update(file=file, scale=scale, footprint=outline, height=height)
    return MeshObstacle(**_read(ctx, sec, decl, values))


def _point(ctx: _Ctx, node: YNode, field: str, line: int | None) -> tuple[float, float]:
    """An [x, y] pair."""
    if not isinstance(node, YSeq) or len(node.items) != 2:
        raise ctx.fail(f"expected a point [x, y], got {describe(node)}", field,
                       node.line or line, "write two numbers in brackets, e.g. [1.0, 2.0]")
    return (_number(ctx, node.items[0], f"{field}[0]", line),
            _number(ctx, node.items[1], f"{field}[1]", line))


def _motion(ctx: _Ctx, obs: _Section, decl: K.Section) -> Motion | None:
    """The obstacle's ``motion`` section: a path at a speed, or a constant velocity."""
    sec = obs.section("motion", decl.names, decl.what)
    if sec is None:
        return None
    start = _read_number(ctx, sec, decl["start"])
    if sec.has("velocity"):
        for key in ("path", "speed", "mode"):
            if sec.has(key):
                raise ctx.fail(f"'{key}' does not go with 'velocity' (a constant velocity has no path)",
                               _join(sec.path, key), sec.line_of(key),
                               "give either velocity: [vx, vy], or a path with a speed")
        vx, vy = _point(ctx, sec.get("velocity"), _join(sec.path, "velocity"), sec.line_of("velocity"))
        return Motion(start=start, velocity=(vx, vy))
    node = sec.get("path")
    field, line = _join(sec.path, "path"), sec.line_of("path")
    path_key = decl["path"]
    if node is None:
        raise sec.missing("path", path_key.example)
    if not isinstance(node, YSeq) or len(node.items) < path_key.min:
        got = f"{len(node.items)} point" + ("" if len(node.items) == 1 else "s") if isinstance(node, YSeq) \
            else describe(node)
        raise ctx.fail(f"a path needs at least two points, got {got}", field, node.line or line,
                       "list the points it walks through, e.g. path: [[0.0, -3.0], [0.0, 3.0]]")
    if len(node.items) > path_key.max:
        raise ctx.fail(f"{len(node.items)} path points is more than the limit of {path_key.max}", field, line,
                       "thin the path out")
    points = tuple(_point(ctx, p, f"{field}[{k}]", p.line or line) for k, p in enumerate(node.items))
    if sum(math.dist(a, b) for a, b in zip(points, points[1:])) <= 0.0:
        raise ctx.fail("the path has no length (all its points are the same)", field, line,
                       "give points that differ, or remove 'motion' for a static obstacle")
    speed = _read_number(ctx, sec, decl["speed"])
    mode = _read_choice(ctx, sec, decl["mode"])
    return Motion(path=points, speed=speed, mode=mode, start=start)


def _check_name(ctx: _Ctx, name: str, field: str, line: int | None, *, file_name: bool = False) -> None:
    """Names are one-line labels; scenario names and families also name files (no path tricks)."""
    limit = int(SCENARIO_LIMITS["max_name_length"])
    if len(name) > limit:
        raise ctx.fail(f"is {len(name)} characters long, more than {limit}", field, line, "shorten it")
    if any(ch in name for ch in "\n\r\t\x00"):
        raise ctx.fail("must be one line without tabs", field, line, "remove the line breaks")
    if file_name and (any(ch in name for ch in "/\\") or name.strip() in (".", "..")):
        raise ctx.fail(f"{name!r} cannot be used: scenario names and families become file and folder names",
                       field, line, "use letters, digits, '-', '_' and '.', without '/' or '\\'")


def _check_family(ctx: _Ctx, family: str, line: int | None) -> None:
    """A family is a name, or a relative folder path such as ``examples/scenarios`` (what the pytest
    plugin names the families of two folders with the same name): each part a name, no climbing."""
    _check_name(ctx, family, "family", line)
    parts = family.split("/")
    if "\\" in family or any(not p.strip() or p.strip() in (".", "..") for p in parts):
        raise ctx.fail(f"{family!r} cannot be used: a family is a name or a relative folder path "
                       f"(scenario names and families become file and folder names)", "family",
                       line, "use names of letters, digits, '-', '_' and '.', separated by '/' "
                             "(e.g. examples/scenarios), without '..' or '\\'")


def _simulation(ctx: _Ctx, top: _Section) -> Simulation:
    return _read_sub(ctx, top, SCENARIO["simulation"])


def _reference(ctx: _Ctx, top: _Section) -> Reference | None:
    return _read_sub(ctx, top, SCENARIO["reference"])


def _marks(ctx: _Ctx, top: _Section) -> tuple[Mark, ...]:
    items = top.sequence("marks", SCENARIO["marks"].max, "marks")
    marks = []
    for i, item in enumerate(items):
        field, line = f"marks[{i}]", item.line or top.line_of("marks")
        if isinstance(item, YScalar) and isinstance(item.value, str):
            name, value = item.value, None
        elif isinstance(item, YMap) and len(item.items) == 1:
            (name, (_, value)), = item.items.items()
        else:
            raise ctx.fail(f"expected a mark name or a one-key mapping, got {describe(item)}", field, line,
                           "write e.g. 'slow', '{xfail: {reason: known}}', '{skip: why}' or '{mymark: [a, b]}'")
        if not isinstance(name, str) or not _IDENT.match(name):
            raise ctx.fail(f"mark name {name!r} is not a valid Python identifier", field, line,
                           "use letters, digits and underscores, e.g. slow or known_failure")
        args: tuple[Any, ...] = ()
        kwargs: dict[str, Any] = {}
        if isinstance(value, YMap):
            kwargs = _free(ctx, value, field)
            bad = [k for k in kwargs if not isinstance(k, str) or not _IDENT.match(k)]
            if bad:
                raise ctx.fail(f"mark keyword {bad[0]!r} is not a valid Python identifier", field, line,
                               "keywords are names such as reason or strict")
        elif isinstance(value, YSeq):
            args = tuple(_free(ctx, value, field))
        elif value is not None and not (isinstance(value, YScalar) and value.value is None):
            args = (_free(ctx, value, field),)
        marks.append(Mark(name=name, args=args, kwargs=kwargs))
    return tuple(marks)


def _mapping(ctx: _Ctx, top: _Section, key: str) -> Mapping[str, Any] | None:
    node = top.get(key)
    if node is None or (isinstance(node, YScalar) and node.value is None):
        return None
    if not isinstance(node, YMap):
        raise ctx.fail(f"expected a mapping, got {describe(node)}", key, top.line_of(key),
                       f"write '{key}:' followed by indented 'key: value' lines")
    return _free(ctx, node, key)


_PLAIN_TYPES = (str, bool, int, float, type(None))


def _free(ctx: _Ctx, node: YNode, field: str) -> Any:
    """Free-form data (search, provenance, mark arguments) as plain Python values. Only strings,
    numbers, booleans, null, lists and mappings: these cross to xdist workers and into JSON
    unchanged (YAML dates and !!binary would not), so anything else is refused here."""
    def check(n: YNode, path: str) -> None:
        if isinstance(n, YScalar):
            if not isinstance(n.value, _PLAIN_TYPES):
                raise ctx.fail(f"{describe(n)} is not supported in free-form data", path, n.line,
                               "quote it to keep it as text; free-form data holds text, numbers, true/false, null, lists and mappings")
        elif isinstance(n, YSeq):
            for i, item in enumerate(n.items):
                check(item, f"{path}[{i}]")
        else:
            for key, (_, item) in n.items.items():
                if not isinstance(key, _PLAIN_TYPES):
                    raise ctx.fail(f"key {key!r} is not supported in free-form data", path, n.line,
                                   "use text keys")
                check(item, f"{path}.{key}")
    check(node, field)
    return to_plain(node)


# --------------------------------------------------------------------------- semantic checks

def _steps_per_tick(sim: Simulation) -> float:
    return 1.0 / (sim.timestep * sim.control_rate)


def check_scenario(scenario: Scenario, *, _ctx: _Ctx | None = None) -> None:
    """Checks across fields: whole physics steps per tick, episode length, start/goal/waypoints clear
    of obstacles. Run by the loader; call it on scenarios built in code (e.g. generated layouts)."""
    ctx = _ctx or _Ctx(scenario.source)
    lines = ctx.lines
    sim = scenario.simulation
    steps = _steps_per_tick(sim)
    if steps > 1e6:
        raise ctx.fail(f"timestep {sim.timestep!r} s and control_rate {sim.control_rate!r} Hz give "
                       f"{steps:.3g} physics steps per control tick", "simulation.control_rate",
                       lines.get("simulation.control_rate", lines.get("simulation")),
                       "raise the control rate (planner ticks per second)")
    if steps < 1 - 1e-9 or abs(steps - round(steps)) > 1e-6 * max(1.0, steps):
        whole = max(1, round(steps))
        raise ctx.fail(f"timestep {sim.timestep!r} s and control_rate {sim.control_rate!r} Hz give "
                       f"{steps:.4g} physics steps per control tick; it must be a whole number",
                       "simulation.control_rate", lines.get("simulation.control_rate", lines.get("simulation")),
                       f"e.g. control_rate: {1.0 / (sim.timestep * whole):g} ({whole} steps of {sim.timestep:g} s)")
    episode_steps = scenario.mission.timeout / sim.timestep
    if episode_steps > SCENARIO_LIMITS["max_episode_steps"]:
        raise ctx.fail(f"timeout {scenario.mission.timeout!r} s at timestep {sim.timestep!r} s is "
                       f"{episode_steps:.3g} physics steps, more than {SCENARIO_LIMITS['max_episode_steps']:g}",
                       "mission.timeout", lines.get("mission.timeout", lines.get("mission")),
                       "shorten the timeout or lengthen the timestep")
    for key in ("observation", "command"):
        delay = getattr(scenario.robot.latency, key)
        ticks = delay * sim.control_rate
        if abs(ticks - round(ticks)) > 1e-6:
            field = f"robot.latency.{key}"
            raise ctx.fail(f"a delay of {delay!r} s is not a whole number of control periods "
                           f"({1.0 / sim.control_rate:g} s at {sim.control_rate:g} Hz)", field,
                           lines.get(field, lines.get("robot.latency")),
                           f"e.g. {key}: {round(ticks) / sim.control_rate:g}")
    if scenario.obstacles:
        _check_clear(scenario, ctx)


def _check_clear(scenario: Scenario, ctx: _Ctx) -> None:
    """Start and goal footprints and waypoints must not touch an obstacle (names the first one)."""
    from shapely.geometry import Point

    from .geometry import bounding_radius, footprint_polygon, footprint_radius, obstacle_polygon

    mission = scenario.mission
    fp = scenario.robot.footprint
    checks = [("start", mission.start, footprint_radius(fp), "the robot's footprint at the start"),
              ("goal", mission.goal, footprint_radius(fp), "the robot's footprint at the goal")]
    checks += [(f"waypoints[{i}]", wp, 0.0, f"waypoint {i}") for i, wp in enumerate(mission.waypoints)]
    # Cheap bounding-circle test first, so thousands of obstacles cost microseconds, not polygons.
    bounds = [(o.x, o.y, bounding_radius(o)) for o in scenario.obstacles]
    moving = {i for i, o in enumerate(scenario.obstacles) if getattr(o, "motion", None) is not None}
    for key, pose, reach, what in checks:
        # a moving obstacle must leave the start clear (where it stands at t = 0); it may cross the
        # goal and the waypoints
        near = [i for i, (x, y, r) in enumerate(bounds) if math.hypot(x - pose.x, y - pose.y) <= r + reach + 1e-9
                and (key == "start" or i not in moving)]
        if not near:
            continue
        shape = (footprint_polygon(fp, pose.x, pose.y, pose.yaw_rad) if reach else Point(pose.x, pose.y))
        for i in near:
            obs = scenario.obstacles[i]
            if shape.intersects(obstacle_polygon(obs)):
                field = f"mission.{key}"
                what_moves = "start" if key == "start" else "goal" if key == "goal" else "waypoint"
                raise ctx.fail(f"{what} ({pose.x:g}, {pose.y:g}) overlaps obstacle {obs.name!r}", field,
                               ctx.lines.get(field, ctx.lines.get("mission")),
                               f"move the {what_moves} or obstacle {obs.name!r} so they are clear")


# --------------------------------------------------------------------------- public API

def _build(root: YNode | None, ctx: _Ctx, name: str | None, family: str | None) -> Scenario:
    if root is None or (isinstance(root, YScalar) and root.value is None):
        raise ctx.fail("the scenario is empty", None, 1,
                       "a scenario needs at least 'version: 1' and a 'mission:' with start and goal")
    if not isinstance(root, YMap):
        raise ctx.fail(f"the top level must be a mapping of scenario fields, got {describe(root)}", None,
                       root.line, "start the file with 'version: 1' followed by 'mission:' etc.")
    # The version decides the schema, so check it before anything else.
    version_item = root.items.get("version")
    if version_item is None:
        raise ctx.fail("missing required field 'version'", "version", root.line,
                       f"add 'version: {SCHEMA_VERSION}' as the first line")
    vnode = version_item[1]
    version = vnode.value if isinstance(vnode, YScalar) else None
    if isinstance(version, bool) or version not in SUPPORTED_VERSIONS:
        raise ctx.fail(f"unsupported version {describe(vnode)}; this pytest-navscenario reads version(s) "
                       f"{', '.join(map(str, SUPPORTED_VERSIONS))}", "version", version_item[0] or vnode.line,
                       f"write 'version: {SCHEMA_VERSION}' (or upgrade pytest-navscenario for newer files)")
    top = _Section(ctx, root, "", TOP_KEYS)
    lines = ctx.lines
    for key in TOP_KEYS:
        if top.has(key):
            lines[key] = top.line_of(key)
    scenario_name = top.string("name", name or "")
    if scenario_name:
        _check_name(ctx, scenario_name, "name", top.line_of("name"), file_name=True)
    scenario_family = top.string("family", family or "", nonempty=False)
    if scenario_family:
        _check_family(ctx, scenario_family, top.line_of("family"))
    scenario = Scenario(
        version=int(version),
        name=scenario_name,
        family=scenario_family,
        description=top.string("description", "", nonempty=False),
        marks=_marks(ctx, top),
        robot=_robot(ctx, top),
        mission=_mission(ctx, top),
        obstacles=_obstacles(ctx, top),
        simulation=_simulation(ctx, top),
        reference=_reference(ctx, top),
        search=_mapping(ctx, top, "search"),
        provenance=_mapping(ctx, top, "provenance"),
        source=ctx.source,
    )
    check_scenario(scenario, _ctx=ctx)
    return scenario


def loads_scenario(text: str | bytes, source: str | os.PathLike | None = None, *,
                   name: str | None = None, family: str | None = None) -> Scenario:
    """Parse and validate scenario YAML text. ``name``/``family`` apply when the YAML has none."""
    src = os.fspath(source) if source is not None else None
    if isinstance(text, (bytes, bytearray)):
        text = _decode(bytes(text), src)
    if not isinstance(text, str):
        raise ScenarioError(f"expected YAML text, got {type(text).__name__}", path=src,
                            hint="pass the file's text, or use load_scenario(path)")
    if len(text) > SCENARIO_LIMITS["max_file_bytes"]:
        raise ScenarioError(f"the text is {len(text)} characters, more than the limit of "
                            f"{SCENARIO_LIMITS['max_file_bytes']:g}", path=src, hint="this is not a scenario file")
    ctx = _Ctx(src)
    root = parse_yaml(text, src, max_depth=int(SCENARIO_LIMITS["max_depth"]),
                      max_nodes=int(SCENARIO_LIMITS["max_nodes"]), list_limits=_LIST_LIMITS)
    return _build(root, ctx, name, family)


def scenario_from_dict(data: Mapping[str, Any], source: str | os.PathLike | None = None) -> Scenario:
    """Validate a plain mapping (as safe_load would give) into a Scenario; errors have no lines."""
    src = os.fspath(source) if source is not None else None
    if not isinstance(data, Mapping):
        raise ScenarioError(f"expected a mapping of scenario fields, got {type(data).__name__}", path=src,
                            hint="pass a dict with 'version' and 'mission' keys")
    try:
        root = from_plain(data, max_depth=int(SCENARIO_LIMITS["max_depth"]),
                          max_nodes=int(SCENARIO_LIMITS["max_nodes"]), source=src)
    except RecursionError:
        raise ScenarioError("the mapping nests too deeply", path=src) from None
    return _build(root, _Ctx(src), None, None)


_BOMS = ((codecs.BOM_UTF32_LE, "utf-32"), (codecs.BOM_UTF32_BE, "utf-32"), (codecs.BOM_UTF8, "utf-8-sig"),
         (codecs.BOM_UTF16_LE, "utf-16"), (codecs.BOM_UTF16_BE, "utf-16"))   # UTF-32 LE before UTF-16 LE


def text_codec(data: bytes) -> str:
    """The codec of a scenario file's bytes: UTF-8, or UTF-16/32 when the file starts with their
    byte-order mark (YAML allows all three); the codec consumes the mark."""
    for bom, codec in _BOMS:
        if data.startswith(bom):
            return codec
    return "utf-8"


def _decode(data: bytes, source: str | None) -> str:
    codec = text_codec(data)
    try:
        return data.decode(codec)
    except UnicodeDecodeError as exc:
        name = {"utf-8-sig": "UTF-8", "utf-8": "UTF-8"}.get(codec, codec.upper())
        line = data.count(b"\n", 0, exc.start) + 1 if name == "UTF-8" else None
        raise ScenarioError(f"not {name} text: byte 0x{data[exc.start]:02x} cannot be decoded", path=source,
                            line=line, hint="is this a binary file? save the scenario as UTF-8 text") from None


def load_scenario(path: str | os.PathLike, *, family: str | None = None) -> Scenario:
    """Load a scenario file; its name defaults to the file stem, its family to ``family`` (by
    default the folder's name) when the YAML has no ``family:``."""
    p = Path(path)
    src = os.fspath(path)
    limit = int(SCENARIO_LIMITS["max_file_bytes"])
    try:
        with open(p, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size   # read(limit + 1) alone would allocate 5 MB per file
            data = fh.read(size + 1 if 0 < size <= limit else limit + 1)
    except FileNotFoundError:
        raise ScenarioError("no such scenario file", path=src, hint="check the path and the file name") from None
    except IsADirectoryError:
        raise ScenarioError("is a directory, not a scenario file", path=src,
                            hint="pass a .yaml file inside it") from None
    except OSError as exc:
        raise ScenarioError(f"cannot read the file: {exc.strerror or exc}", path=src) from None
    if p.is_dir():  # pragma: no cover - some platforms open directories
        raise ScenarioError("is a directory, not a scenario file", path=src, hint="pass a .yaml file inside it")
    if len(data) > limit:
        raise ScenarioError(f"the file is larger than the limit of {limit} bytes", path=src,
                            hint="scenario files are small; is this the right file?")
    text = _decode(data, src)
    return loads_scenario(text, src, name=p.stem, family=p.absolute().parent.name if family is None else family)


def resolve_path(scenario: Scenario, relative: str | os.PathLike) -> Path:
    """A path written in a scenario (reference file, bag, map), resolved against the scenario's folder."""
    rel = Path(relative)
    if rel.is_absolute() or not scenario.source:
        return rel
    return Path(scenario.source).parent / rel


def looks_like_scenario(text_or_mapping: str | bytes | Mapping[str, Any]) -> bool:
    """Cheap test (no YAML parsing) whether a text or mapping is meant to be a scenario: a top-level
    ``version`` key and a ``mission`` key, or a near miss such as ``mision`` or ``obstacles``, so a
    scenario with a typo is collected and reported instead of silently skipped."""
    if isinstance(text_or_mapping, Mapping):
        keys = {str(k) for k in text_or_mapping}
    else:
        text = text_or_mapping
        if isinstance(text, (bytes, bytearray)):
            head = bytes(text[:1_000_000])
            text = head.decode(text_codec(head), errors="replace")
        if not isinstance(text, str):
            return False
        keys = set(_TOP_KEY.findall(text))
    if "version" not in keys:
        return False
    return bool(keys & {"mission", "obstacles", "robot"}) or bool(
        difflib.get_close_matches("mission", [k.lower() for k in keys], n=1, cutoff=0.75))


_TOP_KEY = re.compile(r"^(?:---[ \t]*\n)?[\"']?([A-Za-z_][\w-]*)[\"']?[ \t]*:", re.M)


# --------------------------------------------------------------------------- dumping


