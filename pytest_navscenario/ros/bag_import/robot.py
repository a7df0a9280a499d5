"""The seed's robot when the bag or the user says more than the bag's URDF, Nav2 footprint and
odometry do: ``--robot FILE`` (a robot: section), else the robot of the scenario a bag of ours ran
(``/navscenario/scenario``, written by ``--nav-bag``: the bag reproduces that run, so its robot is
known exactly), else none (the seed's own guess from the bag); ``--footprint`` and ``--drive``
override either, as in the other importers (ros/robot_options.py)."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ...core.errors import ScenarioError
from ...scenario.model import Footprint, Robot
from .reading import BagData
from .topics import RECORDED_SCENARIO


@dataclass(frozen=True)
class RobotChoice:
    """What the command line says of the robot: ``--robot`` (read), ``--footprint``, ``--drive``."""
    robot: Robot | None = None
    robot_file: str = ""
    footprint: Footprint | None = None
    footprint_text: str = ""
    drive: str | None = None


def describe(fp: Footprint) -> str:
    return f"a circle of radius {fp.radius:g} m" if fp.shape == "circle" else f"a {fp.length:g} x {fp.width:g} m box"


def base_robot(data: BagData, choice: RobotChoice) -> tuple[Robot | None, str, list[str]]:
    """The robot the seed starts from (None: the bag's own guess), where it came from, warnings."""
    if choice.robot is not None:
        return choice.robot, f"the robot: section of {choice.robot_file} (--robot)", []
    if not data.recorded:
        return None, "", []
    from ...scenario.loader import loads_scenario
    try:
        robot = loads_scenario(data.recorded, source=f"{data.path}:{RECORDED_SCENARIO}").robot
    except ScenarioError as exc:
        return None, "", [f"{RECORDED_SCENARIO}: the scenario the bag recorded cannot be read ({exc}); the robot "
                          f"is guessed from the bag instead"]
    return robot, f"the scenario the bag recorded ({RECORDED_SCENARIO}: {describe(robot.footprint)}, " \
                  f"{robot.drive} drive)", []


def seed_robot(guessed: Robot, base: Robot | None, choice: RobotChoice, footprint: Footprint) -> Robot:
    """The seed's robot: ``base`` when there is one (else the bag's guess), with ``footprint`` and
    the ``--drive`` given."""
    robot = dataclasses.replace(base if base is not None else guessed, footprint=footprint)
    return dataclasses.replace(robot, drive=choice.drive) if choice.drive else robot
