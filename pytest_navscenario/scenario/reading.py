"""Reading YAML nodes by declaration, with file:line errors: the typed getters of one mapping
(``SectionReader``), numbers with the format's magnitude bound, and one reader per kind of key
(``keys.py``) so that a section declared there is read without code of its own. ``loader.py``
reads a whole scenario with these; ``search_keys.py`` reads ``search:``.

Every problem raises ``ScenarioError`` naming the file, the line, the dotted field and a fix.
"""
from __future__ import annotations

import difflib
import math
import numbers
import re
import unicodedata
from typing import Any, Mapping

from ..core.errors import ScenarioError, ScenarioErrors
from . import keys as K
from .format import key_homes
from .keys import SCENARIO_LIMITS
from .yaml_tree import YMap, YNode, YScalar, YSeq, describe, to_plain

_MAX_ABS = float(SCENARIO_LIMITS["max_abs_value"])


_REQUIRED = K.REQUIRED


_NUMBER_WORD = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+")  # 1e-3: a string in YAML 1.1


_KEY_HOMES = key_homes()


_ALIASES = {  # common synonyms -> the spelling the format uses (for the hint)
    "omnidirectional": "omni", "holonomic": "omni", "differential": "diff", "diff-drive": "diff",
    "rectangle": "box", "rect": "box", "cuboid": "box", "square": "box", "cyl": "cylinder",
    "circle": "cylinder", "disc": "cylinder", "disk": "cylinder", "round": "circle",
}


# --------------------------------------------------------------------------- helpers

MAX_REPORTED = 20   # mistakes of one file reported in one pass (then: fix these and load again)


class Recorded(Exception):
    """A part of the file (a key, a section, a list item) could not be read; its mistakes are in
    ``_Ctx.errors`` and the reader goes on with the next part (issue 32)."""


BROKEN = object()   # the value of a key that could not be read (its mistake is recorded)


class _Ctx:
    """Where we are: the source file (for messages) and the line of every field read; with
    ``collect``, the mistakes found so far (each part of the file that has one is skipped and
    the reading goes on, so one pass reports them all, up to MAX_REPORTED)."""

    def __init__(self, source: str | None, *, collect: bool = False):
        self.source = source
        self.lines: dict[str, int | None] = {}
        #: names of the typed lists read so far (obstacles, then terrain) -> "obstacles[i]": one
        #: name space, so that a name (in ``search: frozen``, a message) means one thing
        self.element_names: dict[str, str] = {}
        self.collect = collect
        self.errors: list[ScenarioError] = []

    def fail(self, message: str, field: str | None, line: int | None, hint: str | None = None) -> ScenarioError:
        return ScenarioError(message, path=self.source, line=line, field=field, hint=hint)

    def note(self, exc: ScenarioError) -> None:
        """Keep ``exc`` and go on (collecting), or raise it (not collecting); at MAX_REPORTED
        mistakes, stop with all of them."""
        if not self.collect:
            raise exc
        self.errors.append(exc)
        if len(self.errors) >= MAX_REPORTED:
            raise ScenarioErrors(self.errors, stopped=MAX_REPORTED)

    def attempt(self, read: Any, *args: Any) -> Any:
        """``read(*args)``, or BROKEN when it found a mistake (recorded: see ``note``)."""
        try:
            return read(*args)
        except Recorded:
            return BROKEN
        except ScenarioErrors:
            raise
        except ScenarioError as exc:
            self.note(exc)
            return BROKEN

    def finish(self) -> None:
        """Raise what was recorded: the one mistake as itself, several as ScenarioErrors."""
        if len(self.errors) == 1:
            raise self.errors[0]
        if self.errors:
            raise ScenarioErrors(self.errors)


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
                           f"write it as 'key: value' lines with keys from: {', '.join(keys)}")
        self.node = node
        self.line = line if line is not None else node.line
        for key, (key_line, _) in node.items.items():
            if key not in keys:   # collecting: noted, and the key is left unread
                ctx.note(ctx.fail(f"unknown key {str(key)!r}", _join(path, str(key)), key_line,
                                  _unknown_key_hint(key, keys, path)))

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


