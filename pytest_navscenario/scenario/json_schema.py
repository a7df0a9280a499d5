"""The JSON Schema (draft 2020-12) of the scenario format, generated from the declarations the
loader reads (``keys.py``, ``format.SCENARIO``), for editors (completion, hover documentation and
inline errors through the YAML language server) and for CI (``check-jsonschema``).

    scenario_schema() -> dict        the schema; ``navscenario schema [-o FILE]`` writes it
    schema_text() -> str             the same as the JSON text written (stable bytes)
    SCHEMA_FILE                      its file name, versioned with the format: scenario-v1.json
    MODELINE_PATH                    where a project keeps it: .navscenario/scenario-v1.json

Every section has ``additionalProperties: false`` (the loader refuses unknown keys everywhere but
in free-form data); every key carries its type, range, allowed values, default, unit and a
one-line description. Rules across keys are included where JSON Schema can say them (``Rule.schema``);
the others (a polygon whose edges cross, a start inside an obstacle, a mesh file's contents) need
a run and are listed by ``run_only_checks()``.
"""
from __future__ import annotations

import json
import re
from typing import Any, Callable

from . import keys as K
from .format import SCENARIO
from .keys import MAX_ABS, SCENARIO_LIMITS, walk
from .model import SCHEMA_VERSION

SCHEMA_FILE = f"scenario-v{SCHEMA_VERSION}.json"
MODELINE_PATH = f".navscenario/{SCHEMA_FILE}"
DRAFT = "https://json-schema.org/draft/2020-12/schema"

_NO_CONTROL = r"^[^\x00-\x1f\x7f-\x9f]*$"     # one line, no control characters (an escape would drive a terminal)
_NOT_BLANK = r"\S"
_FILE_NAME = r"^(?!\s*\.{1,2}\s*$)[^/\\]*$"                    # no '/', '\', '.' or '..'
_FOLDER_PATH = r"^$|^(?!(?:.*/)?\s*\.{0,2}\s*(?:/|$))[^\\]*$"   # names separated by '/': no '..', no empty part
_NO_NUL = r"^[^\x00]*$"
_IDENTIFIER = r"^[A-Za-z_][A-Za-z0-9_]*$"


def scenario_schema() -> dict[str, Any]:
    """The schema of a scenario file, from ``format.SCENARIO``."""
    builder = _Builder()
    root = builder.section(SCENARIO, "scenario")
    root["title"] = f"pytest-navscenario scenario (format version {SCHEMA_VERSION})"
    return {
        "$schema": DRAFT,
        "$comment": "Generated from pytest_navscenario's declarations by 'navscenario schema'; do not edit.",
        **root,
        "$defs": builder.defs,
    }


def schema_text() -> str:
    """The schema as the JSON text ``navscenario schema`` writes (sorted $defs: stable bytes)."""
    return json.dumps(scenario_schema(), indent=2, ensure_ascii=False) + "\n"


def run_only_checks() -> list[tuple[str, str]]:
    """(where, rule) of every rule across keys that the schema cannot say: the loader checks them
    when a file loads (a pytest run, ``navscenario run``), an editor cannot."""
    out = []
    for path, sec in walk(SCENARIO):
        for rule in sec.rules:
            if rule.schema is None and (path or "(top level)", rule.doc) not in out:
                out.append((path or "(top level)", rule.doc))
    return out


# --------------------------------------------------------------------------- building

