"""``navscenario import``: other tools' worlds as scenarios.

* ``navscenario import aerialist test.yaml -o s.yaml``: an Aerialist test definition: its
  obstacles, and start, goal and waypoints from the QGroundControl mission file beside it
  (see ``aerialist.py``); every key not carried over is listed with its file and line.
* ``navscenario import sdf world.world --start x,y,yaw --goal x,y,yaw -o s.yaml``: a Gazebo SDF
  world. The box, cylinder, polyline (a polygon obstacle) and mesh (STL/OBJ found beside the world,
  copied beside the seed) collision geometry of static models becomes obstacles, with the model,
  link and collision poses composed (a world ``<state>`` pose overrides the model's, as Gazebo does
  on load). A model with plugins (compiled code that may move it: DynaBARN's obstacles) is left
  out, said once, and given back moving with ``--plugin-motion`` (``plugin_motion.py``). Planes
  are ignored; everything else (other meshes,
  spheres, includes, tilted shapes, non-static models without plugins) is listed in a warning,
  never dropped silently. A ``<heightmap>`` (a PNG) becomes heightfield terrain, its image copied
  beside the seed (``sdf_terrain.py``); the robot then needs a body that rides the ground. A file
  that is not quite well-formed XML but that Gazebo reads anyway (a bare ``&``, more after
  ``</sdf>``) is repaired and read, with a warning saying what was repaired.

Also home of ``write_seed``, which every importer uses to write its scenario file.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import os
import re
import sys
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

from ..core.errors import NavScenarioError
from ..core.files import usual_mode
from .aerialist import aerialist_obstacles, mission_from_plan, read_aerialist  # noqa: F401 (re-exported)
from ..scenario.model import BoxObstacle, CylinderObstacle, Mission, Obstacle, Pose, Scenario
from .plugin_motion import compiled_plugins, given_motion, left_out_warning, movers_in_walls
from .robot_options import add_robot_arguments, mission_timeout, robot_from_args


class WorldImportError(NavScenarioError):
    """An external world file cannot be imported (not the format, missing field, bad value)."""


# ------------------------------------------------------------------ writing seeds

def write_seed(scenario: Scenario, out: str | Path, *, extra_files: dict[str, str | bytes] | None = None,
               force: bool = False) -> Path:
    """Write ``scenario`` as YAML at ``out`` (plus ``extra_files``: name -> text or bytes, beside it,
    e.g. the mesh files its mesh obstacles name).

    Every file is written to a temporary name first and renamed only when all are complete,
    so a failure leaves no partial output. Refuses to replace an existing file unless ``force``.
    """
    from ..core.errors import ScenarioError
    from ..scenario.loader import loads_scenario
    from ..scenario.dump import dump_scenario

    out = Path(out)
    targets = {out: None, **{out.parent / name: text for name, text in (extra_files or {}).items()}}
    if not force:
        existing = [str(p) for p in targets if p.exists()]
        if existing:
            raise WorldImportError(f"{', '.join(existing)}: already exists; choose another -o or pass --force")
    if not scenario.name:
        import dataclasses
        scenario = dataclasses.replace(scenario, name=out.stem)
    text = dump_scenario(scenario)
    try:   # what a user will load must load: catch it here, before writing (meshes beside it)
        with tempfile.TemporaryDirectory() as tmp:
            for name, data in (extra_files or {}).items():
                (Path(tmp) / name).parent.mkdir(parents=True, exist_ok=True)
                (Path(tmp) / name).write_bytes(data if isinstance(data, bytes) else data.encode("utf-8"))
            loads_scenario(text, source=Path(tmp) / out.name)
    except ScenarioError as exc:   # named by the user's file and field, not the temporary copy checked
        exc.path, exc.line = None, None
        raise WorldImportError(f"{out}: not written, the imported scenario is invalid: {exc.format()}") from None
    from ..scenario.modeline import ensure_project_schema, with_modeline
    targets[out] = with_modeline(text, out)     # the schema for editors (a comment: same scenario)
    out.parent.mkdir(parents=True, exist_ok=True)
    staged: list[tuple[str, Path]] = []
    try:
        for path, text in targets.items():
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
            staged.append((tmp, path))
            os.fchmod(fd, usual_mode())     # mkstemp makes 0600: a seed is an ordinary file
            with os.fdopen(fd, "wb") as fh:
                fh.write(text if isinstance(text, bytes) else text.encode("utf-8"))
        for tmp, path in staged:
            os.replace(tmp, path)
    finally:
        for tmp, _ in staged:
            if os.path.exists(tmp):
                os.unlink(tmp)
    ensure_project_schema(out)
    return out


def parse_pose(text: str, option: str) -> Pose:
    """``x,y,yaw`` (metres, metres, degrees) -> Pose, with an error naming the option."""
    try:
        parts = [float(v) for v in text.split(",")]
    except ValueError:
        parts = []
    if len(parts) not in (2, 3) or not all(math.isfinite(v) for v in parts):
        raise WorldImportError(f"{option} {text!r}: expected x,y,yaw (metres, metres, degrees), e.g. {option} 0,0,90")
    return Pose(parts[0], parts[1], parts[2] if len(parts) == 3 else 0.0)


def _num(v: float, nd: int = 4) -> float:
    return float(round(float(v), nd)) + 0.0


# ------------------------------------------------------------------ SDF

@dataclass
class SdfWorld:
    obstacles: list[Obstacle]
    warnings: list[str] = field(default_factory=list)
    ignored_planes: int = 0
    names: set[str] = field(default_factory=set)
    notes: list[str] = field(default_factory=list)          # imported, but not all of it (said how)
    meshes: dict[str, bytes] = field(default_factory=dict)   # files to write beside the seed
    roots: tuple[Path, ...] = ()                              # folders meshes may come from
    terrain: list = field(default_factory=list)              # <heightmap>s as heightfields (sdf_terrain.py)
    # models that compiled plugins move, left out (plugin_motion.py): name -> (libraries, their obstacles)
    plugin_moved: dict = field(default_factory=dict)
    missing_heightmaps: list[str] = field(default_factory=list)   # their warnings: the CLI fails on them


def _pose6(elem: ET.Element | None, where: str, path: Path) -> tuple[float, ...]:
    if elem is None or not (elem.text or "").strip():
        return (0.0,) * 6
    try:
        vals = [float(v) for v in elem.text.split()]
    except ValueError:
        vals = []
    if elem.get("rotation_format", "euler_rpy") != "euler_rpy":
        raise WorldImportError(f"{path}: {where}: <pose rotation_format={elem.get('rotation_format')!r}> is not "
                               f"supported; write the rotation as 'x y z roll pitch yaw'")
    if len(vals) != 6:
        raise WorldImportError(f"{path}: {where}: <pose> must hold 6 numbers 'x y z roll pitch yaw', got {elem.text.strip()!r}")
    if (elem.get("degrees") or "").strip().lower() in ("true", "1"):  # SDF 1.9: angles in degrees
        vals[3:] = [math.radians(v) for v in vals[3:]]
    return tuple(vals)


def _compose(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, ...]:
    """Planar composition of a then b (x, y, z, roll, pitch, yaw); roll/pitch just add up and
    are only used to detect tilted geometry."""
    c, s = math.cos(a[5]), math.sin(a[5])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2],
            a[3] + b[3], a[4] + b[4], a[5] + b[5])


def _floats(elem: ET.Element | None, n: int, where: str, path: Path) -> list[float]:
    try:
        vals = [float(v) for v in (elem.text or "").split()] if elem is not None else []
    except ValueError:
        vals = []
    if len(vals) != n:
        raise WorldImportError(f"{path}: {where}: expected {n} number(s), got {None if elem is None else elem.text!r}")
    return vals


def sdf_obstacles(path: str | Path, model_path: tuple[str | Path, ...] = ()) -> SdfWorld:
    """Box, cylinder, polyline and mesh collisions of the static models of an SDF world (see
    module docstring). ``model_path``: folders besides the world's own where ``model://`` and
    ``file://`` meshes may be found (like GAZEBO_MODEL_PATH); a mesh elsewhere is an error."""
    path = Path(path)
    recovered: list[str] = []
    try:
        root = ET.parse(path).getroot()
    except FileNotFoundError:
        raise WorldImportError(f"{path}: no such file") from None
    except ET.ParseError as exc:
        root, recovered = _recover(path, exc)
    except OSError as exc:
        raise WorldImportError(f"{path}: cannot read: {exc}") from None
    world = root.find("world") if root.tag == "sdf" else None
    if world is None:
        found = f"<{root.tag}>" + (f" with <{'>, <'.join(sorted({c.tag for c in root}))}> in it" if len(root) else "")
        raise WorldImportError(f"{path}: not an SDF world: expected <sdf><world>..., found {found}"
                               + (f" (even after repairing its XML: {len(recovered)} repair(s), the first at line "
                                  f"{recovered[0]})" if recovered else ""))
    state = world.find("state")
    state_poses = {m.get("name"): m.find("pose") for m in (state.findall("model") if state is not None else [])}
    out = SdfWorld(obstacles=[])
    out.roots = (path.parent.resolve(), *(Path(p).resolve() for p in model_path))
    out.warnings.extend(recovered)
    for inc in world.findall("include"):
        uri = (inc.findtext("uri") or "?").strip()
        out.warnings.append(f"<include> {uri}: included models are not resolved (not imported)")
    for tag in ("actor", "population"):
        for elem in world.findall(tag):
            out.warnings.append(f"<{tag}> {elem.get('name', '?')}: moving or generated models are not "
                                f"supported (not imported)")
    tilt = math.radians(1.0)
    for model in world.findall("model"):
        libs = compiled_plugins(model)
        before, said = len(out.obstacles), len(out.warnings)
        _model(path, model, (0.0,) * 6, state_poses, out, tilt, top=True)
        if libs:     # moved by compiled code: left out, said once for all (plugin_motion.py)
            out.plugin_moved[model.get("name", "?")] = (libs, out.obstacles[before:])
            out.obstacles = out.obstacles[:before]
            out.warnings = out.warnings[:said] + [w for w in out.warnings[said:] if " plugin(s) " not in w]
    if out.plugin_moved:
        out.warnings.append(left_out_warning(out.plugin_moved))
    _one_of_each_pile(out)
    return out


