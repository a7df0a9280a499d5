"""Reading ``signals:`` and ``requirements:`` (``requirements.py``): each formula is parsed when the
file loads, so a mistake is an error at its line (and the column inside the formula) with a fix,
and a formula naming a signal the scenario does not have lists the ones it has.

Also the shared requirements file (``--nav-requirements``): a YAML file with only these two
sections, merged into each scenario of a run by ``with_shared`` (the scenario's own requirement of
the same name wins)."""
from __future__ import annotations

import dataclasses
import fnmatch
import os
import re
from typing import Any, Iterable, Sequence

from ..core.errors import ScenarioError
from .reading import Ctx, SectionReader, did_you_mean, read_section
from .requirements import (BUILTIN_SIGNALS, REGION, REQUIREMENT, REQUIREMENTS, SIGNAL, SIGNAL_KINDS, SIGNALS,
                           Region, Requirement, Signal, waypoint_signals)
from .yaml_tree import YScalar, YSeq, describe

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def read_signals(ctx: Ctx, top: SectionReader) -> tuple[Signal, ...]:
    out: list[Signal] = []
    seen: dict[str, int] = {}
    for i, item in enumerate(top.sequence("signals", SIGNALS.max, SIGNALS.what)):
        path = f"signals[{i}]"
        sec = SectionReader(ctx, item, path, SIGNAL.names, line=item.line or top.line_of("signals"),
                            what="a signal mapping such as {name: d_walker, distance_to: walker}")
        values: dict[str, Any] = {"distance_to": _names(ctx, sec, "distance_to")}
        inside = sec.section("inside", REGION.names, REGION.what)
        values["inside"] = _region(ctx, inside) if inside is not None else None
        values = read_section(ctx, sec, SIGNAL, values)
        signal = Signal(**values)
        name, line = signal.name, sec.line_of("name")
        if not _IDENT.match(name):
            raise ctx.fail(f"{name!r} cannot be named in a formula", f"{path}.name", line,
                           "use letters, digits and '_', starting with a letter (d_walker)")
        from ..stl import RESERVED_WORDS
        if name in RESERVED_WORDS:
            raise ctx.fail(f"{name!r} is a word of the formula language, not a signal name", f"{path}.name", line,
                           f"rename it, e.g. {name.lower()}_signal (reserved: always, eventually, G, F, X, ...)")
        if name in BUILTIN_SIGNALS or name.startswith("d_waypoint"):
            raise ctx.fail(f"{name!r} is a built-in signal's name", f"{path}.name", line,
                           f"choose another name; the built-in {name!r} needs no declaration")
        if name in seen:
            raise ctx.fail(f"signal {name!r} is declared twice (first at signals[{seen[name]}])", f"{path}.name",
                           line, "rename one of them")
        seen[name] = i
        given = [k for k in SIGNAL_KINDS if sec.has(k)]
        if len(given) != 1:
            raise ctx.fail(f"signal {name!r} has {'none' if not given else ' and '.join(given)} of "
                           f"{', '.join(SIGNAL_KINDS)}", path, sec.line,
                           "give exactly one of them, e.g. 'distance_to: walker'")
        ctx.lines[path] = sec.line
        out.append(signal)
    return tuple(out)


def _names(ctx: Ctx, sec: SectionReader, key: str) -> tuple[str, ...]:
    node = sec.get(key)
    if node is None or (isinstance(node, YScalar) and node.value is None):
        return ()
    items = node.items if isinstance(node, YSeq) else [node]
    names = []
    for item in items:
        if not isinstance(item, YScalar) or not isinstance(item.value, str) or not item.value:
            raise ctx.fail(f"expected an obstacle name, got {describe(item)}", f"{sec.path}.{key}",
                           sec.line_of(key), "write a name or a list of names, such as [walker, person*]")
        names.append(item.value)
    return tuple(names)


def _region(ctx: Ctx, sec: SectionReader) -> Region:
    values = read_section(ctx, sec, REGION)
    if (values["radius"] is None) == (not values["points"]):
        raise ctx.fail("a region is a circle (x, y, radius) or a polygon (points), not both or neither",
                       sec.path, sec.line, "write {x: 8, y: 0, radius: 1} or {points: [[0, 0], [2, 0], [2, 2]]}")
    values["points"] = tuple(tuple(p) for p in values["points"])
    return Region(**values)


def read_requirements(ctx: Ctx, top: SectionReader, known: Iterable[str] | None,
                      source: str = "", period: float | None = None) -> tuple[Requirement, ...]:
    """The requirements, each formula parsed and its signals checked against ``known`` (None: not
    checked here), its intervals against the control ``period`` (s; None: not checked here)."""
    from ..stl import StlSyntaxError, parse

    check = known is not None
    known = tuple(sorted(set(known or ())))
    out: list[Requirement] = []
    seen: dict[str, int] = {}
    for i, item in enumerate(top.sequence("requirements", REQUIREMENTS.max, REQUIREMENTS.what)):
        path = f"requirements[{i}]"
        sec = SectionReader(ctx, item, path, REQUIREMENT.names, line=item.line or top.line_of("requirements"),
                            what='a requirement mapping such as {name: keep-clear, spec: "always (clearance >= 0.3)"}')
        values = read_section(ctx, sec, REQUIREMENT)
        name, spec, line = values["name"], values["spec"], sec.line_of("spec")
        if name in seen:
            raise ctx.fail(f"requirement {name!r} is written twice (first at requirements[{seen[name]}])",
                           f"{path}.name", sec.line_of("name"), "rename one of them")
        seen[name] = i
        try:
            formula = parse(spec)
        except StlSyntaxError as exc:
            column = getattr(exc, "column", None)
            where = f" at column {column}" if column else ""
            message = getattr(exc, "message", str(exc))
            raise ctx.fail(f"the formula {spec!r} is not STL{where}: {message}", f"{path}.spec", line,
                           getattr(exc, "hint", "") or "see the operators page (reference/stl.md)") from None
        unknown = sorted(set(formula.signals) - set(known)) if check else ()
        if unknown:
            hint = did_you_mean(unknown[0], known) if len(known) else ""
            raise ctx.fail(f"the formula names {', '.join(map(repr, unknown))}, which is no signal of this "
                           f"scenario (known: {', '.join(known)})", f"{path}.spec", line,
                           f"{hint + '; ' if hint.startswith('did') else ''}declare it under 'signals:' "
                           f"(e.g. {{name: {unknown[0]}, distance_to: <obstacle>}}) or use a known one")
        if period is not None:
            _check_period(ctx, formula, period, f"{path}.spec", line)
        out.append(Requirement(name=name, spec=spec, scale=values["scale"], source=source))
    return tuple(out)


