"""The readers of a scenario file's parts that need code of their own: the robot (an MJCF body's
file hashed), the mission's poses, each obstacle (its motion, a polygon's outline, a mesh read from
its file), each terrain element (a heightfield's file, a rough patch's grid), the marks, the name and
family, and the signals and requirements. The sections read by declaration alone (``keys.py``) go
through ``reading.py``; ``loader.py`` calls these in ``_build``, one part at a time, so that every
mistake of a file is reported in one pass.
"""
from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path
from typing import Any, Mapping

from . import keys as K
from .format import SCENARIO
from .keys import SCENARIO_LIMITS
from .model import (
    MAX_POLYGON_POINTS,
    MISSION,
    OBSTACLES,
    POSE,
    Mark,
    MeshObstacle,
    Mission,
    Motion,
    Obstacle,
    Pose,
    Reference,
    Robot,
    Simulation,
)
from .reading import (
    _MAX_ABS,
    BROKEN,
    _build_section,
    _check_family,
    _check_name,
    _Ctx,
    _free,
    _join,
    _point,
    _read,
    _read_choice,
    _read_elements,
    _read_number,
    _read_scale,
    _read_sub,
    _read_text,
    _Section,
)
from .yaml_tree import YMap, YNode, YScalar, YSeq, describe

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def _robot(ctx: _Ctx, top: _Section) -> Robot:
    robot = _read_sub(ctx, top, SCENARIO["robot"])
    if robot.body.kind == "mjcf":
        robot = replace(robot, body=_mjcf_file(ctx, robot.body))
    return robot


def _mjcf_file(ctx: _Ctx, body: Any) -> Any:
    """An MJCF body's file: beside the scenario (the mesh path rules), there and readable; its
    digest (a hash of its bytes and of every file MuJoCo will open for it: scenario/mjcf_files.py)
    made part of the content. MuJoCo reads it at run time."""
    from .mesh import MeshError, resolve_mesh_path

    field = "robot.body.file"
    line = ctx.lines.get(field, ctx.lines.get("robot.body", ctx.lines.get("robot")))
    folder = Path(ctx.source).parent if ctx.source else Path.cwd()
    fix = "write the MJCF file's path relative to the scenario's folder"
    try:
        path = resolve_mesh_path(folder, body.file, what="MJCF")
    except MeshError as exc:
        raise ctx.fail(str(exc), field, line, fix) from None
    if path.exists() and not path.is_file():   # a folder, or a named pipe that reading would wait on
        raise ctx.fail(f"{path} is not a file", field, line, fix)
    if not path.exists():
        raise ctx.fail(f"{path} does not exist", field, line, fix)
    from .mjcf_files import MjcfFileError, robot_digest
    try:   # the file and every file MuJoCo will open for it: inside the folder, regular, hashed
        return replace(body, digest=robot_digest(path, folder))
    except MjcfFileError as exc:
        raise ctx.fail(str(exc), field, line, "keep the robot's included files, meshes and textures in the "
                                              "scenario's folder, named by relative paths") from None
    except OSError as exc:
        raise ctx.fail(f"{path} cannot be read: {exc.strerror or exc}", field, line, fix) from None


def _pose(ctx: _Ctx, node: YNode | None, path: str, line: int | None, what: str) -> Pose:
    sec = _Section(ctx, node, path, POSE.names, line=line, what=f"{what} as a mapping {{x, y, yaw}}")
    return _build_section(ctx, sec, POSE)