# where lxml's recovery gives up (a truncated file, mismatched tags): Gazebo refuses those too
_FATAL = {"ERR_TAG_NOT_FINISHED", "ERR_TAG_NAME_MISMATCH", "ERR_DOCUMENT_EMPTY", "ERR_DOCUMENT_END_OF_DATA",
          "ERR_LTSLASH_REQUIRED", "ERR_GT_REQUIRED"}


def _recover(path: Path, error: ET.ParseError) -> tuple[ET.Element, list[str]]:
    """Gazebo classic reads world files with TinyXML, which forgives slips a strict XML parser
    refuses (unquoted or empty attribute values, ``<pose frame=>``, a bare ``&``, stray characters,
    more after the root element). libxml2's recovering parser (lxml) reads past them the same way;
    each repair is returned as a warning with its line. A truncated file or mismatched tags, which
    Gazebo refuses too, stay an error naming the line."""
    from lxml import etree

    parser = etree.XMLParser(recover=True, remove_comments=True, remove_pis=True, resolve_entities=False,
                             no_network=True)
    try:
        tree = etree.parse(str(path), parser)
    except (OSError, etree.XMLSyntaxError) as exc:
        raise WorldImportError(f"{path}:{error.position[0]}: not an SDF world: not well-formed XML ({error}; "
                               f"not readable even by a recovering parser: {exc})") from None
    errors = list(parser.error_log)
    fatal = [e for e in errors if e.type_name in _FATAL]
    root = tree.getroot() if tree is not None else None
    if fatal or root is None:
        first = fatal[0] if fatal else None
        line = first.line if first is not None else error.position[0]
        raise WorldImportError(f"{path}:{line}: not an SDF world: not well-formed XML ("
                               f"{first.message.strip() if first is not None else error}); Gazebo refuses it too")
    repairs = [f"{e.line}: not well-formed XML ({e.message.strip()}): repaired and read as Gazebo would; check "
               f"what was imported from there" for e in errors]
    return _plain_tree(root), repairs or [f"{error.position[0]}: not well-formed XML ({error}): repaired"]


