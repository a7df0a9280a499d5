"""The planar body (the default): a rigid box or disc on planar joints with gravity off."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from ..keys import section
from .record import BodyKind


@dataclass(frozen=True)
class PlanarBody:
    """Today's body: a rigid box or disc (the footprint) on planar joints with gravity off. It
    never leaves z = 0; it cannot climb, fall or tip."""
    kind: Literal["planar"] = field(default="planar", init=False)


PLANAR_BODY = section(PlanarBody, "robot.body (planar)", "today's body: planar joints, gravity off", [])

KIND = BodyKind("planar", PlanarBody, PLANAR_BODY, drives=("omni", "diff"), rides_ground=False)
