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

def check_body(scenario: Scenario) -> None:
    """ScenarioError when the body and the drive, or the body and the terrain, do not go together
    (scenario/ground.body_problem: the loader checks the same)."""
    from ...scenario.ground.surface import body_problem

    problem = body_problem(scenario)
    if problem is not None:
        field, message, fix = problem
        raise ScenarioError(message, path=scenario.source, field=field, hint=fix)


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
