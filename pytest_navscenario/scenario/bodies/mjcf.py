"""The user's own MJCF robot and controller (sim/bodies/mjcf.py builds and drives it)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

from ..keys import Number, Rule, Text, section
from .record import TIP, BodyKind, Capability


@dataclass(frozen=True)
class MjcfBody:
    """The user's own robot: an MJCF ``file`` beside the scenario (same path rules as meshes) whose
    ``base`` body (None: the first body with a free joint) is the robot, driven by ``controller``
    (``pkg.mod:Attr``, loaded like a subject), which turns each velocity command into the model's
    actuator controls. ``digest`` is what the loader read from the file (a hash of its bytes): it
    makes the model part of the content, wherever the file lives (with every file MuJoCo opens
    for it: scenario/mjcf_files.robot_digest). What it can cross is the user's to declare (the harness cannot estimate it from an
    arbitrary model): ``max_step`` and ``max_slope`` together, and ``max_gap`` (None: no gap), and the
    path search and the feasibility check then treat it as a legged body's limits
    (scenario/ground/crossing.py); undeclared, they ignore the terrain for it."""
    file: str
    controller: str
    base: str | None = None
    tip_angle: float = 45.0              # degrees of roll or pitch that count as tipped over
    max_step: float | None = None        # m, the highest step it climbs (None: undeclared)
    max_slope: float | None = None       # degrees, the steepest slope it drives (with max_step)
    max_gap: float | None = None         # m, the widest gap it crosses (None: none)
    digest: str = ""                     # what the loader read from the file (a hash of its bytes)
    kind: Literal["mjcf"] = field(default="mjcf", init=False)


def _mjcf_limits(values: Any, given: Any) -> tuple[str, str, str] | None:
    step, slope = values["max_step"] is not None, values["max_slope"] is not None
    if step != slope or (values["max_gap"] is not None and not step):
        missing = "max_slope" if step else "max_step"
        return (missing, f"an mjcf body's limits are partly declared: declare max_step and max_slope together "
                f"(max_gap may be left out: no gap); {missing} is missing",
                f"add {missing}, or leave all three out (then the path search ignores the terrain for it)")
    return None


def _mjcf_limits_schema(sec: Any, required: list[str]) -> dict[str, Any]:
    """A number (not null: undeclared) for one of them needs numbers for the others."""
    def given(key: str) -> dict[str, Any]:
        return {"required": [key], "properties": {key: {"type": "number"}}}
    return {"allOf": [{"if": given("max_step"), "then": given("max_slope")},
                      {"if": given("max_slope"), "then": given("max_step")},
                      {"if": given("max_gap"), "then": given("max_step")}]}


MJCF_BODY = section(MjcfBody, "robot.body (mjcf)", "the user's own MJCF robot and controller", [
    Text("file", "", "the MJCF file, relative to the scenario's folder and inside it", path=True, inside=True,
         example="file: robot/robot.xml"),
    Text("controller", "", "pkg.mod:Attr of the controller turning velocity commands into actuator controls",
         example="controller: mypkg.control:Controller"),
    Text("base", "", "the robot's base body (none: the first body with a free joint)", default=None),
    TIP,
    Number("max_step", "m", "the highest step it climbs, for the path search and the feasibility check "
           "(none: undeclared, the terrain is ignored there)", ge=0, nullable=True),
    Number("max_slope", "deg", "the steepest slope it drives (declared with max_step)", ge=0, le=90.0,
           nullable=True),
    Number("max_gap", "m", "the widest gap it crosses (none: no gap; declared with max_step)", ge=0,
           nullable=True)],
    rules=[Rule("max_step and max_slope are declared together; max_gap only with them", _mjcf_limits,
                _mjcf_limits_schema)])


def capability(body: MjcfBody, footprint: Any) -> Capability | None:
    """Its declared limits, None when undeclared (the harness cannot estimate them from a model)."""
    if body.max_step is None or body.max_slope is None:
        return None
    return Capability(float(body.max_step), float(body.max_slope),
                      float(body.max_gap) if body.max_gap is not None else 0.0)


KIND = BodyKind("mjcf", MjcfBody, MJCF_BODY, drives=("omni", "diff"), capability=capability)
