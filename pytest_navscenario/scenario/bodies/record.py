"""The record every body kind gives (``BodyKind``) and what a body can cross (``Capability``).

A body kind is one module of this package holding its declaration (the frozen dataclass of
``robot.body`` and its YAML keys), the drives it allows, whether it rides the ground, what it can
cross (for the path search and the feasibility check), the steepest slope it climbs (for the safety
layer) and the loader's extra checks; ``bodies/__init__.py`` lists the kinds (the registry).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from ..keys import Number


@dataclass(frozen=True)
class Capability:
    """What a body can cross: steps up and down of ``max_step`` metres, slopes of ``max_slope``
    degrees, gaps of ``max_gap`` metres (0: none)."""
    max_step: float
    max_slope: float
    max_gap: float


def _none(*args: Any) -> None:
    return None


@dataclass(frozen=True)
class BodyKind:
    """One kind of body, as the scenario layer knows it.

    ``capability(body, footprint)``: what it can cross (None: undeclared, the path search and the
    feasibility check ignore the terrain for it). ``climbs(body)``: the steepest slope in degrees it
    can physically drive up (None: unknown; the safety layer then uses its tip angle).
    ``problem(scenario)``: (field, message, fix) when the scenario's body cannot be built or stand,
    checked by the loader and the simulation alike."""
    name: str
    declaration: type
    keys: Any                       # its YAML keys: a keys.section of the declaration
    drives: tuple[str, ...]         # the robot.drive values it allows; the first is the suggested one
    rides_ground: bool = True       # False: the planar body (a flat floor, no terrain)
    capability: Callable[[Any, Any], Capability | None] = _none
    climbs: Callable[[Any], float | None] = _none
    problem: Callable[[Any], tuple[str, str, str] | None] = _none


TIP = Number("tip_angle", "deg", "roll or pitch that counts as tipped over", gt=0, le=90.0)
