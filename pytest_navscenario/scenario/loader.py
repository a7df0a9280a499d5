"""Scenario YAML: load and validate, with file:line errors (writing is in dump.py).

    load_scenario(path)                 -> Scenario   name/family default to file stem / folder name
    loads_scenario(text, source=None, *, name=None, family=None) -> Scenario
    scenario_from_dict(data, source=None) -> Scenario
    check_scenario(scenario)                          semantic checks only (for generated scenarios)
    looks_like_scenario(text_or_mapping) -> bool      cheap test for collectors
    SCENARIO_LIMITS                                   the documented limits for hostile files

Every problem raises ``ScenarioError`` naming the file, the line, the dotted field and a fix.
Parsing has ``yaml.safe_load`` semantics (see ``yaml_tree``), plus one convenience: an unquoted
number in exponent form that YAML 1.1 reads as a string (``1e-3``, ``2.5e3``) is accepted where a
number is expected.
"""
from __future__ import annotations

import codecs
import difflib
import math
import os
import re
import stat
from dataclasses import replace
from pathlib import Path
from typing import Any, Mapping


from ..core.errors import ScenarioError
from . import keys as K
from .format import SCENARIO, SUPPORTED_VERSIONS
from .keys import SCENARIO_LIMITS
from .model import (  # noqa: F401  (DRIVES ... PERSON_SPEED: re-exported, they used to live here)
    DRIVES,
    FOOTPRINT,
    LATENCY,
    LIDAR,
    LIMITS,
    LOCALISATION,
    MAX_POLYGON_POINTS,
    MISSION,
    MOTION,
    MOTION_MODES,
    OBSTACLES,
    PERSON_HEIGHT,
    PERSON_RADIUS,
    PERSON_SPEED,
    POSE,
    REFERENCE,
    REFERENCE_COMPARE,
    ROBOT,
    SAFETY,
    SCHEMA_VERSION,
    SHAPES,
    SIMULATION,
    GOAL_TOLERANCE,
    BoxObstacle,
    CylinderObstacle,
    Mark,
    MeshObstacle,
    Mission,
    Motion,
    Obstacle,
    Pose,
    Reference,
    Robot,
    Scenario,
    Simulation,
)
from .reading import (  # the readers, under the names this module always used
    _MAX_ABS,
    BROKEN,
    _Ctx,
    _Section,
    _build_section,
    _check_family,
    _check_name,
    _free,
    _join,
    _mapping,
    _point,
    _read,
    _read_choice,
    _read_elements,
    _read_number,
    _read_scale,
    _read_sub,
    _read_text,
)
from .search_settings import read_search
from .yaml_tree import YMap, YNode, YScalar, YSeq, describe, from_plain, parse_yaml

_LIST_LIMITS = {"obstacles": (int(SCENARIO_LIMITS["max_obstacles"]), "obstacles")}  # refused while parsing
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")

# The keys of each section, as declared (model.py, format.py); kept under their old names.
TOP_KEYS = SCENARIO.names
ROBOT_KEYS = ROBOT.names
FOOTPRINT_KEYS = FOOTPRINT.names
LIMITS_KEYS = LIMITS.names
LIDAR_KEYS = LIDAR.names
LOCALISATION_KEYS = LOCALISATION.names
LATENCY_KEYS = LATENCY.names
SAFETY_KEYS = SAFETY.names
MISSION_KEYS = MISSION.names
POSE_KEYS = POSE.names
TOLERANCE_KEYS = GOAL_TOLERANCE.names
MOTION_KEYS = MOTION.names
SIMULATION_KEYS = SIMULATION.names
REFERENCE_KEYS = REFERENCE.names
OBSTACLE_TYPES = OBSTACLES.type_names
TYPE_KEYS = {e.type: ("type",) + e.section.names for e in OBSTACLES.types}


# --------------------------------------------------------------------------- sections

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
    from .ground.heightmap import HeightmapError, check_rough, load_heightfield

    try:
        if element.type == "rough":
            check_rough(values["length"], values["width"], values["wavelength"])
        else:
            folder = Path(ctx.source).parent if ctx.source else Path.cwd()
            _, values["digest"] = load_heightfield(folder, values["file"], values["length"], values["width"])
    except HeightmapError as exc:
        hint = ("fix the file or the path (relative to the scenario's folder)" if exc.field == "file"
                else f"change {exc.field}")
        raise ctx.fail(str(exc), _join(sec.path, exc.field), sec.line_of(exc.field) or sec.line, hint) from None
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