class _Builder:
    def __init__(self) -> None:
        self.defs: dict[str, Any] = {}
        self._names: dict[int, str] = {}

    def ref(self, sec: K.Section, name: str) -> dict[str, Any]:
        """A $ref to ``sec``'s definition (made once per section, named ``name`` or, when that
        name is taken by another section, ``name`` and a number)."""
        known = self._names.get(id(sec))
        if known is None:
            known, n = name, 2
            while known in self.defs:
                known, n = f"{name}-{n}", n + 1
            self._names[id(sec)] = known
            self.defs[known] = {}          # reserve (sections may refer to themselves)
            self.defs[known] = self.section(sec, known, nullable=True)
        return {"$ref": f"#/$defs/{known}"}

    def section(self, sec: K.Section, name: str, *, type_const: str | None = None,
                nullable: bool = False) -> dict[str, Any]:
        """A section's schema. A shared definition also admits null (an empty section means its
        defaults); a key that may not be empty adds ``"type": "object"`` beside its $ref."""
        props: dict[str, Any] = {}
        if type_const is not None:
            props["type"] = {"const": type_const, "description": f"{type_const}: {sec.doc}"}
        required = ["type"] if type_const is not None else []
        for key in sec.keys:
            props[key.name] = self.key(key, f"{name}.{key.name}")
            if key.required:
                required.append(key.name)
        out: dict[str, Any] = {"type": ["object", "null"] if nullable else "object",
                               "title": sec.path or "scenario",
                               "description": _sentence(sec.doc), "properties": props,
                               "additionalProperties": False}
        rules = []
        for rule in sec.rules:
            if rule.schema is None:
                continue
            rules.append(rule.schema(sec, required) if callable(rule.schema) else dict(rule.schema))
        if required:
            out["required"] = required
        if rules:
            out["allOf"] = rules
        return out

    def key(self, key: K.Key, name: str) -> dict[str, Any]:
        schema = _KINDS[key.kind](self, key, name)
        nullable = key.nullable and not key.required     # a required key written empty is refused
        if key.kind in ("sub", "variant"):
            if not nullable:
                schema["type"] = "object"
        elif nullable and key.kind in _NULLABLE_BY_TYPE:
            schema = _or_null(schema)
        elif nullable:
            schema = {"anyOf": [schema, {"type": "null"}]}
        doc = _describe(key)
        schema = {"description": doc, "markdownDescription": _markdown(key), **schema}
        default = _default(key)
        if default is not _NONE:
            schema["default"] = default
        return schema


_NONE = object()
_NULLABLE_BY_TYPE = {"number", "text", "listed", "points", "rows", "marks", "elements", "names", "free", "point"}


def _or_null(schema: dict[str, Any]) -> dict[str, Any]:
    kind = schema.get("type")
    if isinstance(kind, str):
        return {**schema, "type": [kind, "null"]}
    return {"anyOf": [schema, {"type": "null"}]}


def _default(key: K.Key) -> Any:
    value = key.default
    if value is K.REQUIRED or value is None or key.default_doc:
        return _NONE
    if isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, tuple) and all(isinstance(v, (int, float, str)) for v in value):
        return list(value)
    if isinstance(value, tuple) and not value:
        return []
    return _NONE        # a section's defaults are its keys' defaults


def _sentence(text: str) -> str:
    return text[:1].upper() + text[1:]


def _describe(key: K.Key) -> str:
    """One line: the description, then unit, range and default in brackets (hover text)."""
    facts = [f for f in (key.unit, describe_range(key)) if f]
    default = describe_default(key)
    if default:
        facts.append(f"default {default}")
    return _sentence(key.doc) + (f" [{'; '.join(facts)}]" if facts else "")


def _markdown(key: K.Key) -> str:
    facts = [f for f in (key.unit and f"unit: {key.unit}", describe_range(key) and f"range: {describe_range(key)}",
                         describe_default(key) and f"default: {describe_default(key)}") if f]
    return f"**{key.name}**: {key.doc}" + (f"  \n{' · '.join(facts)}" if facts else "")


