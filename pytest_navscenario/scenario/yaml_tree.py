"""YAML text -> a small node tree that remembers the line of every value.

Why not ``yaml.safe_load``: it forgets lines, expands alias bombs ("billion laughs") into
gigabytes, and libyaml's composer recurses in C, so a deeply nested file crashes the process
(segfault) instead of raising. Here the events of the (C or pure-Python) parser are composed
*iteratively* into ``YMap``/``YSeq``/``YScalar`` nodes with

* a nesting limit (``max_depth``),
* the expanded size of each node (aliases counted as often as they are used) checked against
  ``max_nodes`` as the tree is built, so an alias bomb is refused before anything expands,
* anchors registered when their node is complete (an alias to its own parent is an error),
* duplicate keys refused, ``<<`` merge keys applied (explicit keys win), and
* scalars resolved and constructed exactly as ``yaml.safe_load`` does (YAML 1.1 types).

Every problem raises ``ScenarioError`` with the file and line; nothing else escapes.
``from_plain`` builds the same tree from Python values (no lines) so one validator serves both.
"""
from __future__ import annotations

import math
import re
from typing import Any, Mapping

import yaml
from yaml.constructor import SafeConstructor
from yaml.nodes import ScalarNode

from ..core.errors import ScenarioError

try:  # libyaml's parser is ~15x faster; only its parser is used (never its recursive composer)
    _Loader: type = yaml.CSafeLoader
except AttributeError:  # pragma: no cover - PyYAML without libyaml
    _Loader = yaml.SafeLoader

_MAP_TAGS = (None, "!", "tag:yaml.org,2002:map")
_SEQ_TAGS = (None, "!", "tag:yaml.org,2002:seq")
_MERGE_TAG = "tag:yaml.org,2002:merge"
_STR_TAG = "tag:yaml.org,2002:str"


class YNode:
    """Base of the tree nodes: ``line`` is 1-based (None for values not read from a file)."""
    __slots__ = ("line", "size")
    line: int | None
    size: int


class YScalar(YNode):
    """A scalar: its safe_load value, and whether it was written plain (unquoted, untagged)."""
    __slots__ = ("value", "plain")

    def __init__(self, value: Any, line: int | None, plain: bool = False):
        self.value, self.line, self.plain, self.size = value, line, plain, 1


class YSeq(YNode):
    __slots__ = ("items",)

    def __init__(self, line: int | None):
        self.items: list[YNode] = []
        self.line, self.size = line, 1


class YMap(YNode):
    """A mapping: ``items`` maps each key to (key line, value node), in file order."""
    __slots__ = ("items", "merges")

    def __init__(self, line: int | None):
        self.items: dict[Any, tuple[int | None, YNode]] = {}
        self.merges: list[YNode] = []
        self.line, self.size = line, 1


def describe(node: YNode) -> str:
    """A short human description of a node's value for 'expected X, got Y' messages."""
    if isinstance(node, YMap):
        return "a mapping"
    if isinstance(node, YSeq):
        return "a list"
    value = node.value
    if value is None:
        return "null (an empty value)"
    if isinstance(value, bool):
        return f"{str(value).lower()} (a boolean)"
    if isinstance(value, str):
        shown = value if len(value) <= 40 else value[:37] + "..."
        return f"{shown!r} (a string)"
    if isinstance(value, (int, float)):
        return repr(value) if not isinstance(value, float) or math.isfinite(value) else (
            ".nan" if math.isnan(value) else (".inf" if value > 0 else "-.inf"))
    return f"a {type(value).__name__} value"


def parse_yaml(text: str, source: str | None, *, max_depth: int, max_nodes: int,
               list_limits: Mapping[str, tuple[int, str]] | None = None) -> YNode | None:
    """Compose ``text`` (one YAML document) into a tree; None for an empty document.

    ``list_limits`` maps a top-level key to (maximum items, what they are): a longer list there is
    refused as soon as it passes the limit, without composing the rest of a huge file.
    """
    try:
        loader = _Loader(text)
    except UnicodeError as exc:  # lone surrogates in a str cannot be encoded for the parser
        raise ScenarioError(f"the text is not valid Unicode ({exc.reason})", path=source,
                            line=text.count("\n", 0, getattr(exc, "start", 0)) + 1,
                            hint="save the scenario as UTF-8 text") from None
    try:
        return _Composer(loader, source, max_depth, max_nodes, list_limits or {}).compose()
    except UnicodeError as exc:
        raise ScenarioError(f"the text is not valid Unicode ({exc.reason})", path=source,
                            hint="save the scenario as UTF-8 text") from None
    except yaml.YAMLError as exc:
        if "nesting depth" in str(exc):  # PyYAML >= 6.0.3 has a flow-depth limit of its own
            mark = getattr(exc, "problem_mark", None)
            raise ScenarioError(f"the YAML nests more than {max_depth} levels deep", path=source,
                                line=None if mark is None else mark.line + 1,
                                hint=f"a scenario needs only a few levels (under {max_depth}); this file "
                                     f"is not a scenario") from None   # as the composer's own limit says
        raise _yaml_error(exc, source, text) from None
    except RecursionError:  # pragma: no cover - the composer is iterative; belt and braces
        raise ScenarioError("the YAML nests too deeply", path=source,
                            hint=f"keep nesting under {max_depth} levels") from None
    finally:
        dispose = getattr(loader, "dispose", None)
        if dispose is not None:
            dispose()