# --------------------------------------------------------------------------- semantic checks

def _steps_per_tick(sim: Simulation) -> float:
    return 1.0 / (sim.timestep * sim.control_rate)


def _check_lidar3d(ctx: _Ctx, scenario: Scenario) -> None:
    """A 3D lidar's rays a scan (each costs ~0.3 us of CPU: 256 x 10000 rays took 0.9 s a scan) and
    the ranges an episode records (a float32 a ray a tick, kept for bags: 3 GB for 30 s of those)
    within SCENARIO_LIMITS."""
    lidar, lines = scenario.robot.lidar3d, ctx.lines
    rays = int(lidar.rings) * int(lidar.beams)
    limit = int(SCENARIO_LIMITS["max_lidar3d_rays"])
    if rays > limit:
        raise ctx.fail(f"{lidar.rings} rings x {lidar.beams} beams = {rays} rays a scan, more than the limit "
                       f"of {limit} (128 x 2048, the densest spinning lidars)", "robot.lidar3d.beams",
                       lines.get("robot.lidar3d.beams", lines.get("robot.lidar3d")),
                       f"fewer rings or beams: rings x beams at most {limit}")
    sim = scenario.simulation
    scans = math.ceil(scenario.mission.timeout * sim.control_rate - 1e-9) + 1
    size, budget = scans * rays * 4, int(SCENARIO_LIMITS["max_lidar3d_record_bytes"])
    if size > budget:
        raise ctx.fail(f"{scans} scans of {lidar.rings} x {lidar.beams} ranges (float32) would record "
                       f"{size / 2**30:.1f} GiB, more than the limit of {budget / 2**30:g} GiB",
                       "robot.lidar3d", lines.get("robot.lidar3d", lines.get("robot")),
                       "fewer rings or beams, a shorter mission.timeout or a lower simulation.control_rate "
                       f"(scans x rings x beams at most {budget // 4})")


def check_scenario(scenario: Scenario, *, _ctx: _Ctx | None = None) -> None:
    """Checks across fields: whole physics steps per tick, episode length, start/goal/waypoints clear
    of obstacles. Run by the loader; call it on scenarios built in code (e.g. generated layouts)."""
    ctx = _ctx or _Ctx(scenario.source)
    lines = ctx.lines
    sim = scenario.simulation
    steps = _steps_per_tick(sim)
    if steps > 1e6:
        raise ctx.fail(f"timestep {sim.timestep!r} s and control_rate {sim.control_rate!r} Hz give "
                       f"{steps:.3g} physics steps per control tick", "simulation.control_rate",
                       lines.get("simulation.control_rate", lines.get("simulation")),
                       "raise the control rate (planner ticks per second)")
    if steps < 1 - 1e-9 or abs(steps - round(steps)) > 1e-6 * max(1.0, steps):
        whole = max(1, round(steps))
        raise ctx.fail(f"timestep {sim.timestep!r} s and control_rate {sim.control_rate!r} Hz give "
                       f"{steps:.4g} physics steps per control tick; it must be a whole number",
                       "simulation.control_rate", lines.get("simulation.control_rate", lines.get("simulation")),
                       f"e.g. control_rate: {1.0 / (sim.timestep * whole):g} ({whole} steps of {sim.timestep:g} s)")
    episode_steps = scenario.mission.timeout / sim.timestep
    if episode_steps > SCENARIO_LIMITS["max_episode_steps"]:
        raise ctx.fail(f"timeout {scenario.mission.timeout!r} s at timestep {sim.timestep!r} s is "
                       f"{episode_steps:.3g} physics steps, more than {SCENARIO_LIMITS['max_episode_steps']:g}",
                       "mission.timeout", lines.get("mission.timeout", lines.get("mission")),
                       "shorten the timeout or lengthen the timestep")
    if scenario.robot.lidar3d is not None:
        _check_lidar3d(ctx, scenario)
    for key in ("observation", "command"):
        delay = getattr(scenario.robot.latency, key)
        ticks = delay * sim.control_rate
        if abs(ticks - round(ticks)) > 1e-6:
            field = f"robot.latency.{key}"
            raise ctx.fail(f"a delay of {delay!r} s is not a whole number of control periods "
                           f"({1.0 / sim.control_rate:g} s at {sim.control_rate:g} Hz)", field,
                           lines.get(field, lines.get("robot.latency")),
                           f"e.g. {key}: {round(ticks) / sim.control_rate:g}")
        timeout = scenario.mission.timeout
        if delay >= timeout:
            field = f"robot.latency.{key}"
            what = ("the planner would see nothing after the first observation" if key == "observation"
                    else "no command would act before the episode ends: the robot never moves")
            raise ctx.fail(f"a delay of {delay!r} s is not shorter than the timeout ({timeout!r} s): {what}",
                           field, lines.get(field, lines.get("robot.latency")),
                           f"shorten the delay below {timeout:g} s, or lengthen mission.timeout")
    if scenario.obstacles:
        _check_clear(scenario, ctx)
        _check_speeds(scenario, ctx)
    if scenario.terrain or scenario.robot.body.kind != "planar" or any(o.z is not None for o in scenario.obstacles):
        from .ground.surface import body_problem, mission_problem, obstacle_problem, terrain_problem
        problem = (body_problem(scenario) or terrain_problem(scenario) or mission_problem(scenario)
                   or obstacle_problem(scenario))
        if problem is not None:
            field, message, fix = problem
            parts = field.split(".")
            line = next((lines[key] for key in (".".join(parts[:n]) for n in range(len(parts), 0, -1))
                         if key in lines), None)
            raise ctx.fail(message, field, line, fix)