def describe_range(key: K.Key) -> str:
    """The allowed values in words (also the reference page's "range" column)."""
    if isinstance(key, K.Number):
        return _interval(key.low, key.low_open, key.le)
    if isinstance(key, K.Integer):
        return f"{key.ge} … {key.le}" if key.le < 10**9 else f"{key.ge} … 2⁶³−1"
    if isinstance(key, (K.Choice,)):
        return " | ".join(key.options)
    if isinstance(key, K.Version):
        return " | ".join(map(str, key.versions))
    if isinstance(key, K.Scale):
        return f"each in (0, {key.le:g}]"
    if isinstance(key, K.Range):
        return f"h in [0, {key.limit:g}] or [lo ≤ 0, hi ≥ 0] within ±{key.limit:g}"
    if isinstance(key, K.SizeRange):
        return f"(0, {key.le:g}]"
    if isinstance(key, K.Points):
        return f"{key.min} … {key.max} points"
    if isinstance(key, (K.Listed, K.Elements)):
        return f"up to {key.max}"
    if isinstance(key, K.Rows):
        return f"up to {key.max} rows"
    if isinstance(key, K.Names):
        return f"up to {key.max} names"
    if isinstance(key, K.Text) and key.name_rules:
        return f"one line, ≤ {int(SCENARIO_LIMITS['max_name_length'])} characters"
    return ""


def _interval(low: float | None, low_open: bool, high: float | None) -> str:
    if low is None and high is None:
        return ""
    if high is None:
        return f"{'>' if low_open else '≥'} {low:g}"
    if low is None:
        return f"≤ {high:g}"
    return f"{'(' if low_open else '['}{low:g}, {high:g}]"


def describe_default(key: K.Key) -> str:
    """The default in words (also the reference page's "default" column)."""
    if key.default_doc:
        return key.default_doc
    value = key.default
    if value is K.REQUIRED:
        return "required"
    if value is None:
        return "none"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, (int, str)):
        return str(value) if value != "" else '""'
    if isinstance(value, tuple):
        if not value:
            return "[]"
        if len(set(value)) == 1 and isinstance(key, K.Scale):
            return f"{value[0]:g}"
        return "[" + ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value) + "]"
    return ""


# --------------------------------------------------------------------------- one schema per kind

def _number_schema(low: float | None = None, low_open: bool = False, high: float | None = None) -> dict[str, Any]:
    out: dict[str, Any] = {"type": "number"}
    if low is None or low < -MAX_ABS:
        out["minimum"] = -MAX_ABS
    elif low_open:
        out["exclusiveMinimum"] = low
    else:
        out["minimum"] = low
    out["maximum"] = MAX_ABS if high is None or high > MAX_ABS else high
    return out


def _number(b: _Builder, key: K.Number, name: str) -> dict[str, Any]:
    return _number_schema(key.low, key.low_open, key.le)


def _integer(b: _Builder, key: K.Integer, name: str) -> dict[str, Any]:
    return {"type": "integer", "minimum": key.ge, "maximum": key.le}


def _text(b: _Builder, key: K.Text, name: str) -> dict[str, Any]:
    out: dict[str, Any] = {"type": "string"}
    patterns = []
    if key.nonempty:
        patterns.append(_NOT_BLANK)
    if key.name_rules:
        out["maxLength"] = int(SCENARIO_LIMITS["max_name_length"])
        patterns.append(_NO_CONTROL)
        if key.file_name:
            patterns.append(_FILE_NAME)
        elif key.name == "family":
            patterns.append(_FOLDER_PATH)
    if key.path:
        patterns.append(_NO_NUL)
    if len(patterns) == 1:
        out["pattern"] = patterns[0]
    elif patterns:
        out["allOf"] = [{"pattern": p} for p in patterns]
    return out


def _flag(b: _Builder, key: K.Flag, name: str) -> dict[str, Any]:
    return {"type": "boolean"}


def _choice(b: _Builder, key: K.Choice, name: str) -> dict[str, Any]:
    return {"type": "string", "enum": list(key.options)}


def _version(b: _Builder, key: K.Version, name: str) -> dict[str, Any]:
    return {"type": "integer", "enum": list(key.versions)}


def _sub(b: _Builder, key: K.Sub, name: str) -> dict[str, Any]:
    return b.ref(key.section, _def_name(key.section.path, name))


def _listed(b: _Builder, key: K.Listed, name: str) -> dict[str, Any]:
    return {"type": "array", "maxItems": key.max, "items": b.ref(key.section, _def_name(key.section.path, name))}