def _yaml_error(exc: yaml.YAMLError, source: str | None, text: str) -> ScenarioError:
    if isinstance(exc, yaml.reader.ReaderError):  # a control character or bad byte
        position = max(0, min(int(exc.position), len(text)))
        char = exc.character if isinstance(exc.character, int) else ord(str(exc.character)[:1] or "?")
        return ScenarioError(f"character #x{char:04x} is not allowed in YAML ({exc.reason})", path=source,
                             line=text.count("\n", 0, position) + 1,
                             hint="is this a binary file? a scenario is UTF-8 text without control characters")
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    context = getattr(exc, "context", None)
    message = f"invalid YAML: {problem}" + (f" ({context})" if context else "")
    line = None
    if mark is not None:
        line = mark.line + 1
        message += f" at column {mark.column + 1}"
    hint = "check indentation, colons and quotes on that line (or the one before)"
    lines = text.splitlines()
    if mark is not None and mark.line < len(lines) and "\t" in lines[mark.line][:mark.column + 1]:
        hint = "YAML does not allow tabs for indentation; indent with spaces"
    return ScenarioError(message, path=source, line=line, hint=hint)


class _Composer:
    """Iterative event -> node composer with depth, size, anchor and duplicate-key checks."""

    def __init__(self, loader: Any, source: str | None, max_depth: int, max_nodes: int,
                 list_limits: Mapping[str, tuple[int, str]]):
        self.loader, self.source = loader, source
        self.list_limits = list_limits
        self.max_depth, self.max_nodes = max_depth, max_nodes
        self.anchors: dict[str, YNode] = {}
        # stack entries: [node, anchor, pending key (value, line) or None, list limit or None]
        self.stack: list[list[Any]] = []

    def error(self, message: str, line: int | None, hint: str | None = None) -> ScenarioError:
        return ScenarioError(message, path=self.source, line=line, hint=hint)

    def compose(self) -> YNode | None:
        self.root: YNode | None = None
        documents = 0
        get_event = self.loader.get_event
        scalar_event, alias_event = yaml.ScalarEvent, yaml.AliasEvent
        map_start, seq_start = yaml.MappingStartEvent, yaml.SequenceStartEvent
        map_end, seq_end = yaml.MappingEndEvent, yaml.SequenceEndEvent
        stack, max_nodes = self.stack, self.max_nodes
        while True:
            event = get_event()
            kind = type(event)
            if kind is yaml.StreamEndEvent or event is None:
                break
            line = event.start_mark.line + 1 if event.start_mark is not None else None
            if kind is scalar_event:
                if event.anchor is None and stack and type(stack[-1][0]) is YMap:
                    # most events: a plain key or value in a mapping (attach(), inlined)
                    top = stack[-1]
                    node = self.scalar(event, line)
                    pending = top[2]
                    if pending is None:
                        top[2] = (node.value, line)
                        parent = top[0]
                        parent.size += 1
                        if parent.size > max_nodes:
                            raise self.too_many(line)
                        continue
                    if pending[0] is not _MERGE:
                        parent = top[0]
                        items = parent.items
                        try:
                            fresh = pending[0] not in items
                        except TypeError:      # an unhashable key: attach() says so
                            fresh = False
                        if fresh:
                            parent.size += 1
                            if parent.size > max_nodes:
                                raise self.too_many(line)
                            top[2] = None
                            items[pending[0]] = (pending[1], node)
                            continue
                    self.attach(node, None, line)
                    continue
                self.attach(self.scalar(event, line), event.anchor, line)
            elif kind is map_start or kind is seq_start:
                is_map = kind is map_start
                if event.tag not in (_MAP_TAGS if is_map else _SEQ_TAGS):
                    raise self.error(f"unsupported YAML tag {event.tag!r}", line,
                                     "scenario files use plain mappings and lists; remove the tag")
                if len(self.stack) >= self.max_depth:
                    raise self.error(f"the YAML nests more than {self.max_depth} levels deep", line,
                                     "a scenario needs only a few levels; this file is not a scenario")
                self.stack.append([YMap(line) if is_map else YSeq(line), event.anchor, None, None])
                if not is_map and len(self.stack) == 2 and self.stack[0][2] is not None:
                    key, key_line = self.stack[0][2]
                    if isinstance(key, str) and key in self.list_limits:
                        self.stack[-1][3] = (key, key_line, *self.list_limits[key])
            elif kind is map_end or kind is seq_end:
                node, anchor, _, _ = self.stack.pop()
                if isinstance(node, YMap) and node.merges:
                    self.merge(node)
                self.attach(node, anchor, line)
            elif kind is alias_event:
                target = self.anchors.get(event.anchor)
                if target is None:
                    raise self.error(f"alias *{event.anchor} has no finished anchor &{event.anchor} before it",
                                     line, "define the anchor first; an alias cannot refer to its own parent")
                self.attach(target, None, line)
            elif kind is yaml.DocumentStartEvent:
                documents += 1
                if documents > 1:
                    raise self.error("the file holds more than one YAML document", line,
                                     "a scenario file holds exactly one document; remove the extra '---'")
        return self.root

    def scalar(self, event: Any, line: int) -> YScalar:
        tag = event.tag
        if tag is None or tag == "!":  # implicit: resolve as safe_load does (cached: keys repeat a lot)
            value, style = event.value, event.style
            if tag is None and not style and len(value) < 40:   # long digit strings: the resolver's errors
                match = _DECIMAL(value)
                if match is not None:
                    return YScalar(float(value) if match.group(1) is not None else int(value), line, False)
            key = (value, event.implicit, not style)
            cached = _SCALARS.get(key)
            if cached is None:
                tag = self.loader.resolve(ScalarNode, value, event.implicit)
                if tag == _MERGE_TAG:
                    cached = (_MERGE, False)
                else:
                    cached = (self.construct(tag, event, line), not style and tag == _STR_TAG)
                if len(value) <= 200 and len(_SCALARS) < 10_000 and type(cached[0]) in _IMMUTABLE:
                    _SCALARS[key] = cached    # short texts only: the cache lives as long as the process
            return YScalar(cached[0], line, cached[1])
        return YScalar(self.construct(tag, event, line), line, False)

    def construct(self, tag: str, event: Any, line: int) -> Any:
        if tag == _STR_TAG:
            return event.value
        construct = SafeConstructor.yaml_constructors.get(tag)
        if construct is None:
            raise self.error(f"unsupported YAML tag {tag!r}", line,
                             "scenario files hold plain values; remove the tag")
        node = ScalarNode(tag, event.value, event.start_mark, event.end_mark, style=event.style)
        try:
            value = construct(self.loader, node)
        except Exception as exc:  # bad !!int/!!binary/!!timestamp text, digit-count limits, ...
            raise self.error(f"cannot read value {event.value[:40]!r} as {tag.rsplit(':', 1)[-1]}: {exc}",
                             line, "write a plain number or string") from None
        return value

    def too_many(self, line: int | None) -> ScenarioError:
        return self.error(f"the YAML expands to more than {self.max_nodes} values (an alias counts "
                          f"as often as it is used: a YAML alias bomb?)", line,
                          "scenario files need far fewer values; do not build aliases of aliases")

    def attach(self, node: YNode, anchor: str | None, line: int) -> None:
        if anchor is not None:
            self.anchors[anchor] = node
        if not self.stack:
            self.root = node
            return
        top = self.stack[-1]
        parent = top[0]
        parent.size += node.size
        if parent.size > self.max_nodes:
            raise self.too_many(line)
        if isinstance(parent, YSeq):
            parent.items.append(node)
            if top[3] is not None and len(parent.items) > top[3][2]:
                key, key_line, limit, what = top[3]
                raise ScenarioError(f"more than {limit} {what}, the limit", path=self.source, line=key_line,
                                    field=key, hint="split the scenario, or thin it out (see SCENARIO_LIMITS)")
            return
        if top[2] is None:  # a key
            if not isinstance(node, YScalar):
                raise self.error("a mapping key must be a plain value, not a list or mapping", line,
                                 "write 'key: value' with a plain key")
            top[2] = (node.value, line)
            return
        key, key_line = top[2]
        top[2] = None
        if key is _MERGE:
            parent.merges.append(node)
            return
        try:
            previous = parent.items.get(key)
        except TypeError:  # unhashable key value (e.g. !!binary is hashable; be safe anyway)
            raise self.error(f"unusable mapping key {key!r}", key_line) from None
        if previous is not None:
            raise self.error(f"key {key!r} is given twice (first on line {previous[0]})", key_line,
                             "remove one of them")
        parent.items[key] = (key_line, node)

    def merge(self, node: YMap) -> None:
        """Apply ``<<: *anchor`` (or a list of them): explicit keys win, then earlier merges."""
        sources: list[YNode] = []
        for merged in node.merges:
            sources.extend(merged.items if isinstance(merged, YSeq) else [merged])
        for source in sources:
            if not isinstance(source, YMap):
                raise self.error("'<<' (merge) needs a mapping or a list of mappings", node.line,
                                 "write '<<: *anchor' where &anchor names a mapping")
            for key, item in source.items.items():
                if key not in node.items:
                    node.items[key] = item
        node.merges = []