STEP_SHARE = 0.2   # of the obstacle's and the robot's smallest widths: the farthest a mover may go in a step


def max_resolved_speed(scenario: Scenario, obs: Any, timestep: float | None = None) -> float:
    """The fastest a moving obstacle may go (m/s) for contacts, checked after every physics step,
    to see it cross the robot: the two may close in on each other by at most ``STEP_SHARE`` of the
    sum of their smallest widths per step (the robot's own top speed counts), so that a crossing
    overlaps at some step; at the limit only a graze shallower than ~1 % of the two widths together
    can fall between two steps (round shapes). Above it a box at 100 m/s passed through the robot
    unseen (issue 26)."""
    reach, robot_speed = _closing(scenario, obs)
    return reach / (timestep or scenario.simulation.timestep) - robot_speed


def _closing(scenario: Scenario, obs: Any) -> tuple[float, float]:
    """(how far the obstacle and the robot may close in per physics step, the robot's top speed)."""
    from .geometry import convex_parts_local, outline_points

    if isinstance(obs, BoxObstacle):
        width = min(obs.length, obs.width)
    elif isinstance(obs, CylinderObstacle):
        width = 2.0 * obs.radius
    else:                                    # polygon, mesh: the thinnest of its convex parts
        width = min(_min_width(part) for part in convex_parts_local(tuple(outline_points(obs))))
    fp = scenario.robot.footprint
    robot_width = 2.0 * fp.radius if fp.shape == "circle" else min(fp.length, fp.width)
    limits = scenario.robot.limits
    robot_speed = math.hypot(limits.max_speed, limits.max_lateral_speed if scenario.robot.drive == "omni" else 0.0)
    return STEP_SHARE * (width + robot_width), robot_speed


def _min_width(points: Any) -> float:
    """The width of a convex polygon across its thinnest direction (the least, over its edges, of
    the farthest corner from the edge's line)."""
    best = math.inf
    n = len(points)
    for i in range(n):
        (ax, ay), (bx, by) = points[i], points[(i + 1) % n]
        ex, ey = bx - ax, by - ay
        length = math.hypot(ex, ey)
        if length > 0.0:
            best = min(best, max(abs(ex * (py - ay) - ey * (px - ax)) for px, py in points) / length)
    return best


def _check_speeds(scenario: Scenario, ctx: _Ctx) -> None:
    """Moving obstacles no faster than the physics step can follow (``max_resolved_speed``)."""
    for i, obs in enumerate(scenario.obstacles):
        motion = getattr(obs, "motion", None)
        if motion is None:
            continue
        speed = math.hypot(*motion.velocity) if motion.velocity is not None else motion.speed
        limit = max_resolved_speed(scenario, obs)
        if speed <= limit:
            continue
        key = "velocity" if motion.velocity is not None else "speed"
        field = f"obstacles[{i}].motion.{key}"
        dt, period = scenario.simulation.timestep, 1.0 / scenario.simulation.control_rate
        reach, robot_speed = _closing(scenario, obs)
        steps = math.ceil(period / (reach / (speed + robot_speed)) - 1e-9)   # per tick, to follow it
        while not _decimal(steps):
            steps += 1          # a step count whose timestep is a short decimal: 0.00125, not 0.00175439
        raise ctx.fail(
            f"{speed:g} m/s is faster than the simulation can follow at a timestep of {dt:g} s: "
            f"{obs.name!r} would move {speed * dt:.3g} m per physics step and could pass through the "
            f"robot between two steps unseen; at most {max(limit, 0.0):.3g} m/s at this timestep (it and "
            f"the robot may close in by {STEP_SHARE:g} of their smallest widths per step)",
            field, ctx.lines.get(field, ctx.lines.get(f"obstacles[{i}].motion", ctx.lines.get("obstacles"))),
            f"slow it down, or give simulation.timestep: {period / steps:.10g} ({steps} steps per control tick)")