def _plain_tree(elem) -> ET.Element:
    """An lxml element (and its children) as a plain ElementTree element."""
    out = ET.Element(str(elem.tag), {str(k): str(v) for k, v in elem.attrib.items()})
    out.text, out.tail = elem.text, elem.tail
    for child in elem:
        if isinstance(child.tag, str):
            out.append(_plain_tree(child))
    return out


def _one_of_each_pile(out: SdfWorld) -> None:
    """Identical obstacles standing at one spot (dynamic worlds start their moving models in a pile
    for their plugins to spread): kept once, and said so."""
    import dataclasses

    piles: dict[tuple, list[int]] = {}
    for i, o in enumerate(out.obstacles):
        key = (type(o).__name__, dataclasses.astuple(dataclasses.replace(o, name="")))
        piles.setdefault(key, []).append(i)
    drop = set()
    for members in piles.values():
        if len(members) > 1:
            names = [out.obstacles[i].name for i in members]
            o = out.obstacles[members[0]]
            shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
            out.warnings.append(f"identical models, {len(names)} of them, stand at one spot ({o.x:g}, {o.y:g}): {shown}; "
                                f"imported once, as {names[0]} (a dynamic world piles up the models its plugins "
                                f"move: write their motion by hand)")
            drop.update(members[1:])
    if drop:
        gone = {out.obstacles[i].name for i in drop}
        # their plugin warnings are said once, by the pile's
        out.warnings = [w for w in out.warnings if not any(w.startswith(f"model {n}: plugin(s)") for n in gone)]
        out.obstacles = [o for i, o in enumerate(out.obstacles) if i not in drop]


