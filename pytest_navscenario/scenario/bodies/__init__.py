"""Scenario/bodies: how the robot meets the ground (``robot.body``), one module per kind of body.

Read first: ``record.py`` (``BodyKind``, the record each kind gives: its declaration and YAML keys,
the drives it allows, whether it rides the ground, what it can cross, the slope it climbs, the
loader's checks; and ``Capability``), then one module per kind: ``planar.py`` (the default),
``wheeled.py`` (with ``chassis.py``, its layout and stability), ``legged.py``, ``mjcf.py``.

``BODY_MODULES`` below is the registry: adding a kind of body is one module giving a ``BodyKind``
(its ``KIND``) and one line here (and its MuJoCo model: one module and one line in ``sim/bodies/``); see
docs/contributing.md. Everything else (the YAML variant, the JSON Schema, the drive check, the
crossing estimates, the safety layer's slope) reads the records.
"""
from __future__ import annotations

import importlib
from typing import Any, Union

from ..keys import Element, Variant
from .legged import LeggedBody
from .mjcf import MjcfBody
from .planar import PlanarBody
from .record import BodyKind, Capability
from .wheeled import WheeledBody

# The registry: the modules of this package that each give a body kind (their ``KIND``), in the
# order the YAML variant, the JSON Schema and the reference list them. Adding a kind: one line.
BODY_MODULES = (
    "planar",
    "wheeled",
    "legged",
    "mjcf",
)
BODY_KINDS: tuple[BodyKind, ...] = tuple(importlib.import_module(f".{m}", __name__).KIND for m in BODY_MODULES)

_BY_NAME = {kind.name: kind for kind in BODY_KINDS}
BODY_TYPES = tuple(_BY_NAME)
BODY_DRIVES = {kind.name: kind.drives for kind in BODY_KINDS}
Body = Union[tuple(kind.declaration for kind in BODY_KINDS)]  # type: ignore[valid-type]

BODY = Variant("body", "", f"how the robot meets the ground: planar (the default), "
               f"{', '.join(BODY_TYPES[1:-1])} or {BODY_TYPES[-1]}",
               types=tuple(Element(kind.name, kind.keys, kind.name, kind.keys.doc) for kind in BODY_KINDS))

__all__ = ["BODY", "BODY_DRIVES", "BODY_KINDS", "BODY_TYPES", "Body", "BodyKind", "Capability", "LeggedBody",
           "MjcfBody", "PlanarBody", "WheeledBody", "body_capability", "body_kind", "body_problem",
           "climb_limit"]


def body_kind(body: Any) -> BodyKind:
    """The record of a body (a declaration, or a kind's name)."""
    return _BY_NAME[body if isinstance(body, str) else body.kind]


def body_capability(scenario: Any) -> Capability | None:
    """What the scenario's body can cross (None: it declares nothing, and the path search and the
    feasibility check ignore the terrain for it)."""
    return body_kind(scenario.robot.body).capability(scenario.robot.body, scenario.robot.footprint)


def climb_limit(body: Any) -> float:
    """The steepest slope (degrees) the safety layer lets the body meet: the slope it climbs, never
    more than its tip angle (the tip angle alone when it is unknown)."""
    tip = float(getattr(body, "tip_angle", 45.0))
    slope = body_kind(body).climbs(body)
    return tip if slope is None else min(float(slope), tip)


def body_problem(scenario: Any) -> tuple[str, str, str] | None:
    """(field, message, fix) when the robot's body and drive, or its body and the terrain, do not
    go together, or the body cannot be built or stand; None when they do."""
    kind, drive = body_kind(scenario.robot.body), scenario.robot.drive
    if drive not in kind.drives:
        return ("robot.drive", f"a {kind.name} body cannot drive '{drive}': it cannot move sideways",
                f"set robot.drive: {kind.drives[0]}")
    if not kind.rides_ground and scenario.terrain:
        riding = [k.name for k in BODY_KINDS if k.rides_ground]
        return ("robot.body", f"the {kind.name} body (the default) slides on a flat floor and cannot ride terrain",
                f"give the robot a body that meets the ground: robot.body: {{type: {riding[0]}}} "
                f"(or {', '.join(riding[1:-1])}, or {riding[-1]} with your own robot)")
    return kind.problem(scenario)
