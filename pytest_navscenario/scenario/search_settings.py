"""Reading a seed's ``search:`` section (declared in ``search_keys.py``): each range within its
documented limit and containing 0, counts within theirs, frozen names naming parts of this seed.
``read_search`` serves the loader (file, line, field); ``search_settings`` a mapping from Python.
"""
from __future__ import annotations

import difflib
from typing import Any, Mapping

from .keys import SCENARIO_LIMITS, Range, SizeRange
from .reading import Ctx, SectionReader, join, number
from .search_keys import MAX_INSERT, MAX_MARGIN, MAX_SIZE, RANGES, SEARCH, SearchSettings
from .yaml_tree import YNode, YScalar, YSeq, describe, from_plain, to_plain


def read_search(ctx: Ctx, node: YNode, field: str, line: int | None, *, obstacles: tuple[str, ...],
                waypoints: int, terrain: tuple[str, ...] = ()) -> SearchSettings:
    """The ``search:`` mapping ``node`` of a seed with these obstacle names and this many waypoints,
    checked key by key (file, line, field and a fix for each problem)."""
    sec = SectionReader(ctx, node, field, SEARCH.names, line=line, what=SEARCH.what)
    bounds = {key.name: _read_range(ctx, sec, key) for key in RANGES}
    min_size = sec.number("min_size", SEARCH["min_size"].default, low=0, low_open=True, high=MAX_SIZE)
    frozen = _read_frozen(ctx, sec, obstacles, waypoints, terrain)
    insert = sec.integer("insert", SEARCH["insert"].default, low=0, high=MAX_INSERT)
    if insert and len(obstacles) + insert > SCENARIO_LIMITS["max_obstacles"]:
        raise ctx.fail(f"the seed has {len(obstacles)} obstacles: with {insert} inserted it could pass the "
                       f"limit of {int(SCENARIO_LIMITS['max_obstacles'])}", join(field, "insert"),
                       sec.line_of("insert"), "insert fewer obstacles, or thin the seed out")
    insert_size = _read_sizes(ctx, sec, SEARCH["insert_size"])
    margin = sec.number("insert_margin", SEARCH["insert_margin"].default, low=0, high=MAX_MARGIN)
    remove = sec.integer("remove", SEARCH["remove"].default, low=0, high=int(SCENARIO_LIMITS["max_obstacles"]))
    if remove > len(obstacles):
        raise ctx.fail(f"the seed has {len(obstacles)} obstacle(s), so at most that many can be removed, "
                       f"got {remove}", join(field, "remove"), sec.line_of("remove"),
                       f"write remove: {len(obstacles)} or less")
    return SearchSettings(bounds, frozen, min_size, insert, insert_size, margin, remove)


def search_settings(scenario: Any, mapping: Mapping[str, Any] | None = None) -> SearchSettings:
    """The settings of ``mapping`` (default: the scenario's own ``search:``) for ``scenario``;
    errors name the scenario's file and the field (no line: the mapping comes from Python)."""
    data = dict(scenario.search or {}) if mapping is None else dict(mapping)
    ctx = Ctx(scenario.source or scenario.name or None)
    node = from_plain(data, max_depth=int(SCENARIO_LIMITS["max_depth"]),
                      max_nodes=int(SCENARIO_LIMITS["max_nodes"]), source=ctx.source)
    return read_search(ctx, node, "search", None, obstacles=tuple(o.name for o in scenario.obstacles),
                       waypoints=len(scenario.mission.waypoints),
                       terrain=tuple(el.name for el in getattr(scenario, "terrain", ())))


# -- the kinds only search: has ----------------------------------------------------------------
def _pair(ctx: Ctx, node: YSeq, field: str, line: int | None, example: str) -> tuple[float, float]:
    if len(node.items) != 2:
        raise ctx.fail(f"a range needs exactly two numbers [lo, hi], got {to_plain(node)!r}", field,
                       node.line or line, f"write e.g. {example}")
    return (number(ctx, node.items[0], field, line), number(ctx, node.items[1], field, line))