def _model(path: Path, model: ET.Element, parent: tuple[float, ...], state_poses: dict, out: SdfWorld,
           tilt: float, top: bool, moved_by: tuple[str, ...] = ()) -> None:
    mname = model.get("name", "?")
    pose_elem = state_poses.get(mname) if top and state_poses.get(mname) is not None else model.find("pose")
    mpose = _compose(parent, _pose6(pose_elem, f"model {mname}", path))
    static = (model.findtext("static") or "0").strip().lower() in ("1", "true")
    plugins = tuple(f"{p.get('name', '?')} ({p.get('filename', '?')})" for p in model.findall("plugin"))
    moved_by = moved_by + plugins
    if plugins:
        out.warnings.append(f"model {mname}: plugin(s) {', '.join(plugins)} may move or change it: imported "
                            f"where it stands in the world file; what the plugins do is not carried over (write "
                            f"its motion by hand)")
    for inner in model.findall("model"):
        _model(path, inner, mpose, {}, out, tilt, top=False, moved_by=moved_by)
    for inc in model.findall("include"):
        uri = (inc.findtext("uri") or "?").strip()
        out.warnings.append(f"model {mname}: <include> {uri}: included models are not resolved (not imported)")
    for link in model.findall("link"):
        lname = link.get("name", "?")
        lpose = _compose(mpose, _pose6(link.find("pose"), f"model {mname} link {lname}", path))
        for col in link.findall("collision"):
            cname = col.get("name", "?")
            where = f"model {mname} link {lname} collision {cname}"
            geom = col.find("geometry")
            shape = next(iter(geom), None) if geom is not None else None
            if shape is None:
                out.warnings.append(f"{where}: no geometry (not imported)")
                continue
            if shape.tag == "plane":
                out.ignored_planes += 1
                continue
            if not static and not moved_by:
                out.warnings.append(f"{where}: {shape.tag} of a non-static model (not imported)")
                continue
            cpose = _compose(lpose, _pose6(col.find("pose"), where, path))
            if shape.tag == "heightmap":
                from .sdf_terrain import heightmap_terrain
                heightmap_terrain(path, where, shape, cpose, mname if mname not in out.names
                                  else f"{mname}/{lname}/{cname}", lambda w, u: _find_inside(w, u, out.roots, where, "heightmap"),
                                  _floats, out)
                continue
            if shape.tag in ("polyline", "mesh") and not (abs(cpose[3]) > tilt or abs(cpose[4]) > tilt):
                _outlined(path, mname, lname, cname, where, geom, shape, cpose, out)
                continue
            if shape.tag not in ("box", "cylinder"):
                out.warnings.append(f"{where}: {shape.tag} geometry cannot be represented (not imported)")
                continue
            if abs(cpose[3]) > tilt or abs(cpose[4]) > tilt:
                out.warnings.append(f"{where}: {shape.tag} tilted (roll {math.degrees(cpose[3]):.1f}, "
                                    f"pitch {math.degrees(cpose[4]):.1f} deg) cannot be represented (not imported)")
                continue
            name = mname if mname not in out.names else f"{mname}/{lname}/{cname}"
            out.names.add(name)
            if shape.tag == "box":
                sx, sy, sz = _floats(shape.find("size"), 3, f"{where} box size", path)
                out.obstacles.append(BoxObstacle(name=name, x=_num(cpose[0]), y=_num(cpose[1]), length=_num(sx),
                                                 width=_num(sy), yaw=_num(math.degrees(cpose[5]), 3),
                                                 height=_num(sz)))
            else:
                (r,) = _floats(shape.find("radius"), 1, f"{where} cylinder radius", path)
                (length,) = _floats(shape.find("length"), 1, f"{where} cylinder length", path)
                out.obstacles.append(CylinderObstacle(name=name, x=_num(cpose[0]), y=_num(cpose[1]),
                                                      radius=_num(r), height=_num(length)))