def _mission(ctx: _Ctx, top: _Section) -> Mission:
    decl = MISSION
    if not top.has("mission"):
        raise top.missing("mission", SCENARIO["mission"].example)
    sec = top.section("mission", decl.names, decl.what)
    if sec is None:
        raise ctx.fail("the mission is empty", "mission", top.line_of("mission"),
                       "give at least start and goal poses")
    values: dict[str, Any] = {}
    for key in ("start", "goal"):
        if not sec.has(key):
            ctx.note(sec.missing(key, decl[key].example))
            values[key] = BROKEN
            continue
        values[key] = ctx.attempt(_pose, ctx, sec.get(key), f"mission.{key}", sec.line_of(key), f"the {key} pose")
    waypoints = []
    listed = decl["waypoints"]
    items = sec.sequence("waypoints", listed.max, listed.what)
    for i, item in enumerate(items):
        ctx.lines[f"mission.waypoints[{i}]"] = item.line
        waypoints.append(ctx.attempt(_pose, ctx, item, f"mission.waypoints[{i}]",
                                     item.line or sec.line_of("waypoints"), "a waypoint"))
    values["waypoints"] = BROKEN if BROKEN in waypoints else tuple(waypoints)
    return Mission(**_read(ctx, sec, decl, values))


def _obstacles(ctx: _Ctx, top: _Section) -> tuple[Obstacle, ...]:
    return _read_elements(ctx, top, OBSTACLES, _obstacle)


def _obstacle(ctx: _Ctx, sec: _Section, element: K.Element, name: str) -> Obstacle:
    """One obstacle: its motion first (a path places it), then its keys as declared."""
    decl = element.section
    keys = decl.by_name
    motion = _motion(ctx, sec, keys["motion"].section) if "motion" in sec.node.items else None
    if motion is not None and motion.path:
        for key in ("x", "y"):
            if sec.has(key):
                raise ctx.fail(f"'{key}' is given by the motion's path (the obstacle starts at its "
                               f"first point)", _join(sec.path, key), sec.line_of(key),
                               f"remove '{key}', or make it the path's first point")
        x, y = motion.path[0]
    else:
        x, y = _read_number(ctx, sec, keys["x"]), _read_number(ctx, sec, keys["y"])
    values: dict[str, Any] = {"name": name, "x": x, "y": y, "motion": motion}
    if element.type == "mesh":
        return _mesh(ctx, sec, decl, values)
    if element.type == "polygon":
        values["points"] = _polygon_points(ctx, sec)
    return decl.cls(**_read(ctx, sec, decl, values))


def _polygon_points(ctx: _Ctx, sec: _Section) -> tuple[tuple[float, float], ...]:
    """A polygon's ``points``: three or more [x, y], a simple polygon (no crossing edges)."""
    from .geometry import polygon_problem

    node = sec.get("points")
    field, line = _join(sec.path, "points"), sec.line_of("points")
    if node is None:
        raise sec.missing("points", "points: [[0, 0], [2, 0], [2, 1], [0, 1]]")
    if not isinstance(node, YSeq):
        raise ctx.fail(f"expected a list of points [x, y], got {describe(node)}", field, line,
                       "write e.g. points: [[0, 0], [2, 0], [2, 1], [0, 1]]")
    if len(node.items) > MAX_POLYGON_POINTS:
        raise ctx.fail(f"{len(node.items)} points is more than the limit of {MAX_POLYGON_POINTS}", field,
                       line, "simplify the outline")
    points = tuple(_point(ctx, p, f"{field}[{k}]", p.line or line) for k, p in enumerate(node.items))
    if len(points) > 3 and points[0] == points[-1]:
        points = points[:-1]          # a closed ring written out: the first point once
    problem = polygon_problem(points)
    if problem is not None:
        raise ctx.fail(problem, field, node.line or line,
                       "list the corners in order around the outline, without edges crossing each other")
    return points


