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
``sim/world.py`` builds as it always has, bit for bit), found in ``MODELS`` (the registry). Read
first: ``protocol.py`` (``BodyModel``, what a body implements), ``base.py`` (a base on a free
joint, which the three kinds share), then ``wheeled.py``, ``legged.py``, ``mjcf.py``. What each kind
declares and can cross is on the scenario side: scenario/bodies/.
"""
from __future__ import annotations

import importlib

from ...core.errors import ScenarioError
from ...scenario.model import Scenario
from .protocol import BodyControl, BodyModel  # noqa: F401  (the interface a body implements)

# The registry: a scenario body kind (scenario/bodies/) -> "module:Class" of its model here (None:
# the planar body, which sim/world.py builds). Adding a kind is one module and one line here.
MODELS: dict[str, str | None] = {
    "planar": None,
    "wheeled": "wheeled:WheeledModel",
    "legged": "legged:LeggedModel",
    "mjcf": "mjcf:MjcfModel",
}


def check_body(scenario: Scenario) -> None:
    """ScenarioError when the body and the drive, or the body and the terrain, do not go together
    (scenario/bodies: ``body_problem``, which the loader checks too)."""
    from ...scenario.bodies import body_problem

    problem = body_problem(scenario)
    if problem is not None:
        field, message, fix = problem
        raise ScenarioError(message, path=scenario.source, field=field, hint=fix)


def body_model(scenario: Scenario) -> BodyModel | None:
    """The simulation's model of the scenario's body (a ``BodyModel``), or None for the planar body."""
    check_body(scenario)
    kind = scenario.robot.body.kind
    if kind not in MODELS:
        raise ScenarioError(f"no simulation model for a '{kind}' body", path=scenario.source, field="robot.body",
                            hint=f"add one to sim/bodies/__init__.py MODELS (known: {', '.join(MODELS)})")
    where = MODELS[kind]
    if where is None:
        return None
    module, name = where.split(":")
    return getattr(importlib.import_module(f".{module}", __name__), name)(scenario)