def _outlined(path: Path, mname: str, lname: str, cname: str, where: str, geom: ET.Element,
              shape: ET.Element, cpose: tuple[float, ...], out: SdfWorld) -> None:
    """A polyline (one polygon obstacle per <polyline>) or a mesh (an STL/OBJ file found beside the
    world, copied beside the seed) of a collision."""
    from ..scenario.geometry import polygon_problem
    from ..scenario.mesh import MeshError, mesh_outline, read_mesh
    from ..scenario.model import MeshObstacle, PolygonObstacle

    name = mname if mname not in out.names else f"{mname}/{lname}/{cname}"
    x, y, yaw = _num(cpose[0]), _num(cpose[1]), _num(math.degrees(cpose[5]), 3)
    if shape.tag == "polyline":
        for k, line in enumerate(geom.findall("polyline")):
            points = tuple((_num(px), _num(py)) for px, py in
                           (_floats(pt, 2, f"{where} polyline point", path) for pt in line.findall("point")))
            (height,) = _floats(line.find("height"), 1, f"{where} polyline height", path)
            problem = polygon_problem(points)
            if problem is not None:
                out.warnings.append(f"{where}: polyline {k}: {problem} (not imported)")
                continue
            pname = name if k == 0 else f"{name}/{k}"
            out.names.add(pname)
            out.obstacles.append(PolygonObstacle(name=pname, x=x, y=y, yaw=yaw, points=points, height=_num(height)))
        return
    uri = (shape.findtext("uri") or "").strip()
    scale = tuple(_floats(shape.find("scale"), 3, f"{where} mesh scale", path)) if shape.find("scale") is not None \
        else (1.0, 1.0, 1.0)
    found = _find_inside(path, uri, out.roots, where, "mesh")
    if found is None:
        out.warnings.append(f"{where}: mesh {uri or '(no uri)'}: no such file beside the world, looked in "
                            f"{path.parent} and its models/ folder" +
                            (f" and {', '.join(str(r) for r in out.roots[1:])}" if len(out.roots) > 1 else "")
                            + " (not imported)")
        return
    try:
        verts, tris = read_mesh(found)
        outline, height = mesh_outline(verts, tris, scale, found.name)
    except MeshError as exc:
        out.warnings.append(f"{where}: mesh {uri}: {exc} (not imported)")
        return
    rel = f"meshes/{found.stem}{found.suffix.lower()}"
    if rel in out.meshes and out.meshes[rel] != found.read_bytes():
        rel = f"meshes/{found.stem}-{len(out.meshes)}{found.suffix.lower()}"
    out.meshes[rel] = found.read_bytes()
    out.names.add(name)
    out.obstacles.append(MeshObstacle(name=name, x=x, y=y, yaw=yaw, file=rel, scale=scale,
                                      footprint=outline, height=height))