# --------------------------------------------------------------------------- one reader per kind of key

def _read(ctx: _Ctx, sec: _Section, decl: K.Section, values: dict[str, Any] | None = None) -> dict[str, Any]:
    """The values of ``decl``'s keys (by dataclass field), each read and checked as declared, then
    the section's rules. Keys already in ``values`` are not read again."""
    values = {} if values is None else values
    items = sec.node.items
    for key in decl.keys:
        field = key.field
        if field in values:
            continue
        if key.name not in items and key.default is not _REQUIRED:
            values[field] = key.default             # absent: its default (most keys of most files)
        else:
            values[field] = ctx.attempt(_READ[key.kind], ctx, sec, key)
    if any(v is BROKEN for v in values.values()):
        raise Recorded()                            # the section's rules need every key
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


def _read_elements(ctx: _Ctx, top: _Section, key: K.Elements, build: Any = None) -> tuple[Any, ...]:
    """A typed list (obstacles, terrain): each item's ``type`` chooses its keys; names are unique
    and generated where absent (box1, box2, cyl1 ... per type in file order, skipping names given);
    ``build(ctx, sec, element, name)`` makes each item (default: by its declaration)."""
    items = top.sequence(key.name, key.max, key.what)
    if not items:
        return key.default
    types = key.type_names
    type_keys = {e.type: ("type",) + e.section.names for e in key.types}
    article = "an" if key.item[:1] in "aeiou" else "a"
    given: dict[str, int] = {}
    parsed: list[tuple[K.Element, _Section, str | None]] = []
    broken = False
    for i, item in enumerate(items):
        found = ctx.attempt(_parse_element, ctx, top, key, i, item, type_keys, given)
        if found is BROKEN:
            broken = True
        else:
            parsed.append(found)
    taken = set(given) | set(ctx.element_names)
    counters = dict.fromkeys(types, 0)
    result = []
    for element, sec, name in parsed:
        if name is None:
            while True:
                counters[element.type] += 1
                name = f"{element.prefix}{counters[element.type]}"
                if name not in taken:
                    break
            taken.add(name)
        made = ctx.attempt(build, ctx, sec, element, name) if build is not None else \
            ctx.attempt(lambda: element.section.cls(**_read(ctx, sec, element.section, {"name": name})))
        if made is BROKEN:
            broken = True
        else:
            result.append(made)
    if broken:
        raise Recorded()
    ctx.element_names.update((item.name, f"{key.name}[{i}]") for i, item in enumerate(result))
    return tuple(result)


def _parse_element(ctx: _Ctx, top: _Section, key: K.Elements, i: int, item: YNode,
                   type_keys: dict[str, tuple[str, ...]], given: dict[str, int]) -> tuple[Any, _Section, str | None]:
    """List item ``i`` of a typed list: its element (by ``type``), its section and its given name."""
    types = key.type_names
    article = "an" if key.item[:1] in "aeiou" else "a"
    path = f"{key.name}[{i}]"
    line = item.line or top.line_of(key.name)
    if not isinstance(item, YMap):
        raise ctx.fail(f"expected {article} {key.item} mapping, got {describe(item)}", path, line,
                       f"write '- {key.example}'")
    type_item = item.items.get("type")
    if type_item is None:
        raise ctx.fail("missing required field 'type'", f"{path}.type", line,
                       f"add 'type: {types[0]}' or 'type: {types[1]}'")
    kind = type_item[1].value if isinstance(type_item[1], YScalar) else None
    element = key.element(kind) if isinstance(kind, str) else None
    if element is None:
        raise ctx.fail(f"unknown {key.item} type {describe(type_item[1])}", f"{path}.type",
                       type_item[0] or line, _did_you_mean(kind if kind is not None else "", types))
    keys = type_keys[kind]
    for name, (key_line, _) in item.items.items():
        if name in keys:
            continue
        other = next((t for t, t_keys in type_keys.items() if name in t_keys), None)
        if other is not None:
            raise ctx.fail(f"'{name}' does not apply to type: {kind} (it is a {other} key)", f"{path}.{name}",
                           key_line or line, f"remove '{name}', or set type: {other}")
    sec = _Section(ctx, item, path, keys, line=line)
    name = _read_text(ctx, sec, element.section.by_name["name"]) if "name" in item.items else None
    if name is not None:
        if name in given or name in ctx.element_names:
            first = f"{key.name}[{given[name]}]" if name in given else ctx.element_names[name]
            raise ctx.fail(f"name {name!r} is already used by {first}", f"{path}.name",
                           sec.line_of("name"), "names of obstacles and terrain elements must be unique; "
                           "rename one of them")
        given[name] = i
    return (element, sec, name)