# Resolved plain scalars shared by every file (keys and words repeat across a suite): only values
# that cannot be changed in place, so a cached value is never shared mutably between scenarios.
_SCALARS: dict[Any, tuple[Any, bool]] = {}
_IMMUTABLE = frozenset({str, int, float, bool, type(None), bytes})
# Plain decimals written the ordinary way: YAML 1.1 resolves these to float / int, and
# SafeConstructor gives exactly float(text) / int(text); anything else (1_000, 0x1f, 017, 1:30,
# .inf, 1e3, ...) goes through the resolver. About half the values of a scenario are such numbers.
# The match: group 1 set for a float.
_DECIMAL = re.compile(r"[-+]?(?:([0-9]+\.[0-9]*)|0|[1-9][0-9]*)\Z").match


class _MergeKey:
    def __repr__(self) -> str:
        return "'<<'"


_MERGE = _MergeKey()


def from_plain(value: Any, *, max_depth: int, max_nodes: int, source: str | None = None) -> YNode:
    """The tree of a Python value (from ``scenario_from_dict``): no lines, same limits."""
    budget = [max_nodes]

    def build(obj: Any, depth: int) -> YNode:
        budget[0] -= 1
        if budget[0] < 0:
            raise ScenarioError(f"the mapping holds more than {max_nodes} values", path=source,
                                hint="scenarios need far fewer values")
        if depth > max_depth:
            raise ScenarioError(f"the mapping nests more than {max_depth} levels deep", path=source,
                                hint="a scenario needs only a few levels")
        if isinstance(obj, Mapping):
            node = YMap(None)
            for key, item in obj.items():
                node.items[key] = (None, build(item, depth + 1))
            return node
        if isinstance(obj, (list, tuple)):
            seq = YSeq(None)
            seq.items = [build(item, depth + 1) for item in obj]
            return seq
        return YScalar(obj, None)

    return build(value, 0)