def _find_inside(world: Path, uri: str, roots: tuple[Path, ...], where: str, what: str) -> Path | None:
    """The file of a mesh's or heightmap's ``uri`` (``_find_mesh``), None when there is none;
    WorldImportError when it lies outside the world's folder and the --model-path folders (an
    absolute path, file://, model://../../, ../../, a link out): the scenario loader's own rule, the
    same for every file the import copies."""
    found = _find_mesh(world, uri, roots)
    if found is not None and not any(found.resolve().is_relative_to(r) for r in roots):
        raise WorldImportError(f"{world}: {where}: {what} {uri} is {found.resolve()}, outside the world's folder "
                               f"{world.parent.resolve()}: {what} files are read only from beside the world (the "
                               f"scenario loader's own rule); copy it there, or name its folder with --model-path")
    return found


def _find_mesh(world: Path, uri: str, roots: tuple[Path, ...] = ()) -> Path | None:
    """The file of a mesh ``uri``: file://, a path relative to the world, or model://<model>/<path>
    under the world's folder, its models/ folder or the ``roots`` given (as GAZEBO_MODEL_PATH
    would often have it). Whether it may be read is the caller's check."""
    if not uri:
        return None
    if uri.startswith("file://"):
        candidates = [Path(uri[len("file://"):])]
    elif uri.startswith("model://"):
        rest = uri[len("model://"):]
        candidates = [world.parent / rest, world.parent / "models" / rest] + [r / rest for r in roots[1:]]
    else:
        candidates = [world.parent / uri]
    return next((c for c in candidates if c.is_file()), None)


# ------------------------------------------------------------------ CLI