def _mesh(ctx: _Ctx, sec: _Section, decl: K.Section, values: dict[str, Any]) -> Obstacle:
    """A mesh obstacle: its file (beside the scenario) read now, so a bad file is an error here."""
    from .mesh import MeshError, mesh_outline, read_mesh, resolve_mesh_path

    file = _read_text(ctx, sec, decl["file"])
    scale = _read_scale(ctx, sec, decl["scale"])
    folder = Path(ctx.source).parent if ctx.source else Path.cwd()
    try:
        path = resolve_mesh_path(folder, file)
        verts, tris = read_mesh(path)
        reach = max(float(abs(verts[:, k]).max()) * scale[k] for k in range(3))   # m, scale included
        if not reach <= _MAX_ABS:
            raise MeshError(f"{Path(file).name}: a vertex lies {reach:g} m from the mesh's origin (scale "
                            f"included), beyond the supported magnitude of {_MAX_ABS:g} m; check the file's "
                            f"units and the scale (e.g. scale: 0.001 for millimetres)")
        outline, height = mesh_outline(verts, tris, scale, Path(file).name)
    except MeshError as exc:
        raise ctx.fail(str(exc), _join(sec.path, "file"), sec.line_of("file"),
                       "fix the file or the path (relative to the scenario's folder)") from None
    values.update(file=file, scale=scale, footprint=outline, height=height)
    return MeshObstacle(**_read(ctx, sec, decl, values))


def _terrain_element(ctx: _Ctx, sec: _Section, element: K.Element, name: str) -> Any:
    """One terrain element as declared; a heightfield's file read now (a bad file is an error here,
    at its line, and its digest makes the grid content), a rough patch's grid size checked."""
    decl = element.section
    values = _read(ctx, sec, decl, {"name": name})
    if element.type not in ("heightfield", "rough"):
        return decl.cls(**values)
    from .ground.heightmap import HeightmapError, check_grid_total, check_rough, load_heightfield

    try:
        if element.type == "rough":
            check_rough(values["length"], values["width"], values["wavelength"])
        else:
            folder = Path(ctx.source).parent if ctx.source else Path.cwd()
            _, values["digest"] = load_heightfield(folder, values["file"], values["length"], values["width"])
        ctx.grid_samples = check_grid_total(getattr(ctx, "grid_samples", 0), decl.cls(**values), ctx.source)
    except HeightmapError as exc:
        hint = ("fix the file or the path (relative to the scenario's folder)" if exc.field == "file"
                else f"change {exc.field}" if exc.field else "use fewer or coarser grids (rough ground, heightfields)")
        field = _join(sec.path, exc.field) if exc.field else sec.path
        raise ctx.fail(str(exc), field, (sec.line_of(exc.field) if exc.field else None) or sec.line, hint) from None
    return decl.cls(**values)


def _motion(ctx: _Ctx, obs: _Section, decl: K.Section) -> Motion | None:
    """The obstacle's ``motion`` section: a path at a speed, or a constant velocity."""
    sec = obs.section("motion", decl.names, decl.what)
    if sec is None:
        return None
    start = _read_number(ctx, sec, decl["start"])
    if sec.has("velocity"):
        for key in ("path", "speed", "mode"):
            if sec.has(key):
                raise ctx.fail(f"'{key}' does not go with 'velocity' (a constant velocity has no path)",
                               _join(sec.path, key), sec.line_of(key),
                               "give either velocity: [vx, vy], or a path with a speed")
        vx, vy = _point(ctx, sec.get("velocity"), _join(sec.path, "velocity"), sec.line_of("velocity"))
        return Motion(start=start, velocity=(vx, vy))
    node = sec.get("path")
    field, line = _join(sec.path, "path"), sec.line_of("path")
    path_key = decl["path"]
    if node is None:
        raise sec.missing("path", path_key.example)
    if not isinstance(node, YSeq) or len(node.items) < path_key.min:
        got = f"{len(node.items)} point" + ("" if len(node.items) == 1 else "s") if isinstance(node, YSeq) \
            else describe(node)
        raise ctx.fail(f"a path needs at least two points, got {got}", field, node.line or line,
                       "list the points it walks through, e.g. path: [[0.0, -3.0], [0.0, 3.0]]")
    if len(node.items) > path_key.max:
        raise ctx.fail(f"{len(node.items)} path points is more than the limit of {path_key.max}", field, line,
                       "thin the path out")
    points = tuple(_point(ctx, p, f"{field}[{k}]", p.line or line) for k, p in enumerate(node.items))
    if sum(math.dist(a, b) for a, b in zip(points, points[1:])) <= 0.0:
        raise ctx.fail("the path has no length (all its points are the same)", field, line,
                       "give points that differ, or remove 'motion' for a static obstacle")
    speed = _read_number(ctx, sec, decl["speed"])
    mode = _read_choice(ctx, sec, decl["mode"])
    return Motion(path=points, speed=speed, mode=mode, start=start)


