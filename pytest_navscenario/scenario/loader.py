"""Scenario YAML: load and validate, with file:line errors (writing is in dump.py).

    load_scenario(path)                 -> Scenario   name/family default to file stem / folder name
    loads_scenario(text, source=None, *, name=None, family=None) -> Scenario
    scenario_from_dict(data, source=None) -> Scenario
    check_scenario(scenario)                          semantic checks only (for generated scenarios)
    looks_like_scenario(text_or_mapping) -> bool      cheap test for collectors
    SCENARIO_LIMITS                                   the documented limits for hostile files

Every problem raises ``ScenarioError`` naming the file, the line, the dotted field and a fix.
This module holds the entry points (bytes and text in, one part read at a time in ``_build``); each
part's reader is in ``part_readers.py``, the checks across fields (``check_scenario``,
``max_resolved_speed``) in ``scenario_checks.py``; both are re-exported here.
Parsing has ``yaml.safe_load`` semantics (see ``yaml_tree``), plus one convenience: an unquoted
number in exponent form that YAML 1.1 reads as a string (``1e-3``, ``2.5e3``) is accepted where a
number is expected.
"""
from __future__ import annotations

import codecs
import difflib
import os
import re
import stat
from dataclasses import replace
from pathlib import Path
from typing import Any, Mapping


from ..core.errors import ScenarioError
from . import keys as K  # noqa: F401  (re-exported)
from .format import SCENARIO, SUPPORTED_VERSIONS
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
    BoxObstacle,
    CylinderObstacle,
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
from .part_readers import (  # noqa: F401  (each part's reader; the others re-exported, they lived here)
    _IDENT,
    _family,
    _marks,
    _mesh,
    _mission,
    _mjcf_file,
    _motion,
    _name,
    _obstacle,
    _obstacles,
    _polygon_points,
    _pose,
    _reference,
    _requirements_part,
    _robot,
    _simulation,
    _terrain_element,
)
from .reading import (  # noqa: F401  (the readers, under the names this module always used)
    _MAX_ABS,
    BROKEN,
    _Ctx,
    _Section,
    _build_section,
    _check_family,
    _check_name,
    _free,
    _join,
    _mapping,
    _point,
    _read,
    _read_choice,
    _read_elements,
    _read_number,
    _read_scale,
    _read_sub,
    _read_text,
)
from .scenario_checks import (  # noqa: F401  (the checks across fields; re-exported, they lived here)
    STEP_SHARE,
    _check_clear,
    _check_lidar3d,
    _check_speeds,
    _closing,
    _decimal,
    _min_width,
    _steps_per_tick,
    check_scenario,
    max_resolved_speed,
)
from .search_settings import read_search
from .yaml_tree import YMap, YNode, YScalar, YSeq, describe, from_plain, parse_yaml  # noqa: F401

_LIST_LIMITS = {"obstacles": (int(SCENARIO_LIMITS["max_obstacles"]), "obstacles")}  # refused while parsing

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


# --------------------------------------------------------------------------- entry points

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
    # Each part is read on its own: with ctx.collect a mistake in one is recorded and the others
    # are still read, so that one pass reports every mistake it can find (ctx.finish).
    parts = {
        "name": ctx.attempt(_name, ctx, top, name),
        "family": ctx.attempt(_family, ctx, top, family),
        "description": ctx.attempt(lambda: top.string("description", "", nonempty=False)),
        "marks": ctx.attempt(_marks, ctx, top),
        "robot": ctx.attempt(_robot, ctx, top),
        "mission": ctx.attempt(_mission, ctx, top),
        "obstacles": ctx.attempt(_obstacles, ctx, top),
        "terrain": ctx.attempt(_read_elements, ctx, top, SCENARIO["terrain"], _terrain_element),
        "simulation": ctx.attempt(_simulation, ctx, top),
        "reference": ctx.attempt(_reference, ctx, top),
        "search": ctx.attempt(_mapping, ctx, top, "search"),
        "provenance": ctx.attempt(_mapping, ctx, top, "provenance"),
    }
    judged = ctx.attempt(_requirements_part, ctx, top, parts)
    ctx.finish()
    scenario = Scenario(version=int(version), source=ctx.source, **parts)
    if judged is not None:
        scenario = replace(scenario, signals=judged[0], requirements=judged[1])
    if scenario.search is not None:     # the search's space, checked on plain runs too
        read_search(ctx, top.get("search"), "search", top.line_of("search"),
                    obstacles=tuple(o.name for o in scenario.obstacles), waypoints=len(scenario.mission.waypoints),
                    terrain=tuple(el.name for el in scenario.terrain))
        ctx.finish()
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
    ctx = _Ctx(src, collect=True)
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
    return _build(root, _Ctx(src, collect=True), None, None)


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
        # O_NONBLOCK: opening a named pipe (a FIFO named like a scenario) would wait for a writer forever
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
        with open(fd, "rb") as fh:
            info = os.fstat(fh.fileno())
            if stat.S_ISDIR(info.st_mode):
                raise IsADirectoryError(src)
            if not stat.S_ISREG(info.st_mode):
                raise ScenarioError("is not a regular file (a named pipe, socket or device)", path=src,
                                    hint="pass the scenario's .yaml file itself")
            size = info.st_size   # read(limit + 1) alone would allocate 5 MB per file
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


# --------------------------------------------------------------------------- lines of a loaded file

def field_line(source: str | os.PathLike | None, field: str) -> int | None:
    """The line of a dotted field (``robot.body.file``) in the scenario file ``source``, for an
    error found after loading (at run time); None when the file or the field is not there."""
    if not source:
        return None
    try:
        text = _decode(Path(source).read_bytes()[:int(SCENARIO_LIMITS["max_file_bytes"])], os.fspath(source))
        node = parse_yaml(text, os.fspath(source), max_depth=int(SCENARIO_LIMITS["max_depth"]),
                          max_nodes=int(SCENARIO_LIMITS["max_nodes"]))
    except (OSError, ScenarioError):
        return None
    line = None
    for key in field.split("."):
        if not isinstance(node, YMap) or key not in node.items:
            break
        key_line, node = node.items[key]
        line = key_line or node.line
    return line
