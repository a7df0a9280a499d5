"""The scenario format as data: each YAML key's type, range, allowed values, default, unit and a
one-line description, declared next to the dataclass it fills (``model.py``, ``obstacles.py``,
``robot.py``; new sections and element types in their own modules, e.g. ``terrain.py``).

One source for four readers: the loader reads a file by these declarations (``loader.py``), the
JSON Schema for editors is generated from them (``json_schema.py``), so is the key table of the
scenario-format reference page (``docs/hooks/reference.py``), and the failure search takes its
limits from them (``search_keys.py``). A test checks that the loader and the schema agree.

Declaring a section: the dataclass as usual (its defaults are the format's defaults), then one
``Key`` per YAML key, in the order the reference lists them::

    @dataclass(frozen=True)
    class Safety:
        enabled: bool = True
        horizon: float = 0.5            # s
        margin: float = 0.05            # m

    SAFETY = section(Safety, "robot.safety", "the collision safety layer", [
        Flag("enabled", "", "the safety layer halts the robot (outcome safety-stop)"),
        Number("horizon", "s", "how far ahead the current velocity is extrapolated", gt=0),
        Number("margin", "m", "the footprint grown by this", ge=0),
    ])

and name it where it sits: a ``Sub`` key of its parent section (``Sub("safety", "", "the
collision safety layer", section=SAFETY)``), or an ``Element`` of a typed list such as
``obstacles``. Rules across keys (``range_max > range_min``) are ``Rule`` objects of the section:
the loader runs them, the schema includes those that JSON Schema can say, and the reference lists
the others as "checks that need a run". Every number is also bounded by
``SCENARIO_LIMITS["max_abs_value"]``. Then regenerate the two committed copies of the schema
(``navscenario schema -o .navscenario/scenario-v1.json`` and the same file into this folder).

This module holds no I/O and imports nothing heavy (it is read when a scenario loads).
"""
from __future__ import annotations

import dataclasses
from dataclasses import KW_ONLY, dataclass, field
from types import MappingProxyType
from typing import Any, Callable, ClassVar, Collection, Iterator, Mapping, Sequence

#: Limits that keep hostile or absurd files from hanging or crashing a run (documented in
#: docs/reference/scenario-format.md).
SCENARIO_LIMITS: Mapping[str, float] = MappingProxyType({
    "max_file_bytes": 5_000_000,       # a scenario file larger than this is refused unread
    "max_depth": 64,                    # YAML nesting levels
    "max_nodes": 500_000,               # YAML values after expanding aliases (alias bombs)
    "max_obstacles": 5_000,
    "max_waypoints": 1_000,
    "max_reference_points": 50_000,
    "max_abs_value": 1e6,               # any coordinate, size, time or angle (m, s, deg)
    "max_lidar_beams": 10_000,
    "max_lidar3d_rays": 262_144,        # rings x beams of robot.lidar3d (128 x 2048, the densest units)
    "max_lidar3d_record_bytes": 2**30,  # its ranges recorded over an episode (float32 a ray a tick)
    "max_episode_steps": 10_000_000,    # timeout / timestep
    "max_name_length": 200,
})
MAX_ABS = float(SCENARIO_LIMITS["max_abs_value"])


class _Marker:
    def __init__(self, name: str):
        self.name = name

    def __repr__(self) -> str:
        return self.name


#: The key must be written (no default).
REQUIRED: Any = _Marker("REQUIRED")
#: The default is the dataclass field's default (resolved by ``section``).
FROM_CLASS: Any = _Marker("FROM_CLASS")


# --------------------------------------------------------------------------- key kinds

@dataclass(frozen=True)
class Key:
    """One YAML key. ``name`` is the key as written, ``unit`` its unit ("" for none), ``doc`` one
    line saying what it means. ``default`` is REQUIRED or the value when the key is absent (by
    default the dataclass field's); ``attr`` the dataclass field it fills when not ``name``;
    ``example`` the line a "missing" error suggests; ``nullable``: an empty value (null) is
    allowed and means the default; ``default_doc`` the default in words when it is not a value."""
    name: str
    unit: str
    doc: str
    _: KW_ONLY
    default: Any = FROM_CLASS
    attr: str = ""
    example: str = ""
    nullable: bool = False
    default_doc: str = ""
    kind: ClassVar[str] = "key"

    def __post_init__(self) -> None:
        object.__setattr__(self, "field", self.attr or self.name)   # the dataclass field it fills

    @property
    def required(self) -> bool:
        return self.default is REQUIRED


@dataclass(frozen=True)
class Number(Key):
    """A finite number (integers are accepted); ``ge``/``gt`` a lower bound (inclusive/exclusive),
    ``le`` an upper one. |value| <= max_abs_value always."""
    _: KW_ONLY
    ge: float | None = None
    gt: float | None = None
    le: float | None = None
    kind: ClassVar[str] = "number"

    def __post_init__(self) -> None:
        super().__post_init__()     # the loader's arguments, worked out once (a number is read often)
        object.__setattr__(self, "low", self.gt if self.gt is not None else self.ge)
        object.__setattr__(self, "low_open", self.gt is not None)

    @property
    def span(self) -> tuple[float, float]:
        """The closed range the value can take (the magnitude bound included)."""
        low = self.low if self.low is not None else -MAX_ABS
        return (max(low, -MAX_ABS), min(self.le if self.le is not None else MAX_ABS, MAX_ABS))


