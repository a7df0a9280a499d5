"""Models moved by compiled Gazebo plugins (DynaBARN's obstacles, issue 37): left out of an imported
world, said so, and given back moving when the user writes their motion.

A model plugin is a shared library (``filename='easylibobs_66.so'``): what it does to its model is
compiled code, not written in the world file. DynaBARN's plugins drive their cylinders at 0.5-1.9 m/s
round looping paths, and the world file piles every one of them at one spot before they start: read
as static, the seven difficulty levels become one scenario with a phantom obstacle that is never
there when Gazebo runs. So such models are left out with one warning (how many, which plugins,
why), and ``--plugin-motion FILE`` gives their motion back: a YAML mapping of model name to an
``obstacles[].motion`` mapping of the scenario format (path, speed, mode, start; or velocity)::

    easylibobs_66: {path: [[-2.0, 11.0], [-2.0, -11.0]], speed: 1.2, mode: loop}
    door_1: static          # a plugin that does not move it: where the world file puts it

A moving obstacle that starts or ends inside a wall (DynaBARN's paths start and end inside the
arena's walls, where Gazebo hides them) is warned about (``movers_in_walls``): MuJoCo moves it
through the wall, and the pytest plugin reports such a scenario as infeasible (a mover through a
static obstacle).
"""
from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

from ..core.errors import NavScenarioError
from ..scenario.model import Obstacle


class PluginMotionError(NavScenarioError):
    """The ``--plugin-motion`` file cannot be used (not YAML, an unknown model, an invalid motion)."""


def compiled_plugins(model: ET.Element) -> list[str]:
    """The shared libraries of the plugins of ``model`` and the models nested in it (a Gazebo model
    plugin is always compiled: ``libfoo`` names ``libfoo.so``)."""
    return [p.get("filename", "").strip() for p in model.iter("plugin") if p.get("filename", "").strip()]


def left_out_warning(moved: dict[str, tuple[list[str], list[Obstacle]]]) -> str:
    """One warning for every model left out because compiled plugins move it."""
    names = list(moved)
    shown = ", ".join(names[:8]) + (f", ... ({len(names) - 8} more)" if len(names) > 8 else "")
    libs = list(dict.fromkeys(lib for libs, _ in moved.values() for lib in libs))
    lib_text = ", ".join(libs[:8]) + (f", ... ({len(libs)} libraries)" if len(libs) > 8 else "")
    return (f"{len(names)} model(s) moved by compiled Gazebo plugins left out: {shown} (plugin(s) {lib_text}): "
            f"their motion is compiled into the plugins, not written in the world file, so where the world file "
            f"puts them (DynaBARN piles them at one spot before they start) is not where they are when Gazebo "
            f"runs; give their motion with --plugin-motion FILE (a YAML mapping of model name to a motion: "
            f"docs/how-to/import.md) to have them in the seed, moving")


def read_plugin_motion(path: str | Path) -> dict[str, tuple[dict, int]]:
    """The ``--plugin-motion`` file: model name -> (its motion mapping, its line)."""
    import yaml

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise PluginMotionError(f"--plugin-motion {path}: cannot read: {exc.strerror or exc}") from None
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        body = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise PluginMotionError(f"{path}:{mark.line + 1 if mark else 1}: not YAML: {exc}") from None
    if not isinstance(body, dict) or not body:
        raise PluginMotionError(f"{path}:1: expected a mapping of model name to its motion, e.g. "
                               f"'easylibobs_66: {{path: [[-2, 11], [-2, -11]], speed: 1.2, mode: loop}}'")
    lines = {str(k.value): k.start_mark.line + 1 for k, _ in node.value}
    out = {}
    for name, motion in body.items():
        if not isinstance(motion, dict) and motion != "static":
            raise PluginMotionError(f"{path}:{lines.get(str(name), 1)}: {name}: expected a motion mapping (path, "
                                   f"speed, mode, start; or velocity) or 'static' (where the world file puts it), "
                                   f"got {motion!r}")
        out[str(name)] = (motion, lines.get(str(name), 1))
    return out


def given_motion(moved: dict[str, tuple[list[str], list[Obstacle]]], path: str | Path) -> list[Obstacle]:
    """The left-out models' obstacles moving as the ``--plugin-motion`` file says (each checked as
    the scenario format checks a motion); a name that is not a left-out model is an error listing them."""
    from ..core.errors import ScenarioError
    from ..scenario.dump import dump_scenario
    from ..scenario.loader import loads_scenario
    import yaml

    from ..scenario.model import Mission, Pose, Scenario
    given = read_plugin_motion(path)
    out: list[Obstacle] = []
    for name, (motion, line) in given.items():
        if name not in moved:
            known = ", ".join(moved) or "none"
            raise PluginMotionError(f"{path}:{line}: {name}: not a model the world's compiled plugins move (those "
                                   f"are: {known})")
        if motion == "static":          # the plugin does not move it: where the world file puts it
            out.extend(moved[name][1])
            continue
        for obs in moved[name][1]:
            probe = Scenario(mission=Mission(start=Pose(1e4, 1e4), goal=Pose(1e4 + 10, 1e4)),
                             obstacles=(dataclasses.replace(obs, x=0.0, y=0.0),))
            doc = yaml.safe_load(dump_scenario(probe))
            doc["obstacles"][0]["motion"] = motion
            if "path" in motion:
                doc["obstacles"][0].pop("x", None)
                doc["obstacles"][0].pop("y", None)
            try:
                out.append(loads_scenario(yaml.safe_dump(doc, sort_keys=False)).obstacles[0])
            except ScenarioError as exc:
                field = (exc.field or "").replace("obstacles[0].", "")
                raise PluginMotionError(f"{path}:{line}: {name}: {field + ': ' if field else ''}{exc.message}"
                                       + (f" (fix: {exc.hint})" if exc.hint else "")) from None
    return out


def movers_in_walls(obstacles) -> list[str]:
    """Warnings for moving obstacles whose motion starts or ends inside a static obstacle."""
    from ..verdict.movers import movers_inside

    return [message for _, message in movers_inside(obstacles)]