def _read_variant(ctx: _Ctx, sec: _Section, key: K.Variant) -> Any:
    """One mapping whose ``type`` chooses its keys (``robot.body``)."""
    node = sec.get(key.name)
    if node is None or (isinstance(node, YScalar) and node.value is None):
        return key.default
    field, line = _join(sec.path, key.name), sec.line_of(key.name)
    types = key.type_names
    if not isinstance(node, YMap):
        raise ctx.fail(f"expected a mapping with a type, got {describe(node)}", field, line,
                       f"write e.g. {key.name}: {{type: {types[1] if len(types) > 1 else types[0]}}}")
    type_item = node.items.get("type")
    if type_item is None:
        raise ctx.fail("missing required field 'type'", f"{field}.type", line,
                       "add 'type: ' and one of: " + ", ".join(types))
    kind = type_item[1].value if isinstance(type_item[1], YScalar) else None
    element = key.element(kind) if isinstance(kind, str) else None
    if element is None:
        raise ctx.fail(f"unknown {key.name} type {describe(type_item[1])}", f"{field}.type",
                       type_item[0] or line, _did_you_mean(kind if kind is not None else "", types))
    keys = ("type",) + element.section.names
    for name, (key_line, _) in node.items.items():
        other = next((e.type for e in key.types if name in e.section.names), None) if name not in keys else None
        if other is not None:
            raise ctx.fail(f"'{name}' does not apply to type: {kind} (it is a {other} key)", f"{field}.{name}",
                           key_line or line, f"remove '{name}', or set type: {other}")
    sub = _Section(ctx, node, field, keys, line=line)
    return _build_section(ctx, sub, element.section)


_READ["variant"] = _read_variant


def _point(ctx: _Ctx, node: YNode, field: str, line: int | None) -> tuple[float, float]:
    """An [x, y] pair."""
    if not isinstance(node, YSeq) or len(node.items) != 2:
        raise ctx.fail(f"expected a point [x, y], got {describe(node)}", field,
                       node.line or line, "write two numbers in brackets, e.g. [1.0, 2.0]")
    return (_number(ctx, node.items[0], f"{field}[0]", line),
            _number(ctx, node.items[1], f"{field}[1]", line))


def _check_name(ctx: _Ctx, name: str, field: str, line: int | None, *, file_name: bool = False) -> None:
    """Names are one-line labels; scenario names and families also name files (no path tricks)."""
    limit = int(SCENARIO_LIMITS["max_name_length"])
    if len(name) > limit:
        raise ctx.fail(f"is {len(name)} characters long, more than {limit}", field, line, "shorten it")
    if any(ch in name for ch in "\n\r\t\x00"):
        raise ctx.fail("must be one line without tabs", field, line, "remove the line breaks")
    control = next((ch for ch in name if unicodedata.category(ch) == "Cc"), None)
    if control is not None:   # an escape sequence would drive the terminal that prints the name
        raise ctx.fail(f"{name!r} holds the control character U+{ord(control):04X}: names are printed in "
                       f"terminals and reports, where it would act (clear the screen, recolour, retitle)",
                       field, line, "remove the control characters (\\e, \\a, \\x1b ... in YAML escapes)")
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

# Names other modules of the package use (loader.py imports them under the names above).
Ctx = _Ctx
SectionReader = _Section
REQUIRED = _REQUIRED
read_section = _read
build_section = _build_section
read_elements = _read_elements
READERS = _READ
join = _join
number = _number
