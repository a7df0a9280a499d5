"""Bodies: how the robot meets the ground (``robot.body`` in a scenario).

Which body and drive combinations exist (``robot.drive`` says what the planner's commands mean):

=========  ==================  ==============================================================
body       drive               what it is
=========  ==================  ==============================================================
planar     omni, diff          today's body: slide and hinge joints, gravity off, a flat floor
                               only (a scenario with terrain must choose another body)
wheeled    diff                wheels on the ground under gravity (``drive_wheels``: diff with
                               casters, or skid-steer); it cannot move sideways
legged     omni, diff          a capability model of a walking robot (see legged.py)
mjcf       omni, diff          the user's MJCF robot and controller (see mjcf.py)
=========  ==================  ==============================================================

``body_model(scenario)`` gives the simulation's model of the scenario's body (None: planar, which
``sim/world.py`` builds as it always has, bit for bit).
"""
from __future__ import annotations

from ...core.errors import ScenarioError
from ...scenario.model import Scenario

BODY_DRIVES = {"planar": ("omni", "diff"), "wheeled": ("diff",), "legged": ("omni", "diff"),
               "mjcf": ("omni", "diff")}


def check_body(scenario: Scenario) -> None:
    """ScenarioError when the body and the drive, or the body and the terrain, do not go together."""
    kind = scenario.robot.body.kind
    drive = scenario.robot.drive
    if drive not in BODY_DRIVES[kind]:
        raise ScenarioError(f"a {kind} body cannot drive '{drive}': it cannot move sideways",
                            path=scenario.source, field="robot.drive",
                            hint=f"set robot.drive: {BODY_DRIVES[kind][0]}")
    if kind == "planar" and scenario.terrain:
        raise ScenarioError("the planar body (the default) slides on a flat floor and cannot ride "
                            "terrain", path=scenario.source, field="robot.body",
                            hint="give the robot a body that meets the ground: robot.body: "
                                 "{type: wheeled} (or legged, or mjcf with your own robot)")


def body_model(scenario: Scenario):
    """The simulation's model of the scenario's body, or None for the planar body."""
    check_body(scenario)
    kind = scenario.robot.body.kind
    if kind == "planar":
        return None
    if kind == "wheeled":
        from .wheeled import WheeledModel
        return WheeledModel(scenario)
    if kind == "legged":
        from .legged import LeggedModel
        return LeggedModel(scenario)
    from .mjcf import MjcfModel
    return MjcfModel(scenario)