def _read_range(ctx: Ctx, sec: SectionReader, key: Range) -> tuple[float, float]:
    node = sec.get(key.name)
    if node is None:
        return key.default
    field, line = join(sec.path, key.name), sec.line_of(key.name)
    unit = f" {key.unit}" if key.unit else ""
    if isinstance(node, YSeq):
        lo, hi = _pair(ctx, node, field, line, f"{key.name}: [-0.5, 0.5]")
    else:
        half = number(ctx, node, field, line)
        if half < 0:
            raise ctx.fail(f"a single number is a half-width and must be >= 0, got {half:g}", field, line,
                           f"write {key.name}: {-half:g} (meaning [{half:g}, {-half:g}])")
        if half > key.limit:
            raise ctx.fail(f"{half:g}{unit} is more than the limit of {key.limit:g}{unit}", field, line,
                           _limit_fix(key))
        lo, hi = -half, half
    if lo > hi:
        raise ctx.fail(f"inverted bounds [{lo:g}, {hi:g}] (lo > hi)", field, line, f"write [{hi:g}, {lo:g}]")
    if lo == hi and lo != 0:
        raise ctx.fail(f"empty bounds [{lo:g}, {hi:g}]: no room to search", field, line,
                       "give a range containing 0, e.g. [-0.5, 0.5], or 0 to leave it fixed")
    if not lo <= 0 <= hi:
        raise ctx.fail(f"bounds [{lo:g}, {hi:g}] do not contain 0, so the seed itself is outside the search "
                       "space", field, line,
                       f"offsets are relative to the seed: use e.g. [{min(lo, 0):g}, {max(hi, 0):g}]")
    if max(-lo, hi) > key.limit:
        raise ctx.fail(f"bounds [{lo:g}, {hi:g}] reach beyond the limit of {key.limit:g}{unit}", field, line,
                       _limit_fix(key))
    return (lo, hi)


def _limit_fix(key: Range) -> str:
    if key.name.startswith(("lidar_", "drift_", "yaw_drift_")):
        return f"{key.target.name} itself is at most {key.target.span[1]:g}{' ' + key.unit if key.unit else ''}: " \
               f"search within [-{key.limit:g}, {key.limit:g}]"
    return f"search within ±{key.limit:g} of the seed (the documented limit)"


def _read_sizes(ctx: Ctx, sec: SectionReader, key: SizeRange) -> tuple[float, float]:
    node = sec.get(key.name)
    if node is None:
        return key.default
    field, line = join(sec.path, key.name), sec.line_of(key.name)
    if isinstance(node, YSeq):
        lo, hi = _pair(ctx, node, field, line, f"{key.name}: [0.3, 1.0]")
    else:
        lo = hi = number(ctx, node, field, line)
    if not 0 < lo <= hi:
        raise ctx.fail(f"sizes must satisfy 0 < lo <= hi, got [{lo:g}, {hi:g}]", field, line,
                       f"write e.g. {key.name}: [0.3, 1.0] (side length of an inserted box, m)")
    if hi > key.le:
        raise ctx.fail(f"{hi:g} m is more than the limit of {key.le:g} m", field, line,
                       f"write sizes up to {key.le:g}")
    return (lo, hi)


def _read_frozen(ctx: Ctx, sec: SectionReader, obstacles: tuple[str, ...], waypoints: int,
                 terrain: tuple[str, ...] = ()) -> frozenset:
    node = sec.get("frozen")
    if node is None or (isinstance(node, YScalar) and node.value is None):
        return frozenset()
    field, line = join(sec.path, "frozen"), sec.line_of("frozen")
    items = node.items if isinstance(node, YSeq) else [node] if isinstance(node, YScalar) and \
        isinstance(node.value, str) else None
    if items is None:
        raise ctx.fail(f"must be a list of part names, got {describe(node)}", field, line,
                       "write e.g. frozen: [wall_left, start]")
    limit = SEARCH["frozen"].max
    if len(items) > limit:
        raise ctx.fail(f"{len(items)} names is more than the limit of {limit}", field, line,
                       "name each part once")
    parts = list(obstacles) + ["start", "goal", "waypoints", "robot"] + [f"waypoints[{i}]" for i in range(waypoints)] \
        + list(terrain)
    known = set(parts)
    names = []
    for i, item in enumerate(items):
        name = item.value if isinstance(item, YScalar) else None
        if not isinstance(name, str) or name not in known:
            shown = repr(name) if isinstance(item, YScalar) else describe(item)
            close = difflib.get_close_matches(str(name), parts, n=1) if isinstance(name, str) else []
            hint = f"did you mean {close[0]!r}?" if close else f"parts of this seed: {', '.join(parts[:20])}" + \
                (" ..." if len(parts) > 20 else "")
            raise ctx.fail(f"{shown} is not an obstacle, terrain element or mission part of this seed", f"{field}[{i}]",
                           item.line or line, hint)
        names.append(name)
    return frozenset(names)

