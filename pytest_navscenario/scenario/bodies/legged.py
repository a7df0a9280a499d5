"""The legged body: a walking robot declared by what it can cross (sim/bodies/legged.py moves it)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

from ..keys import Number, section
from .record import TIP, BodyKind, Capability


@dataclass(frozen=True)
class LeggedBody:
    """A walking robot (an ANYmal) declared by what it can do, not how it walks: it climbs steps up
    to ``max_step`` metres, slopes up to ``max_slope`` degrees, crosses gaps up to ``max_gap``
    metres and carries its body ``clearance`` metres above the ground. A capability model: the body
    follows the ground it can cross and is stopped (or falls) where it cannot; no legs, feet or gait
    are simulated."""
    max_step: float = 0.2                # m
    max_slope: float = 30.0              # degrees
    max_gap: float = 0.3                 # m
    clearance: float = 0.35              # m, body underside above the ground
    tip_angle: float = 45.0              # degrees of roll or pitch that count as tipped over
    kind: Literal["legged"] = field(default="legged", init=False)


LEGGED_BODY = section(LeggedBody, "robot.body (legged)", "a walking robot declared by what it can cross", [
    Number("max_step", "m", "the highest step it climbs", ge=0),
    Number("max_slope", "deg", "the steepest slope it walks", ge=0, le=90.0),
    Number("max_gap", "m", "the widest gap it crosses", ge=0),
    Number("clearance", "m", "its body's underside above the ground", ge=0),
    TIP])


def capability(body: LeggedBody, footprint: Any) -> Capability:
    """Its declared limits."""
    return Capability(float(body.max_step), float(body.max_slope), float(body.max_gap))


KIND = BodyKind("legged", LeggedBody, LEGGED_BODY, drives=("omni", "diff"), capability=capability,
                climbs=lambda body: float(body.max_slope))