@dataclass(frozen=True)
class Integer(Key):
    """A whole number from ``ge`` to ``le`` (a float such as 3.0 counts)."""
    _: KW_ONLY
    ge: int = 0
    le: int = 2**63 - 1
    kind: ClassVar[str] = "integer"


@dataclass(frozen=True)
class Text(Key):
    """A string. ``nonempty``: blank text is an error; ``name_rules``: a one-line label of at most
    max_name_length characters; ``file_name``: also no '/' or '\\' (it names files); ``path``: a
    file path relative to the scenario's folder (no NUL byte); ``inside``: one that must stay in
    that folder (no absolute path, no '..': the mesh path rules)."""
    _: KW_ONLY
    nullable: bool = True
    nonempty: bool = True
    name_rules: bool = False
    file_name: bool = False
    path: bool = False
    inside: bool = False
    kind: ClassVar[str] = "text"


@dataclass(frozen=True)
class Flag(Key):
    """true or false."""
    kind: ClassVar[str] = "flag"


@dataclass(frozen=True)
class Choice(Key):
    """One of ``options`` (strings)."""
    _: KW_ONLY
    options: tuple[str, ...] = ()
    kind: ClassVar[str] = "choice"


@dataclass(frozen=True)
class Version(Key):
    """The format version: one of ``versions``."""
    _: KW_ONLY
    versions: tuple[int, ...] = ()
    kind: ClassVar[str] = "version"


@dataclass(frozen=True)
class Sub(Key):
    """A nested mapping read by ``section`` (empty or absent: its defaults)."""
    _: KW_ONLY
    nullable: bool = True
    section: "Section | None" = None
    kind: ClassVar[str] = "sub"


@dataclass(frozen=True)
class Listed(Key):
    """A list of up to ``max`` mappings of one ``section`` (``what``: their name in messages)."""
    _: KW_ONLY
    nullable: bool = True
    section: "Section | None" = None
    max: int = 0
    what: str = ""
    kind: ClassVar[str] = "listed"


@dataclass(frozen=True)
class Point(Key):
    """A pair [x, y] of numbers."""
    kind: ClassVar[str] = "point"


@dataclass(frozen=True)
class Points(Key):
    """A list of ``min`` to ``max`` points [x, y]."""
    _: KW_ONLY
    nullable: bool = True
    min: int = 0
    max: int = 0
    kind: ClassVar[str] = "points"


@dataclass(frozen=True)
class Rows(Key):
    """A list of up to ``max`` rows of ``columns`` numbers (``[t, x, y]``)."""
    _: KW_ONLY
    nullable: bool = True
    columns: tuple[str, ...] = ()
    max: int = 0
    kind: ClassVar[str] = "rows"


@dataclass(frozen=True)
class Scale(Key):
    """One number for all three axes or three [sx, sy, sz]; each > 0 and <= ``le``."""
    _: KW_ONLY
    le: float = MAX_ABS
    kind: ClassVar[str] = "scale"


@dataclass(frozen=True)
class Free(Key):
    """Free-form data kept as written: text, numbers, true/false, null, lists and mappings."""
    _: KW_ONLY
    nullable: bool = True
    kind: ClassVar[str] = "free"


@dataclass(frozen=True)
class Marks(Key):
    """pytest marks: ``name``, ``{name: {kw: value}}``, ``{name: [a, b]}`` or ``{name: value}``."""
    _: KW_ONLY
    nullable: bool = True
    max: int = 1000
    kind: ClassVar[str] = "marks"


@dataclass(frozen=True)
class Elements(Key):
    """A list of up to ``max`` mappings, each of one of ``types`` chosen by its ``type`` key."""
    _: KW_ONLY
    nullable: bool = True
    types: tuple["Element", ...] = ()
    max: int = 0
    what: str = ""              # the items in messages: "obstacles"
    item: str = "element"       # one of them: "obstacle"
    kind: ClassVar[str] = "elements"

    def element(self, type_name: Any) -> "Element | None":
        for element in self.types:
            if element.type == type_name:
                return element
        return None

    @property
    def type_names(self) -> tuple[str, ...]:
        return tuple(e.type for e in self.types)


@dataclass(frozen=True)
class Variant(Key):
    """One mapping of one of ``types``, chosen by its ``type`` key (``body: {type: wheeled, ...}``)."""
    _: KW_ONLY
    nullable: bool = True
    types: tuple["Element", ...] = ()
    kind: ClassVar[str] = "variant"

    element = Elements.element
    type_names = Elements.type_names