def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("format", choices=("aerialist", "sdf"), help="aerialist test YAML or Gazebo SDF world")
    p.add_argument("file", metavar="PATH", help="the file to import (test YAML or .world/.sdf)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.yaml", help="scenario YAML to write")
    p.add_argument("--start", default=None, metavar="X,Y,YAW", help="start pose x,y,yaw (m, m, degrees); "
                   "required for sdf; for aerialist, default the home of the mission file (.plan) beside the test, "
                   "else 0,0,90 (the paper's 10 m task)")
    p.add_argument("--goal", default=None, metavar="X,Y,YAW", help="goal pose x,y,yaw (m, m, degrees); required for "
                   "sdf; for aerialist, default the mission file's last position, else 0,10,90")
    add_robot_arguments(p)
    p.add_argument("--model-path", action="append", default=[], metavar="DIR",
                   help="sdf: a folder where model:// meshes may also be found (like GAZEBO_MODEL_PATH; repeat for "
                        "more); meshes are read only from the world's folder and these")
    p.add_argument("--plugin-motion", default=None, metavar="FILE.yaml",
                   help="sdf: the motion of models that compiled Gazebo plugins move (left out otherwise, e.g. "
                        "DynaBARN's obstacles): a YAML mapping of model name to an obstacles[].motion mapping, e.g. "
                        "'easylibobs_66: {path: [[-2, 11], [-2, -11]], speed: 1.2, mode: loop}'")
    p.add_argument("--name", default="", metavar="TEXT", help="scenario name (default: the output file's stem)")
    p.add_argument("--force", action="store_true", help="overwrite an existing output file")


_LINE = re.compile(r"^\d+: ")     # a repair's warning starts with its line number


def run(args: argparse.Namespace) -> int:
    src = Path(args.file)
    notes: list[str] = []
    extra: dict[str, bytes] = {}
    robot, robot_note = robot_from_args(args)
    if args.format == "aerialist":
        obstacles, start, goal, waypoints = _aerialist(args, src, notes)
    else:
        if not args.start or not args.goal:
            raise WorldImportError(f"{src}: an SDF world has no mission: pass --start x,y,yaw and --goal x,y,yaw")
        start, goal = parse_pose(args.start, "--start"), parse_pose(args.goal, "--goal")
        waypoints = ()
        world = sdf_obstacles(src, tuple(args.model_path))
        obstacles = world.obstacles
        if args.plugin_motion:
            moving = given_motion(world.plugin_moved, args.plugin_motion)
            obstacles = obstacles + moving
            left = {n: v for n, v in world.plugin_moved.items() if n not in {o.name for o in moving}}
            said = left_out_warning(world.plugin_moved)
            world.warnings = [w for w in world.warnings if w != said] + ([left_out_warning(left)] if left else [])
            notes.append(f"{len(moving)} plugin-moved model(s) moving as {args.plugin_motion} says: "
                         + ", ".join(o.name for o in moving))
            world.warnings.extend(movers_in_walls(obstacles))
        extra = world.meshes
        notes.extend(world.notes)
        if world.ignored_planes:
            notes.append(f"{world.ignored_planes} plane(s) ignored (the ground)")
        for w in world.warnings:   # a repair starts with its line number: file:line: as editors read it
            print(f"navscenario import: warning: {src}:{w}" if _LINE.match(w) else
                  f"navscenario import: warning: {src}: {w}", file=sys.stderr)
        if world.warnings:
            print(f"navscenario import: warning: {len(world.warnings)} warning(s) about {src} (listed above)",
                  file=sys.stderr)
        if world.missing_heightmaps:   # a flat seed would pass where the world has hills: fail (#36.5)
            raise WorldImportError(f"{src}: heightmap(s) not found: {', '.join(world.missing_heightmaps)}; "
                                   f"nothing written: pass --model-path DIR with the folder that holds them "
                                   f"(a Gazebo models folder, as GAZEBO_MODEL_PATH), or copy them beside the world")
    terrain = tuple(world.terrain) if args.format == "sdf" else ()
    scenario = Scenario(mission=Mission(start=start, goal=goal, waypoints=waypoints),
                        obstacles=tuple(obstacles), robot=robot, name=args.name, terrain=terrain,
                        description=f"Imported from {args.format} file {src.name}.")
    if terrain and scenario.robot.body.kind == "planar":   # the planar body cannot ride terrain: guess
        from ..scenario.bodies import WheeledBody
        scenario = dataclasses.replace(scenario, robot=dataclasses.replace(scenario.robot, body=WheeledBody(),
                                                                           drive="diff"))
        notes.append("robot.body: wheeled, drive: diff (a guess: the world does not say which robot drives it; "
                     "set robot.body)")
        robot_note = robot_note.replace(f", {robot.drive} drive,", ", diff drive,")   # what the seed has
    if terrain:          # the route's length reads the heightfields: from their files, staged as beside the seed
        with tempfile.TemporaryDirectory() as tmp:
            for name, data in extra.items():
                (Path(tmp) / name).parent.mkdir(parents=True, exist_ok=True)
                (Path(tmp) / name).write_bytes(data if isinstance(data, bytes) else data.encode("utf-8"))
            staged = dataclasses.replace(scenario, source=str(Path(tmp) / Path(args.output).name))
            timeout, timeout_note = mission_timeout(staged, args.timeout)
    else:
        timeout, timeout_note = mission_timeout(scenario, args.timeout)
    scenario = dataclasses.replace(scenario, mission=dataclasses.replace(scenario.mission, timeout=timeout))
    write_seed(scenario, args.output, force=args.force, extra_files=extra)
    for note in [*notes, robot_note, timeout_note]:
        print(f"navscenario import: {note}")
    print(f"navscenario import: {len(obstacles)} obstacle(s)"
          + (f", {len(terrain)} terrain element(s)" if terrain else "") + f" -> wrote {args.output}")
    return 0