def to_plain(node: YNode) -> Any:
    """The plain Python value of a node (dicts, lists, scalars) as safe_load would give it.

    The tree's sizes were checked while composing, so this expansion is bounded.
    """
    if isinstance(node, YScalar):
        return node.value
    if isinstance(node, YSeq):
        return [to_plain(item) for item in node.items]
    return {key: to_plain(item) for key, (_, item) in node.items.items()}


_FIELD_PART = re.compile(r"\[(\d+)\]|([^.\[\]]+)")


def field_line(text: str, field: str, *, max_depth: int = 64, max_nodes: int = 500_000) -> int | None:
    """The 1-based line of a dotted ``field`` (``mission.timeout``, ``obstacles[3].motion.path``) in
    YAML ``text``: the line of its own key, else of the nearest enclosing key written in the text (a
    value left at its default is reported at its section's key); None when the text does not parse.
    For errors found after loading (the feasibility check) that name a field."""
    try:
        node = parse_yaml(text, None, max_depth=max_depth, max_nodes=max_nodes)
    except ScenarioError:
        return None
    line = None
    for index, key in _FIELD_PART.findall(field):
        if index:
            if not isinstance(node, YSeq) or int(index) >= len(node.items):
                break
            node = node.items[int(index)]
            line = node.line or line
        else:
            if not isinstance(node, YMap) or key not in node.items:
                break
            key_line, node = node.items[key]
            line = key_line or node.line or line
    return line
