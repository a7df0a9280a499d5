"""The policy declaration: the YAML beside a model file that says what observation the policy was
trained on and what action it answers, read into ``Declaration`` with the line of every field so
that each mistake is reported as ``nav.policy.yaml:12: observation[0].lidar.beams: ...``.

Where it is read from (``find_declaration``): the file ``<model stem>.policy.yaml`` beside the model
(``nav.onnx`` -> ``nav.policy.yaml``), else the model's own metadata (ONNX ``metadata_props`` key
``navscenario.policy``, holding the same YAML text). When both exist they must say the same.

The format (``navscenario-policy: 1``)::

    navscenario-policy: 1        # marks the file and its format version
    name: corridor-ppo           # optional: the subject's name in results (default: the model's stem)
    version: ckpt-1200           # optional (default: "sha256:" and the first 12 hex digits of the model)
    input: obs                   # optional when the model has one input
    output: action               # optional when the model has one output
    observation:                 # the model's input row: these fields, concatenated in this order
      - lidar: {beams: 64, fov: 360, resample: min, clip: [0.0, 5.0], std: 5.0}
      - target: {form: polar}    # the next waypoint (else the goal) in the robot frame
      - velocity: {components: [vx, wz]}
      - previous_command: {components: [vx, wz]}
    action:
      components: [vx, wz]       # the model's outputs, in order ([vx, vy, wz] for an omni drive)
      clip: [-1.0, 1.0]          # the raw outputs clipped to this
      scale: limits              # then multiplied: a number, one per component, or the robot's limits

Every observation field takes ``clip`` ([low, high], or one pair per value), then ``mean`` and
``std`` (a number or one per value): the model sees ``(clip(value) - mean) / std``.
"""
from __future__ import annotations

import difflib
import hashlib
import math
import re
import os
from dataclasses import dataclass, field
from typing import Any

from ...core.errors import ScenarioError, SubjectLoadError
from ...scenario.keys import SCENARIO_LIMITS
from ...scenario.yaml_tree import YMap, YNode, YScalar, YSeq, describe, parse_yaml

FORMAT_KEY = "navscenario-policy"
FORMAT_VERSION = 1
METADATA_KEY = "navscenario.policy"      # the ONNX metadata_props key that may hold the declaration
SUFFIX = ".policy.yaml"

COMPONENTS = ("vx", "vy", "wz")           # a command's components, robot frame (m/s, m/s, rad/s)
FIELD_KINDS = ("lidar", "target", "goal", "velocity", "previous_command")
FORMS = ("polar", "cartesian")
RESAMPLING = ("min", "nearest")
TOP_KEYS = (FORMAT_KEY, "name", "version", "input", "output", "observation", "action")
_FIELD_KEYS = {
    "lidar": ("beams", "fov", "resample", "clip", "mean", "std"),
    "target": ("form", "clip", "mean", "std"),
    "goal": ("form", "clip", "mean", "std"),
    "velocity": ("components", "clip", "mean", "std"),
    "previous_command": ("components", "clip", "mean", "std"),
}
ACTION_KEYS = ("components", "clip", "scale")
_LIMITS = 50_000          # nodes: a declaration is a few dozen
_NUMBER_WORD = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+")   # = scenario.reading's: 1e-3 unquoted
MAX_LABEL = int(SCENARIO_LIMITS["max_name_length"])   # characters of a name or version
MAX_OBSERVATION = 100_000   # values in the observation row, all fields together (= one lidar's beam limit)
MAX_FIELDS = 1_000          # fields in the observation


class DeclarationError(SubjectLoadError):
    """A policy declaration is missing, unreadable or invalid: file, line, field, what, fix."""

    def __init__(self, message: str, *, path: str | None = None, line: int | None = None,
                 field: str | None = None, hint: str | None = None):
        self.path, self.line, self.field, self.hint = path, line, field, hint
        super().__init__(ScenarioError(message, path=path, line=line, field=field, hint=hint).format())