def _decimal(n: int) -> bool:
    """True if 1/n has a finite decimal expansion (n = 2^a 5^b)."""
    for p in (2, 5):
        while n % p == 0:
            n //= p
    return n == 1


def _check_clear(scenario: Scenario, ctx: _Ctx) -> None:
    """Start and goal footprints and waypoints must not touch an obstacle (names the first one)."""
    from shapely.geometry import Point

    from .geometry import bounding_radius, footprint_polygon, footprint_radius, obstacle_polygon

    mission = scenario.mission
    fp = scenario.robot.footprint
    checks = [("start", mission.start, footprint_radius(fp), "the robot's footprint at the start"),
              ("goal", mission.goal, footprint_radius(fp), "the robot's footprint at the goal")]
    checks += [(f"waypoints[{i}]", wp, 0.0, f"waypoint {i}") for i, wp in enumerate(mission.waypoints)]
    # Cheap bounding-circle test first, so thousands of obstacles cost microseconds, not polygons.
    bounds = [(o.x, o.y, bounding_radius(o)) for o in scenario.obstacles]
    moving = {i for i, o in enumerate(scenario.obstacles) if getattr(o, "motion", None) is not None}
    for key, pose, reach, what in checks:
        # a moving obstacle must leave the start clear (where it stands at t = 0); it may cross the
        # goal and the waypoints
        near = [i for i, (x, y, r) in enumerate(bounds) if math.hypot(x - pose.x, y - pose.y) <= r + reach + 1e-9
                and (key == "start" or i not in moving)]
        if not near:
            continue
        shape = (footprint_polygon(fp, pose.x, pose.y, pose.yaw_rad) if reach else Point(pose.x, pose.y))
        for i in near:
            obs = scenario.obstacles[i]
            if shape.intersects(obstacle_polygon(obs)):
                field = f"mission.{key}"
                what_moves = "start" if key == "start" else "goal" if key == "goal" else "waypoint"
                raise ctx.fail(f"{what} ({pose.x:g}, {pose.y:g}) overlaps obstacle {obs.name!r}", field,
                               ctx.lines.get(field, ctx.lines.get("mission")),
                               f"move the {what_moves} or obstacle {obs.name!r} so they are clear")


# --------------------------------------------------------------------------- public API

def _build(root: YNode | None, ctx: _Ctx, name: str | None, family: str | None) -> Scenario:
    if root is None or (isinstance(root, YScalar) and root.value is None):
        raise ctx.fail("the scenario is empty", None, 1,
                       "a scenario needs at least 'version: 1' and a 'mission:' with start and goal")
    if not isinstance(root, YMap):
        raise ctx.fail(f"the top level must be a mapping of scenario fields, got {describe(root)}", None,
                       root.line, "start the file with 'version: 1' followed by 'mission:' etc.")
    # The version decides the schema, so check it before anything else.
    version_item = root.items.get("version")
    if version_item is None:
        raise ctx.fail("missing required field 'version'", "version", root.line,
                       f"add 'version: {SCHEMA_VERSION}' as the first line")
    vnode = version_item[1]
    version = vnode.value if isinstance(vnode, YScalar) else None
    if isinstance(version, bool) or version not in SUPPORTED_VERSIONS:
        raise ctx.fail(f"unsupported version {describe(vnode)}; this pytest-navscenario reads version(s) "
                       f"{', '.join(map(str, SUPPORTED_VERSIONS))}", "version", version_item[0] or vnode.line,
                       f"write 'version: {SCHEMA_VERSION}' (or upgrade pytest-navscenario for newer files)")
    top = _Section(ctx, root, "", TOP_KEYS)
    lines = ctx.lines
    for key in TOP_KEYS:
        if top.has(key):
            lines[key] = top.line_of(key)
    # Each part is read on its own: with ctx.collect a mistake in one is recorded and the others
    # are still read, so that one pass reports every mistake it can find (ctx.finish).
    parts = {
        "name": ctx.attempt(_name, ctx, top, name),
        "family": ctx.attempt(_family, ctx, top, family),
        "description": ctx.attempt(lambda: top.string("description", "", nonempty=False)),
        "marks": ctx.attempt(_marks, ctx, top),
        "robot": ctx.attempt(_robot, ctx, top),
        "mission": ctx.attempt(_mission, ctx, top),
        "obstacles": ctx.attempt(_obstacles, ctx, top),
        "terrain": ctx.attempt(_read_elements, ctx, top, SCENARIO["terrain"], _terrain_element),
        "simulation": ctx.attempt(_simulation, ctx, top),
        "reference": ctx.attempt(_reference, ctx, top),
        "search": ctx.attempt(_mapping, ctx, top, "search"),
        "provenance": ctx.attempt(_mapping, ctx, top, "provenance"),
    }
    ctx.finish()
    scenario = Scenario(version=int(version), source=ctx.source, **parts)
    if scenario.search is not None:     # the search's space, checked on plain runs too
        read_search(ctx, top.get("search"), "search", top.line_of("search"),
                    obstacles=tuple(o.name for o in scenario.obstacles), waypoints=len(scenario.mission.waypoints),
                    terrain=tuple(el.name for el in scenario.terrain))
        ctx.finish()
    check_scenario(scenario, _ctx=ctx)
    return scenario


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