def _check_period(ctx: Ctx, formula: Any, period: float, field: str, line: int | None) -> None:
    """Every interval bound is a whole number of control periods (signals are sampled per tick)."""
    from ..stl import StlError
    try:
        formula.check_period(period)
    except StlError as exc:
        raise ctx.fail(f"{getattr(exc, 'message', exc)}", field, line,
                       getattr(exc, "hint", "") or f"write interval bounds as multiples of the control "
                                                  f"period {period:g} s (1 / simulation.control_rate)") from None


def known_signals(waypoints: int, signals: Sequence[Signal]) -> tuple[str, ...]:
    return (*BUILTIN_SIGNALS, *waypoint_signals(waypoints), *(s.name for s in signals))


def check_obstacle_names(ctx: Ctx, signals: Sequence[Signal], obstacles: Sequence[str]) -> None:
    """Each obstacle name or pattern a signal gives matches an obstacle of the scenario."""
    for i, signal in enumerate(signals):
        patterns = signal.distance_to or ((signal.speed_toward,) if signal.speed_toward else ())
        for pattern in patterns:
            if not fnmatch.filter(obstacles, pattern):
                key = "distance_to" if signal.distance_to else "speed_toward"
                field = f"signals[{i}].{key}"
                raise ctx.fail(f"{pattern!r} names no obstacle of this scenario", field,
                               ctx.lines.get(f"signals[{i}]"),
                               did_you_mean(pattern, tuple(obstacles)) if obstacles else "add the obstacle")


# --------------------------------------------------------------------------- the shared file

@dataclasses.dataclass(frozen=True)
class SharedRequirements:
    """A shared requirements file: its signals and requirements (formulas parsed, signals not yet
    checked against a scenario: ``with_shared`` does)."""
    path: str
    signals: tuple[Signal, ...]
    requirements: tuple[Requirement, ...]


def load_shared(path: str | os.PathLike) -> SharedRequirements:
    """Read a shared requirements file: ``signals:`` and ``requirements:`` only."""
    from .yaml_tree import parse_yaml

    src = os.fspath(path)
    try:
        with open(src, encoding="utf-8") as fh:
            text = fh.read()
    except OSError as exc:
        raise ScenarioError(f"cannot read the requirements file: {exc.strerror}", path=src,
                            hint="check --nav-requirements / nav_requirements") from None
    ctx = Ctx(src)
    root = parse_yaml(text, src, max_depth=64, max_nodes=100_000)
    top = SectionReader(ctx, root, "", ("signals", "requirements"), line=1,
                        what="a mapping with 'signals:' and 'requirements:'")
    signals = read_signals(ctx, top)
    # every signal name is allowed here: with_shared checks them against each scenario
    requirements = read_requirements(ctx, top, None, source=src)
    return SharedRequirements(src, signals, requirements)


def with_shared(scenario: Any, shared: SharedRequirements | None) -> Any:
    """The scenario with the shared file's signals and requirements added (its own of the same
    name win); a shared formula naming a signal the scenario lacks is an error naming both."""
    if shared is None or not (shared.signals or shared.requirements):
        return scenario
    from ..stl import StlError, parse

    own_signals = {s.name for s in scenario.signals}
    signals = scenario.signals + tuple(s for s in shared.signals if s.name not in own_signals)
    own = {r.name for r in scenario.requirements}
    added = tuple(r for r in shared.requirements if r.name not in own)
    known = set(known_signals(len(scenario.mission.waypoints), signals))
    period = 1.0 / scenario.simulation.control_rate
    for r in added:
        formula = parse(r.spec)
        try:
            formula.check_period(period)
        except StlError as exc:
            raise ScenarioError(f"requirement {r.name!r}, in scenario {scenario.name!r}: {getattr(exc, 'message', exc)}",
                                path=shared.path, field="requirements",
                                hint=f"write interval bounds as multiples of {period:g} s (its control period)") from None
        unknown = sorted(set(formula.signals) - known)
        if unknown:
            raise ScenarioError(f"requirement {r.name!r} names {', '.join(map(repr, unknown))}, which scenario "
                                f"{scenario.name!r} ({scenario.source or 'no file'}) does not have "
                                f"(known: {', '.join(sorted(known))})", path=shared.path, field="requirements",
                                hint="declare the signal in the shared file or in the scenario")
    return dataclasses.replace(scenario, signals=signals, requirements=scenario.requirements + added)