@dataclass(frozen=True)
class Feature:
    """One field of the observation row: ``width`` values, clipped, then (value - mean) / std."""
    kind: str                                  # one of FIELD_KINDS
    width: int
    where: str                                 # "observation[0].lidar", for messages
    line: int | None = field(default=None, compare=False)
    clip: tuple[tuple[float, float], ...] | None = None   # one (low, high) per value
    mean: tuple[float, ...] = ()
    std: tuple[float, ...] = ()
    beams: int = 0                             # lidar: beams the policy sees
    fov: float = 0.0                           # lidar: degrees, centred on the heading
    resample: str = "min"                      # lidar: how the scenario's beams become `beams`
    form: str = "polar"                        # target/goal: polar (distance, bearing) or cartesian (x, y)
    components: tuple[int, ...] = ()           # velocity/previous_command: indices into COMPONENTS

    def describe(self) -> str:
        """``lidar (64 beams)``, ``target (polar: distance, bearing)``, ``velocity (vx, wz)``."""
        if self.kind == "lidar":
            return f"lidar ({self.beams} beams)"
        if self.kind in ("target", "goal"):
            return f"{self.kind} ({self.form}: {'distance, bearing' if self.form == 'polar' else 'x, y'})"
        return f"{self.kind} ({', '.join(COMPONENTS[c] for c in self.components)})"


@dataclass(frozen=True)
class Action:
    """The model's output row: which command components, clipped, then scaled."""
    components: tuple[int, ...]                # indices into COMPONENTS, in output order
    line: int | None = field(default=None, compare=False)
    clip: tuple[tuple[float, float], ...] | None = None
    scale: tuple[float, ...] | str = ()         # one per component, or "limits"

    @property
    def width(self) -> int:
        return len(self.components)


@dataclass(frozen=True)
class Declaration:
    """What a policy was trained on (see the module docstring)."""
    source: str                                # the file, or "the metadata of nav.onnx"
    observation: tuple[Feature, ...]
    action: Action
    name: str | None = None
    version: str | None = None
    input: str | None = None
    output: str | None = None
    lines: dict[str, int | None] = field(default_factory=dict, compare=False)

    @property
    def width(self) -> int:
        """The number of values in the model's input row."""
        return sum(f.width for f in self.observation)

    def layout(self) -> str:
        """``lidar (64 beams) 64 + target (polar: distance, bearing) 2 + ...`` for messages."""
        return " + ".join(f"{f.describe()} {f.width}" for f in self.observation)


def declaration_path(model: str | os.PathLike) -> str:
    """The declaration file that belongs beside ``model``: ``nav.onnx`` -> ``nav.policy.yaml``."""
    model = os.fspath(model)
    stem, _ = os.path.splitext(model)
    return stem + SUFFIX