def _simulation(ctx: _Ctx, top: _Section) -> Simulation:
    return _read_sub(ctx, top, SCENARIO["simulation"])


def _reference(ctx: _Ctx, top: _Section) -> Reference | None:
    return _read_sub(ctx, top, SCENARIO["reference"])


def _marks(ctx: _Ctx, top: _Section) -> tuple[Mark, ...]:
    items = top.sequence("marks", SCENARIO["marks"].max, "marks")
    marks = []
    for i, item in enumerate(items):
        field, line = f"marks[{i}]", item.line or top.line_of("marks")
        if isinstance(item, YScalar) and isinstance(item.value, str):
            name, value = item.value, None
        elif isinstance(item, YMap) and len(item.items) == 1:
            (name, (_, value)), = item.items.items()
        else:
            raise ctx.fail(f"expected a mark name or a one-key mapping, got {describe(item)}", field, line,
                           "write e.g. 'slow', '{xfail: {reason: known}}', '{skip: why}' or '{mymark: [a, b]}'")
        if not isinstance(name, str) or not _IDENT.match(name):
            raise ctx.fail(f"mark name {name!r} is not a valid Python identifier", field, line,
                           "use letters, digits and underscores, e.g. slow or known_failure")
        args: tuple[Any, ...] = ()
        kwargs: dict[str, Any] = {}
        if isinstance(value, YMap):
            kwargs = _free(ctx, value, field)
            bad = [k for k in kwargs if not isinstance(k, str) or not _IDENT.match(k)]
            if bad:
                raise ctx.fail(f"mark keyword {bad[0]!r} is not a valid Python identifier", field, line,
                               "keywords are names such as reason or strict")
        elif isinstance(value, YSeq):
            args = tuple(_free(ctx, value, field))
        elif value is not None and not (isinstance(value, YScalar) and value.value is None):
            args = (_free(ctx, value, field),)
        marks.append(Mark(name=name, args=args, kwargs=kwargs))
    return tuple(marks)



def _requirements_part(ctx: _Ctx, top: _Section, parts: Mapping[str, Any]) -> Any:
    """``(signals, requirements)`` of the file (requirement_reading.py), read beside its other parts
    so that their mistakes are reported together; what they check against a part that could not be
    read (its obstacles, waypoints, control rate) is left to the next load. None without them."""
    if not (top.has("signals") or top.has("requirements")):
        return None
    from .requirement_reading import check_obstacle_names, known_signals, read_requirements, read_signals

    mission, obstacles, simulation = parts["mission"], parts["obstacles"], parts["simulation"]
    signals = read_signals(ctx, top)          # None: an entry has a mistake (recorded)
    if obstacles is not BROKEN and signals is not None:
        check_obstacle_names(ctx, signals, tuple(o.name for o in obstacles))
    waypoints = len(mission.waypoints) if mission is not BROKEN else int(SCENARIO_LIMITS["max_waypoints"])
    period = 1.0 / simulation.control_rate if simulation is not BROKEN else None
    known = known_signals(waypoints, signals) if signals is not None else None   # else not checked
    return signals or (), read_requirements(ctx, top, known, period=period)



def _name(ctx: _Ctx, top: _Section, default: str | None) -> str:
    scenario_name = top.string("name", default or "")
    if scenario_name:
        _check_name(ctx, scenario_name, "name", top.line_of("name"), file_name=True)
    return scenario_name


def _family(ctx: _Ctx, top: _Section, default: str | None) -> str:
    scenario_family = top.string("family", default or "", nonempty=False)
    if scenario_family:
        _check_family(ctx, scenario_family, top.line_of("family"))
    return scenario_family

