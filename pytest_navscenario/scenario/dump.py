"""Writing scenarios: the plain dict form with the documented key order, YAML text whose floats
round-trip exactly (``load(dump(s)) == s``), and atomic saving to a file."""
from __future__ import annotations

import datetime
import os
from typing import Any, Mapping

import yaml

from ..core.files import atomic_write_text
from . import keys as K
from .loader import LATENCY_KEYS, LIDAR_KEYS, LIMITS_KEYS, LOCALISATION_KEYS
from .model import LIDAR, PERTURB, BoxObstacle, Mark, MeshObstacle, Motion, Obstacle, PolygonObstacle, Pose, Scenario
from .requirements import Signal
from .bodies import BODY, PlanarBody
from .terrain import LIDAR3D


def _f(value: Any) -> float:
    return float(value)


def _pose_dict(pose: Pose) -> dict[str, Any]:
    return {"x": _f(pose.x), "y": _f(pose.y), "yaw": _f(pose.yaw)}


def _plain(value: Any) -> Any:
    """Free-form data as safe_dump-able plain types (numpy scalars, tuples, mappings)."""
    if isinstance(value, Mapping):
        return {(_plain(k) if not isinstance(k, str) else k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if type(value).__module__ == "numpy" and hasattr(value, "tolist"):  # numpy scalars and arrays
        return _plain(value.tolist())
    if isinstance(value, (datetime.date, datetime.time)):  # free-form data keeps dates as text
        return value.isoformat()
    return value


def _mark_entry(mark: Mark) -> Any:
    if mark.args and mark.kwargs:
        raise ValueError(f"mark {mark.name!r} has both positional and keyword arguments, which the "
                         f"scenario format cannot express; use keyword arguments only")
    if mark.kwargs:
        return {mark.name: _plain(dict(mark.kwargs))}
    if not mark.args:
        return mark.name
    if len(mark.args) == 1 and not isinstance(mark.args[0], (list, tuple, Mapping)) and mark.args[0] is not None:
        return {mark.name: _plain(mark.args[0])}
    return {mark.name: _plain(list(mark.args))}


def _declared(value: Any, decl: K.Section) -> dict[str, Any]:
    """A dataclass as the mapping of its declared keys (keys whose value is None are left out)."""
    out: dict[str, Any] = {}
    for key in decl.keys:
        item = getattr(value, key.field)
        if item is None:
            continue
        if isinstance(key, K.Number):
            item = _f(item)
        elif isinstance(key, K.Integer):
            item = int(item)
        out[key.name] = item
    return out


def _obstacle_dict(obs: Obstacle) -> dict[str, Any]:
    if isinstance(obs, BoxObstacle):
        out = {"type": "box", "name": obs.name, "x": _f(obs.x), "y": _f(obs.y), "length": _f(obs.length),
               "width": _f(obs.width), "yaw": _f(obs.yaw), "height": _f(obs.height)}
    elif isinstance(obs, PolygonObstacle):
        out = {"type": "polygon", "name": obs.name, "x": _f(obs.x), "y": _f(obs.y),
               "points": [[_f(a), _f(b)] for a, b in obs.points], "yaw": _f(obs.yaw), "height": _f(obs.height)}
    elif isinstance(obs, MeshObstacle):     # the outline and height come from the file again
        out = {"type": "mesh", "name": obs.name, "x": _f(obs.x), "y": _f(obs.y), "file": obs.file,
               "scale": [_f(v) for v in obs.scale], "yaw": _f(obs.yaw)}
    else:
        out = {"type": "cylinder", "name": obs.name, "x": _f(obs.x), "y": _f(obs.y),
               "radius": _f(obs.radius), "height": _f(obs.height)}
    if not getattr(obs, "visible_to_lidar", True):
        out["visible_to_lidar"] = False
    if getattr(obs, "z", None) is not None:
        out["z"] = _f(obs.z)
    motion = getattr(obs, "motion", None)
    if motion is not None:
        out["motion"] = _motion_dict(motion)
        if motion.path:             # the path's first point is where it stands: no x, y
            del out["x"], out["y"]
    return out


def _motion_dict(motion: Motion) -> dict[str, Any]:
    if motion.velocity is not None:
        return {"velocity": [_f(motion.velocity[0]), _f(motion.velocity[1])], "start": _f(motion.start)}
    return {"path": [[_f(x), _f(y)] for x, y in motion.path], "speed": _f(motion.speed),
            "mode": motion.mode, "start": _f(motion.start)}


def _signal_dict(signal: Signal) -> dict[str, Any]:
    out: dict[str, Any] = {"name": signal.name}
    if signal.distance_to:
        out["distance_to"] = list(signal.distance_to)
    elif signal.inside is not None:
        region = signal.inside
        out["inside"] = ({"x": _f(region.x), "y": _f(region.y), "radius": _f(region.radius)}
                         if region.radius is not None else {"points": [[_f(a), _f(b)] for a, b in region.points]})
    elif signal.speed_toward:
        out["speed_toward"] = signal.speed_toward
    else:
        out["function"] = signal.function
    return out


def scenario_to_dict(scenario: Scenario) -> dict[str, Any]:
    """The scenario as plain data in the documented key order. Physical settings (robot, mission,
    obstacles, simulation) are always written in full, so a saved file does not depend on defaults;
    empty metadata (description, marks, reference, search, provenance) is left out."""
    s = scenario
    out: dict[str, Any] = {"version": int(s.version)}
    if s.name:
        out["name"] = s.name
    if s.family:
        out["family"] = s.family
    if s.description:
        out["description"] = s.description
    if s.marks:
        out["marks"] = [_mark_entry(m) for m in s.marks]
    r = s.robot
    fp = r.footprint
    footprint: dict[str, Any] = {"shape": fp.shape}
    if fp.shape == "circle":
        footprint["radius"] = _f(fp.radius)
    else:
        footprint.update(length=_f(fp.length), width=_f(fp.width))
    lim, lid, saf = r.limits, r.lidar, r.safety
    out["robot"] = {
        "footprint": footprint,
        "drive": r.drive,
        "limits": {k: _f(getattr(lim, k)) for k in LIMITS_KEYS},
        "lidar": {"beams": int(lid.beams), **{k: _f(getattr(lid, k)) for k in LIDAR_KEYS[1:6]}},
        "safety": {"enabled": bool(saf.enabled), "horizon": _f(saf.horizon), "margin": _f(saf.margin)},
    }
    # the sensor and localisation faults: written when set (files without them stay as they were)
    for key in ("noise_per_metre", "dropout_at_max", "spurious"):
        if getattr(lid, key) not in (0.0, None):
            out["robot"]["lidar"][key] = _f(getattr(lid, key))
    if lid.mount_height != LIDAR["mount_height"].default:
        out["robot"]["lidar"]["mount_height"] = _f(lid.mount_height)
    if r.localisation.drifts:
        out["robot"]["localisation"] = {k: _f(getattr(r.localisation, k)) for k in LOCALISATION_KEYS}
    if r.latency.observation or r.latency.command:
        out["robot"]["latency"] = {k: _f(getattr(r.latency, k)) for k in LATENCY_KEYS}
    if not isinstance(r.body, PlanarBody):     # terrain: written when not today's planar body
        out["robot"]["body"] = {"type": r.body.kind, **_declared(r.body, BODY.element(r.body.kind).section)}
    if r.lidar3d is not None:
        out["robot"]["lidar3d"] = _declared(r.lidar3d, LIDAR3D)
    m = s.mission
    mission: dict[str, Any] = {"start": _pose_dict(m.start), "goal": _pose_dict(m.goal)}
    if m.waypoints:
        mission["waypoints"] = [_pose_dict(w) for w in m.waypoints]
    tol: dict[str, Any] = {"position": _f(m.goal_tolerance.position)}
    if m.goal_tolerance.yaw is not None:
        tol["yaw"] = _f(m.goal_tolerance.yaw)
    mission.update(goal_tolerance=tol, waypoint_tolerance=_f(m.waypoint_tolerance), timeout=_f(m.timeout))
    out["mission"] = mission
    out["obstacles"] = [_obstacle_dict(o) for o in s.obstacles]
    if s.terrain:
        from .terrain import TERRAIN
        out["terrain"] = [{"type": e.kind, **_declared(e, TERRAIN.element(e.kind).section)} for e in s.terrain]
    sim = s.simulation
    out["simulation"] = {"timestep": _f(sim.timestep), "control_rate": _f(sim.control_rate), "seed": int(sim.seed)}
    if sim.perturb.any:     # written when set (files without it stay as they were)
        out["simulation"]["perturb"] = _declared(sim.perturb, PERTURB)
    if s.reference is not None:
        if s.reference.file is not None:
            out["reference"] = {"file": str(s.reference.file)}
        else:
            out["reference"] = {"points": [[_f(t), _f(x), _f(y)] for t, x, y in s.reference.points]}
        if s.reference.compare != "time":
            out["reference"]["compare"] = s.reference.compare
    if s.signals:
        out["signals"] = [_signal_dict(x) for x in s.signals]
    if s.requirements:
        out["requirements"] = [{"name": r.name, "spec": r.spec, **({"scale": _f(r.scale)} if r.scale else {})}
                               for r in s.requirements]
    if s.search is not None:
        out["search"] = _plain(dict(s.search))
    if s.provenance is not None:
        out["provenance"] = _plain(dict(s.provenance))
    return out


_Dumper: type = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


def dump_scenario(scenario: Scenario) -> str:
    """YAML text of the scenario (safe YAML, block style, documented key order); exact round trip."""
    return yaml.dump(scenario_to_dict(scenario), Dumper=_Dumper, sort_keys=False, default_flow_style=False,
                     allow_unicode=True, width=100)


def save_scenario(scenario: Scenario, path: str | os.PathLike) -> None:
    """Write the scenario to ``path`` atomically (never a half-written file), its first line the
    YAML language server's modeline naming the project's scenario schema (``modeline.py``)."""
    from .modeline import with_modeline
    atomic_write_text(path, with_modeline(dump_scenario(scenario), path))