@dataclass(frozen=True)
class Range(Key):
    """A search range: an offset range [lo, hi] containing 0, or one number h >= 0 meaning
    [-h, h]; |lo| and |hi| at most ``limit``. ``target`` is the key whose value the offset moves:
    the search keeps the moved value within that key's range (``default`` is a pair)."""
    _: KW_ONLY
    limit: float = MAX_ABS
    target: Key | None = None
    kind: ClassVar[str] = "range"


@dataclass(frozen=True)
class SizeRange(Key):
    """A range of sizes [lo, hi] with 0 < lo <= hi <= ``le``, or one number for both."""
    _: KW_ONLY
    le: float = MAX_ABS
    kind: ClassVar[str] = "size_range"


@dataclass(frozen=True)
class Names(Key):
    """A list of up to ``max`` names of parts of the scenario (or one name)."""
    _: KW_ONLY
    nullable: bool = True
    max: int = 0
    kind: ClassVar[str] = "names"


# --------------------------------------------------------------------------- sections

@dataclass(frozen=True)
class Rule:
    """A check across the keys of one section. ``check(values, given)`` gets the values read (by
    dataclass field) and the set of keys written, and returns None or (key, message, fix): the
    loader reports it at that key (None: the loader's own code for that section checks it, e.g.
    a motion's path or velocity). ``schema``: the same rule as a JSON Schema fragment merged into
    the section's schema, when JSON Schema can say it (else the reference lists it among the
    checks that need a run)."""
    doc: str
    check: Callable[[Mapping[str, Any], Collection[str]], Any] | None
    schema: Mapping[str, Any] | None = None


@dataclass(frozen=True, eq=False)
class Section:
    """A mapping with a known set of keys, filling dataclass ``cls``. ``path`` says where it is in
    a file (``robot.limits``; an element type ``obstacles[] (box)``), ``what`` how messages name it
    (``the velocity limits (a mapping)``)."""
    path: str
    cls: type | None
    doc: str
    keys: tuple[Key, ...]
    what: str = "a mapping"
    rules: tuple[Rule, ...] = ()
    home: bool = True           # its keys are suggested when written in the wrong section
    names: tuple[str, ...] = field(init=False)
    by_name: Mapping[str, Key] = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "names", tuple(k.name for k in self.keys))
        object.__setattr__(self, "by_name", MappingProxyType({k.name: k for k in self.keys}))
        if len(self.by_name) != len(self.keys):
            raise ValueError(f"{self.path}: a key is declared twice")

    def __getitem__(self, name: str) -> Key:
        return self.by_name[name]

    def derive(self, path: str, doc: str, *, defaults: Mapping[str, Any] | None = None,
               keys: Mapping[str, Key] | None = None, what: str | None = None) -> "Section":
        """The same section with other defaults (``{key: value}``) or keys replaced (``{key: Key}``):
        e.g. a person is a cylinder with a person's size and walking speed as defaults."""
        new = []
        for key in self.keys:
            if keys and key.name in keys:
                key = keys[key.name]
            if defaults and key.name in defaults:
                key = dataclasses.replace(key, default=defaults[key.name])
            new.append(key)
        return Section(path, self.cls, doc, tuple(new), what or self.what, self.rules, self.home)


@dataclass(frozen=True, eq=False)
class Element:
    """One type of a typed list (``type: box``): its keys (``section``, without ``type``), the prefix
    of its generated names (box1, box2 ...) and a one-line description."""
    type: str
    section: Section
    prefix: str
    doc: str


def section(cls: type | None, path: str, doc: str, keys: Sequence[Key], *, what: str = "a mapping",
            rules: Sequence[Rule] = (), home: bool = True) -> Section:
    """Declare the section ``path`` filling dataclass ``cls`` (None: kept as a mapping): each key's
    default is resolved from the dataclass field it fills unless given; a key naming no field of
    ``cls`` is an error here, at import, not when a file is read."""
    resolved = []
    fields = {f.name: f for f in dataclasses.fields(cls)} if cls is not None else {}
    for key in keys:
        if key.default is FROM_CLASS:
            f = fields.get(key.field)
            if f is None:
                if cls is not None:
                    raise ValueError(f"{path}.{key.name}: {cls.__name__} has no field {key.field!r}")
                default = REQUIRED
            elif f.default is not dataclasses.MISSING:
                default = f.default
            elif f.default_factory is not dataclasses.MISSING:
                default = f.default_factory()
            else:
                default = REQUIRED
            key = dataclasses.replace(key, default=default)
        resolved.append(key)
    return Section(path, cls, doc, tuple(resolved), what, tuple(rules), home)


def walk(root: Section, path: str = "") -> Iterator[tuple[str, Section]]:
    """Every section under ``root`` (root included), depth first in key order, with the dotted path
    of where it is written (``robot.lidar``, ``obstacles[]`` for each element type)."""
    yield path, root
    for key in root.keys:
        child = f"{path}.{key.name}" if path else key.name
        if isinstance(key, (Sub, Listed)) and key.section is not None:
            yield from walk(key.section, child + ("[]" if isinstance(key, Listed) else ""))
        elif isinstance(key, (Elements, Variant)):
            for element in key.types:
                yield from walk(element.section, child + ("[]" if isinstance(key, Elements) else ""))