def loads_scenario(text: str | bytes, source: str | os.PathLike | None = None, *,
                   name: str | None = None, family: str | None = None) -> Scenario:
    """Parse and validate scenario YAML text. ``name``/``family`` apply when the YAML has none."""
    src = os.fspath(source) if source is not None else None
    if isinstance(text, (bytes, bytearray)):
        text = _decode(bytes(text), src)
    if not isinstance(text, str):
        raise ScenarioError(f"expected YAML text, got {type(text).__name__}", path=src,
                            hint="pass the file's text, or use load_scenario(path)")
    if len(text) > SCENARIO_LIMITS["max_file_bytes"]:
        raise ScenarioError(f"the text is {len(text)} characters, more than the limit of "
                            f"{SCENARIO_LIMITS['max_file_bytes']:g}", path=src, hint="this is not a scenario file")
    ctx = _Ctx(src, collect=True)
    root = parse_yaml(text, src, max_depth=int(SCENARIO_LIMITS["max_depth"]),
                      max_nodes=int(SCENARIO_LIMITS["max_nodes"]), list_limits=_LIST_LIMITS)
    return _build(root, ctx, name, family)


def scenario_from_dict(data: Mapping[str, Any], source: str | os.PathLike | None = None) -> Scenario:
    """Validate a plain mapping (as safe_load would give) into a Scenario; errors have no lines."""
    src = os.fspath(source) if source is not None else None
    if not isinstance(data, Mapping):
        raise ScenarioError(f"expected a mapping of scenario fields, got {type(data).__name__}", path=src,
                            hint="pass a dict with 'version' and 'mission' keys")
    try:
        root = from_plain(data, max_depth=int(SCENARIO_LIMITS["max_depth"]),
                          max_nodes=int(SCENARIO_LIMITS["max_nodes"]), source=src)
    except RecursionError:
        raise ScenarioError("the mapping nests too deeply", path=src) from None
    return _build(root, _Ctx(src, collect=True), None, None)


_BOMS = ((codecs.BOM_UTF32_LE, "utf-32"), (codecs.BOM_UTF32_BE, "utf-32"), (codecs.BOM_UTF8, "utf-8-sig"),
         (codecs.BOM_UTF16_LE, "utf-16"), (codecs.BOM_UTF16_BE, "utf-16"))   # UTF-32 LE before UTF-16 LE


def text_codec(data: bytes) -> str:
    """The codec of a scenario file's bytes: UTF-8, or UTF-16/32 when the file starts with their
    byte-order mark (YAML allows all three); the codec consumes the mark."""
    for bom, codec in _BOMS:
        if data.startswith(bom):
            return codec
    return "utf-8"


def _decode(data: bytes, source: str | None) -> str:
    codec = text_codec(data)
    try:
        return data.decode(codec)
    except UnicodeDecodeError as exc:
        name = {"utf-8-sig": "UTF-8", "utf-8": "UTF-8"}.get(codec, codec.upper())
        line = data.count(b"\n", 0, exc.start) + 1 if name == "UTF-8" else None
        raise ScenarioError(f"not {name} text: byte 0x{data[exc.start]:02x} cannot be decoded", path=source,
                            line=line, hint="is this a binary file? save the scenario as UTF-8 text") from None