def _aerialist(args: argparse.Namespace, src: Path, notes: list[str]):
    """Obstacles, start, goal and waypoints of an Aerialist test: the plan beside it gives the
    mission unless --start/--goal are given; what is not carried over is warned about by line."""
    from .qgc_plan import local_xy, read_plan

    test = read_aerialist(src)
    for line in test.dropped:
        print(f"navscenario import: warning: {line}", file=sys.stderr)
    if test.dropped:
        print(f"navscenario import: warning: {len(test.dropped)} key(s) of {src} not carried over "
              f"(listed above)", file=sys.stderr)
    mission = None
    if test.mission_file is not None and not (args.start and args.goal):
        plan = read_plan(test.mission_file)
        notes.extend(plan.notes)
        lat, lon, _ = plan.home
        home = (0.0, 0.0)
        if test.home_position is not None:
            home = local_xy(*test.home_position, lat, lon)
            notes.append(f"start from simulation.home_position ({test.home_key.split(': ')[0]}): "
                         f"x={home[0]:.2f}, y={home[1]:.2f} from the plan's home")
        mission = mission_from_plan(plan.points, start=home)
        if mission is None:
            notes.append(f"{test.mission_file.name}: the mission has no position away from its home")
        else:
            notes.append(f"start, {len(mission[2])} waypoint(s) and goal from {test.mission_file} "
                         f"(home {lat:.7f}, {lon:.7f} is x=0, y=0; x east, y north, metres)")
    if test.home_position is not None and mission is None and not (args.start and args.goal):
        print(f"navscenario import: warning: {test.home_key}: not carried over (a geographic position, and no "
              f"mission plan to place it against)", file=sys.stderr)
    if test.mission_key and test.mission_file is None:
        print(f"navscenario import: warning: {test.mission_key}: the mission file is not beside the test "
              f"(looked for it relative to {src.parent} and by its name there): using a default mission",
              file=sys.stderr)
    if mission is not None:
        start, goal, waypoints = mission
    else:
        start, goal, waypoints = parse_pose("0,0,90", "--start"), parse_pose("0,10,90", "--goal"), ()
    if args.start or args.goal:
        start = parse_pose(args.start, "--start") if args.start else start
        goal = parse_pose(args.goal, "--goal") if args.goal else goal
        waypoints = () if (args.start and args.goal) else waypoints
    elif mission is None:
        notes.append("Aerialist missions are drone flight plans: using start/goal "
                     f"{start.x},{start.y} -> {goal.x},{goal.y} (set --start/--goal)")
    return list(test.obstacles), start, goal, waypoints