def model_digest(model: str | os.PathLike) -> str:
    """``sha256:`` and the first 12 hex digits of the model file: its default version."""
    h = hashlib.sha256()
    with open(model, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return "sha256:" + h.hexdigest()[:12]


def find_declaration(model: str, metadata: dict[str, str]) -> Declaration:
    """The model's declaration: the ``.policy.yaml`` beside it, else its metadata's (see the module
    docstring). Raises DeclarationError saying where it looked and how to write one."""
    path = declaration_path(model)
    embedded = metadata.get(METADATA_KEY)
    from_file = None
    if os.path.exists(path) and not os.path.isfile(path) and not os.path.isdir(path):
        raise DeclarationError(f"{path} is not a regular file (a named pipe, socket or device): reading it would "
                               f"wait", path=None, hint=f"write the declaration as a file {os.path.basename(path)}")
    if os.path.exists(path):
        try:
            with open(path, encoding="utf-8") as f:
                text = f.read()
        except (OSError, UnicodeDecodeError) as exc:
            raise DeclarationError(f"cannot read the policy declaration: {exc}", path=path,
                                   hint="save it as UTF-8 text readable by this user") from None
        from_file = read_declaration(text, path)
    from_meta = read_declaration(embedded, f"the metadata of {model} (key {METADATA_KEY!r})") \
        if embedded is not None else None
    if from_file is not None and from_meta is not None and _meaning(from_file) != _meaning(from_meta):
        raise DeclarationError(
            f"the model's metadata (key {METADATA_KEY!r}) declares a different observation or action than "
            f"this file", path=path, hint="delete this file or re-export the model with the same declaration")
    found = from_file or from_meta
    if found is None:
        raise DeclarationError(
            f"no policy declaration for {model}: looked for {path} and for the model's metadata key "
            f"{METADATA_KEY!r}", path=None,
            hint=f"write one: `navscenario policy-template {model}` writes {os.path.basename(path)} to edit "
                 f"(docs/how-to/learned-policies.md)")
    return found


def _meaning(decl: Declaration) -> tuple:
    return (decl.observation, decl.action, decl.name, decl.version, decl.input, decl.output)


# ------------------------------------------------------------------------------------------ reading

class _Reader:
    """Reads the node tree, raising DeclarationError with file, line and field."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, message: str, where: str | None, line: int | None, hint: str | None = None) -> DeclarationError:
        return DeclarationError(message, path=self.source, line=line, field=where, hint=hint)

    def mapping(self, node: YNode, where: str, keys: tuple[str, ...], what: str) -> dict[str, tuple[int | None, YNode]]:
        if not isinstance(node, YMap):
            raise self.fail(f"expected {what} (a mapping), got {describe(node)}", where, node.line)
        if node.merges:
            raise self.fail("merge keys (<<) are not supported here", where, node.line, "write the keys out")
        out = {}
        for key, (line, value) in node.items.items():
            if key not in keys:
                close = difflib.get_close_matches(str(key), keys, n=1, cutoff=0.6)
                hint = f"did you mean '{close[0]}'?" if close else "use one of: " + ", ".join(keys)
                raise self.fail(f"unknown key {key!r}", where, line, hint)
            out[key] = (line, value)
        return out

    def number(self, node: YNode, where: str) -> float:
        value = node.value if isinstance(node, YScalar) else None
        if isinstance(value, str) and getattr(node, "plain", False) and _NUMBER_WORD.fullmatch(value):
            value = float(value)       # 2e-1: a string in YAML 1.1, a number in scenario files too
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(f"expected a finite number, got {describe(node)}", where, node.line)
        return float(value)

    def text(self, node: YNode, where: str) -> str:
        value = node.value if isinstance(node, YScalar) else None
        if isinstance(value, bool) or value is None or isinstance(value, (list, dict)):
            raise self.fail(f"expected a text, got {describe(node)}", where, node.line)
        return str(value)

    def choice(self, node: YNode, where: str, options: tuple[str, ...]) -> str:
        value = self.text(node, where)
        if value not in options:
            raise self.fail(f"{value!r} is not one of {', '.join(options)}", where, node.line,
                            _did_you_mean(value, options))
        return value

    def per_value(self, node: YNode, where: str, width: int, *, positive: bool = False) -> tuple[float, ...]:
        """A number for every value, or a list of ``width`` numbers."""
        if isinstance(node, YSeq):
            if len(node.items) != width:
                raise self.fail(f"has {len(node.items)} numbers, but the field has {width} value(s)", where,
                                node.line, f"give one number for all, or exactly {width}")
            values = tuple(self.number(n, f"{where}[{i}]") for i, n in enumerate(node.items))
        else:
            values = (self.number(node, where),) * width
        if positive:
            for i, v in enumerate(values):
                if v <= 0:
                    raise self.fail(f"must be > 0, got {v!r}", where, node.line,
                                    "a standard deviation divides the value")
        return values

    def clip(self, node: YNode, where: str, width: int) -> tuple[tuple[float, float], ...]:
        """[low, high] for every value, or a list of ``width`` such pairs (``.inf`` for no bound)."""
        hint = f"write [low, high] for all values, or {width} such pairs (.inf for no bound)"
        if not isinstance(node, YSeq):
            raise self.fail(f"expected [low, high], got {describe(node)}", where, node.line, hint)
        if len(node.items) == 2 and all(isinstance(n, YScalar) for n in node.items):
            pairs = [node]
        elif len(node.items) == width and all(isinstance(n, YSeq) for n in node.items):
            pairs = node.items
        else:
            raise self.fail(f"expected [low, high] or {width} pairs, got a list of {len(node.items)}", where,
                            node.line, hint)
        out = []
        for i, pair in enumerate(pairs):
            at = where if pair is node else f"{where}[{i}]"
            if not isinstance(pair, YSeq) or len(pair.items) != 2:
                raise self.fail(f"expected [low, high], got {describe(pair)}", at, pair.line, hint)
            lo, hi = (self._bound(n, at) for n in pair.items)
            if not lo <= hi:
                raise self.fail(f"low ({lo!r}) is above high ({hi!r})", at, pair.line, "swap them")
            out.append((lo, hi))
        return tuple(out) * (width if len(out) == 1 else 1)

    def _bound(self, node: YNode, where: str) -> float:
        value = node.value if isinstance(node, YScalar) else None
        if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(value):
            raise self.fail(f"expected a number (or .inf / -.inf), got {describe(node)}", where, node.line)
        return float(value)

    def components(self, node: YNode, where: str) -> tuple[int, ...]:
        hint = "a list of vx, vy, wz (each once, in the model's order), e.g. [vx, wz] for a differential drive"
        if not isinstance(node, YSeq) or not node.items:
            raise self.fail(f"expected {hint}, got {describe(node)}", where, node.line)
        names = [self.choice(n, f"{where}[{i}]", COMPONENTS) for i, n in enumerate(node.items)]
        if len(set(names)) != len(names):
            raise self.fail(f"names a component twice: {names}", where, node.line, hint)
        return tuple(COMPONENTS.index(n) for n in names)


def _did_you_mean(word: str, options: tuple[str, ...]) -> str:
    close = difflib.get_close_matches(word.lower(), options, n=1, cutoff=0.6)
    return f"did you mean '{close[0]}'?" if close else "use one of: " + ", ".join(options)


def _of_a_declaration(hint: str) -> str:
    """A hint of the YAML reader (written for scenarios) said of a policy declaration."""
    for old, new in (("this file is not a scenario", "this file is not a policy declaration"),
                     ("scenario files", "policy declarations"), ("a scenario", "a policy declaration"),
                     ("the scenario", "the declaration")):
        hint = hint.replace(old, new)
    return hint


def _one_line(r: "_Reader", text: str, key: str, line: int | None) -> None:
    """A name or version: one line of at most MAX_LABEL characters (the scenario names' rule)."""
    if any(ch in text for ch in "\n\r\t\x00"):
        raise r.fail("must be one line without tabs", key, line, "remove the line breaks")
    if len(text) > MAX_LABEL:
        raise r.fail(f"is {len(text)} characters long, more than {MAX_LABEL}", key, line, "shorten it")


def read_declaration(text: str, source: str) -> Declaration:
    """The declaration in ``text`` (read from ``source``, named in messages). Raises DeclarationError."""
    r = _Reader(source)
    try:
        root = parse_yaml(text, source, max_depth=20, max_nodes=_LIMITS)
    except ScenarioError as exc:   # the YAML reader's limits and errors, said of a declaration
        raise DeclarationError(exc.message, path=source, line=exc.line, field=exc.field,
                               hint=exc.hint and _of_a_declaration(exc.hint)) from None
    if root is None:
        raise r.fail("the policy declaration is empty", None, None,
                     f"start from `navscenario policy-template MODEL` ({FORMAT_KEY}: {FORMAT_VERSION}, "
                     f"observation, action)")
    top = r.mapping(root, "", TOP_KEYS, "the policy declaration")
    lines = {key: line for key, (line, _) in top.items()}
    if FORMAT_KEY not in top:
        raise r.fail(f"the first key must be '{FORMAT_KEY}: {FORMAT_VERSION}' (the format version)", None,
                     root.line, f"add the line '{FORMAT_KEY}: {FORMAT_VERSION}'")
    line, node = top[FORMAT_KEY]
    if not (isinstance(node, YScalar) and node.value == FORMAT_VERSION and not isinstance(node.value, bool)):
        raise r.fail(f"format version {describe(node)} is not known (this version reads {FORMAT_VERSION})",
                     FORMAT_KEY, line, "update pytest-navscenario, or write the declaration in format 1")
    texts = {}
    for key in ("name", "version", "input", "output"):
        if key in top:
            texts[key] = r.text(top[key][1], key)
            if key in ("name", "version"):      # printed in headers, results files and JUnit
                _one_line(r, texts[key], key, top[key][1].line)
    for key in ("observation", "action"):
        if key not in top:
            raise r.fail(f"'{key}' is missing", None, root.line,
                         f"declare the {key} (see `navscenario policy-template MODEL`)")
    observation = _read_observation(r, top["observation"][1])
    action = _read_action(r, top["action"][1])
    return Declaration(source=source, observation=observation, action=action, lines=lines, **texts)


def _read_observation(r: _Reader, node: YNode) -> tuple[Feature, ...]:
    hint = "a list of fields, e.g. [{lidar: {beams: 64, fov: 360}}, {target: {form: polar}}]"
    if not isinstance(node, YSeq) or not node.items:
        raise r.fail(f"expected {hint}, got {describe(node)}", "observation", node.line)
    out = []
    for i, item in enumerate(node.items):
        where = f"observation[{i}]"
        if not isinstance(item, YMap) or len(item.items) != 1:
            raise r.fail(f"expected one field name with its settings (e.g. 'target: {{form: polar}}'), "
                         f"got {describe(item) if not isinstance(item, YMap) else f'{len(item.items)} keys'}",
                         where, item.line, f"one of: {', '.join(FIELD_KINDS)}")
        (kind, (line, settings)), = item.items.items()
        if kind not in FIELD_KINDS:
            raise r.fail(f"unknown field {kind!r}", where, line, _did_you_mean(str(kind), FIELD_KINDS))
        where = f"{where}.{kind}"
        if isinstance(settings, YScalar) and settings.value is None:
            settings = YMap(line)        # `- velocity:` with nothing after it: the defaults
        if i >= MAX_FIELDS:
            raise r.fail(f"the observation has more than {MAX_FIELDS} fields", where, item.line,
                         "a policy's observation row is a few fields (lidar, target, velocity ...)")
        out.append(_read_feature(r, kind, settings, where, line))
        total = sum(f.width for f in out)
        if total > MAX_OBSERVATION:   # refused before any array of that width is made
            raise r.fail(f"brings the observation to {total} values, more than the limit of {MAX_OBSERVATION} "
                         f"(each tick's row, its clip and scale arrays are that wide)", where, line,
                         "declare the fields the policy was trained on; resample the lidar to fewer beams")
    return tuple(out)


def _read_feature(r: _Reader, kind: str, node: YNode, where: str, line: int | None) -> Feature:
    keys = r.mapping(node, where, _FIELD_KEYS[kind], f"the settings of {kind}")
    values: dict[str, Any] = {}
    if kind == "lidar":
        for key in ("beams", "fov"):
            if key not in keys:
                raise r.fail(f"'{key}' is missing: the lidar the policy was trained on", where, line,
                             "e.g. {beams: 64, fov: 360}")
        b_line, b_node = keys["beams"]
        beams = b_node.value if isinstance(b_node, YScalar) else None
        if isinstance(beams, bool) or not isinstance(beams, int) or not 1 <= beams <= 100_000:
            raise r.fail(f"expected a whole number of beams from 1 to 100000, got {describe(b_node)}",
                         f"{where}.beams", b_line)
        fov = r.number(keys["fov"][1], f"{where}.fov")
        if not 0 < fov <= 360:
            raise r.fail(f"expected degrees in (0, 360], got {fov!r}", f"{where}.fov", keys["fov"][0])
        values.update(beams=beams, fov=fov, width=beams)
        if "resample" in keys:
            values["resample"] = r.choice(keys["resample"][1], f"{where}.resample", RESAMPLING)
    elif kind in ("target", "goal"):
        values["form"] = r.choice(keys["form"][1], f"{where}.form", FORMS) if "form" in keys else "polar"
        values["width"] = 2
    else:
        comps = r.components(keys["components"][1], f"{where}.components") if "components" in keys else (0, 1, 2)
        values.update(components=comps, width=len(comps))
    width = values["width"]
    if "clip" in keys:
        values["clip"] = r.clip(keys["clip"][1], f"{where}.clip", width)
    values["mean"] = r.per_value(keys["mean"][1], f"{where}.mean", width) if "mean" in keys else (0.0,) * width
    values["std"] = r.per_value(keys["std"][1], f"{where}.std", width, positive=True) if "std" in keys \
        else (1.0,) * width
    return Feature(kind=kind, where=where, line=line, **values)


def _read_action(r: _Reader, node: YNode) -> Action:
    keys = r.mapping(node, "action", ACTION_KEYS, "the action")
    if "components" not in keys:
        raise r.fail("'components' is missing: which command the model's outputs are", "action", node.line,
                     "components: [vx, vy, wz] (omnidirectional) or [vx, wz] (differential drive)")
    comps = r.components(keys["components"][1], "action.components")
    clip = r.clip(keys["clip"][1], "action.clip", len(comps)) if "clip" in keys else None
    scale: tuple[float, ...] | str = (1.0,) * len(comps)
    if "scale" in keys:
        s_line, s_node = keys["scale"]
        if isinstance(s_node, YScalar) and s_node.value == "limits":
            scale = "limits"
        elif isinstance(s_node, YScalar) and isinstance(s_node.value, str) and not (
                s_node.plain and _NUMBER_WORD.fullmatch(s_node.value)):
            raise r.fail(f"expected a number, {len(comps)} numbers or 'limits', got {describe(s_node)}",
                         "action.scale", s_line)
        else:
            scale = r.per_value(s_node, "action.scale", len(comps))
    return Action(components=comps, line=node.line, clip=clip, scale=scale)