def load_scenario(path: str | os.PathLike, *, family: str | None = None) -> Scenario:
    """Load a scenario file; its name defaults to the file stem, its family to ``family`` (by
    default the folder's name) when the YAML has no ``family:``."""
    p = Path(path)
    src = os.fspath(path)
    limit = int(SCENARIO_LIMITS["max_file_bytes"])
    try:
        # O_NONBLOCK: opening a named pipe (a FIFO named like a scenario) would wait for a writer forever
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
        with open(fd, "rb") as fh:
            info = os.fstat(fh.fileno())
            if stat.S_ISDIR(info.st_mode):
                raise IsADirectoryError(src)
            if not stat.S_ISREG(info.st_mode):
                raise ScenarioError("is not a regular file (a named pipe, socket or device)", path=src,
                                    hint="pass the scenario's .yaml file itself")
            size = info.st_size   # read(limit + 1) alone would allocate 5 MB per file
            data = fh.read(size + 1 if 0 < size <= limit else limit + 1)
    except FileNotFoundError:
        raise ScenarioError("no such scenario file", path=src, hint="check the path and the file name") from None
    except IsADirectoryError:
        raise ScenarioError("is a directory, not a scenario file", path=src,
                            hint="pass a .yaml file inside it") from None
    except OSError as exc:
        raise ScenarioError(f"cannot read the file: {exc.strerror or exc}", path=src) from None
    if p.is_dir():  # pragma: no cover - some platforms open directories
        raise ScenarioError("is a directory, not a scenario file", path=src, hint="pass a .yaml file inside it")
    if len(data) > limit:
        raise ScenarioError(f"the file is larger than the limit of {limit} bytes", path=src,
                            hint="scenario files are small; is this the right file?")
    text = _decode(data, src)
    return loads_scenario(text, src, name=p.stem, family=p.absolute().parent.name if family is None else family)


def resolve_path(scenario: Scenario, relative: str | os.PathLike) -> Path:
    """A path written in a scenario (reference file, bag, map), resolved against the scenario's folder."""
    rel = Path(relative)
    if rel.is_absolute() or not scenario.source:
        return rel
    return Path(scenario.source).parent / rel


def looks_like_scenario(text_or_mapping: str | bytes | Mapping[str, Any]) -> bool:
    """Cheap test (no YAML parsing) whether a text or mapping is meant to be a scenario: a top-level
    ``version`` key and a ``mission`` key, or a near miss such as ``mision`` or ``obstacles``, so a
    scenario with a typo is collected and reported instead of silently skipped."""
    if isinstance(text_or_mapping, Mapping):
        keys = {str(k) for k in text_or_mapping}
    else:
        text = text_or_mapping
        if isinstance(text, (bytes, bytearray)):
            head = bytes(text[:1_000_000])
            text = head.decode(text_codec(head), errors="replace")
        if not isinstance(text, str):
            return False
        keys = set(_TOP_KEY.findall(text))
    if "version" not in keys:
        return False
    return bool(keys & {"mission", "obstacles", "robot"}) or bool(
        difflib.get_close_matches("mission", [k.lower() for k in keys], n=1, cutoff=0.75))


_TOP_KEY = re.compile(r"^(?:---[ \t]*\n)?[\"']?([A-Za-z_][\w-]*)[\"']?[ \t]*:", re.M)


# --------------------------------------------------------------------------- dumping




def field_line(source: str | os.PathLike | None, field: str) -> int | None:
    """The line of a dotted field (``robot.body.file``) in the scenario file ``source``, for an
    error found after loading (at run time); None when the file or the field is not there."""
    if not source:
        return None
    try:
        text = _decode(Path(source).read_bytes()[:int(SCENARIO_LIMITS["max_file_bytes"])], os.fspath(source))
        node = parse_yaml(text, os.fspath(source), max_depth=int(SCENARIO_LIMITS["max_depth"]),
                          max_nodes=int(SCENARIO_LIMITS["max_nodes"]))
    except (OSError, ScenarioError):
        return None
    line = None
    for key in field.split("."):
        if not isinstance(node, YMap) or key not in node.items:
            break
        key_line, node = node.items[key]
        line = key_line or node.line
    return line