def _point(b: _Builder, key: K.Key, name: str) -> dict[str, Any]:
    return {"type": "array", "items": _number_schema(), "minItems": 2, "maxItems": 2}


def _points(b: _Builder, key: K.Points, name: str) -> dict[str, Any]:
    return {"type": "array", "items": _point(b, key, name), "minItems": key.min, "maxItems": key.max}


def _rows(b: _Builder, key: K.Rows, name: str) -> dict[str, Any]:
    width = len(key.columns)
    return {"type": "array", "maxItems": key.max,
            "items": {"type": "array", "items": _number_schema(), "minItems": width, "maxItems": width}}


def _scale(b: _Builder, key: K.Scale, name: str) -> dict[str, Any]:
    one = _number_schema(0.0, True, key.le)
    return {"oneOf": [one, {"type": "array", "items": one, "minItems": 3, "maxItems": 3}]}


def _free(b: _Builder, key: K.Free, name: str) -> dict[str, Any]:
    return {"type": "object"}


def _marks(b: _Builder, key: K.Marks, name: str) -> dict[str, Any]:
    return {"type": "array", "maxItems": key.max, "items": {"oneOf": [
        {"type": "string", "pattern": _IDENTIFIER},
        {"type": "object", "minProperties": 1, "maxProperties": 1, "propertyNames": {"pattern": _IDENTIFIER}},
    ]}}


def _typed(b: _Builder, key: K.Elements | K.Variant, name: str) -> dict[str, Any]:
    """One mapping whose ``type`` chooses its keys: an if/then per type (precise errors, and
    completion of the chosen type's keys)."""
    branches = []
    for element in key.types:
        def_name = _def_name(element.section.path, f"{name}.{element.type}")
        if def_name not in b.defs:
            b.defs[def_name] = b.section(element.section, def_name, type_const=element.type, nullable=True)
        branches.append({"if": {"properties": {"type": {"const": element.type}}, "required": ["type"]},
                         "then": {"$ref": f"#/$defs/{def_name}"}})
    return {"type": ["object", "null"] if key.nullable and isinstance(key, K.Variant) else "object",
            "required": ["type"],
            "properties": {"type": {"enum": list(key.type_names), "description": "which kind: "
                                    + ", ".join(key.type_names)}},
            "allOf": branches}


def _elements(b: _Builder, key: K.Elements, name: str) -> dict[str, Any]:
    return {"type": "array", "maxItems": key.max, "items": _typed(b, key, name)}


def _range(b: _Builder, key: K.Range, name: str) -> dict[str, Any]:
    return {"oneOf": [
        {"type": "number", "minimum": 0, "maximum": key.limit},
        {"type": "array", "minItems": 2, "maxItems": 2,
         "prefixItems": [{"type": "number", "minimum": -key.limit, "maximum": 0},
                         {"type": "number", "minimum": 0, "maximum": key.limit}]},
    ]}


def _size_range(b: _Builder, key: K.SizeRange, name: str) -> dict[str, Any]:
    one = _number_schema(0.0, True, key.le)
    return {"oneOf": [one, {"type": "array", "items": one, "minItems": 2, "maxItems": 2}]}


def _names(b: _Builder, key: K.Names, name: str) -> dict[str, Any]:
    return {"oneOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}, "maxItems": key.max}]}


_KINDS: dict[str, Callable[..., dict[str, Any]]] = {
    "number": _number, "integer": _integer, "text": _text, "flag": _flag, "choice": _choice,
    "version": _version, "sub": _sub, "listed": _listed, "point": _point, "points": _points, "rows": _rows,
    "scale": _scale, "free": _free, "marks": _marks, "elements": _elements, "variant": _typed,
    "range": _range, "size_range": _size_range, "names": _names,
}


def _def_name(path: str, fallback: str) -> str:
    """A $defs name from a section's path: robot.limits, obstacles.box, robot.body.wheeled."""
    name = re.sub(r"(\[\])? \((\w+)\)", r".\2", path).replace("[]", "").replace(" ", "")
    return name or fallback
