"""The user's own body: their MJCF robot (one from MuJoCo Menagerie, say) driven by a controller of
theirs, riding the terrain like the wheeled body.

The model. ``robot.body.file`` (beside the scenario: the mesh path rules) is read by MuJoCo; its
base (``robot.body.base``, else the first body with a free joint) and everything below it are
attached to the scenario's world with their names, defaults, actuators, tendons and sensors kept;
the rest of the file's world (its floor, lights, other bodies) is not used; of its ``<option>``, the
contact ones (``ROBOT_OPTIONS``: cone, impratio, noslip) are kept for the whole world, the scenario's
timestep, gravity, integrator and the rest rule. The robot's geoms are put in geom group 5 (the lidars skip the robot's own geoms) and keep
their contact bits among themselves; each that would meet a default MuJoCo floor (contype 1,
conaffinity 1: MuJoCo Menagerie's robots have contype 0, conaffinity 1) meets the scenario's ground
and obstacles, through a bit of its own (``_world_bit``). A contact of any of them with an obstacle is a
collision, a contact of the base's own geoms with a terrain face is a collision with the terrain
(wheels and feet, on bodies below the base, meet the ground freely).

The pose. The robot starts resting on the ground at the start pose: its base is placed so that
its lowest colliding geom (at the model's reference pose) is 2 mm above the ground, and
``ground_offset`` (the base's height above the ground there) is taken off the base's z in the
state, the trajectory and the lidars' mounting height, so they mean what they mean for the other
bodies.

The controller. ``robot.body.controller`` is ``package.module:Attribute`` (looked up as subjects
are: sys.path, then the current folder and the scenario's folder), a class or zero-argument
factory function of the user's own code (core/user_code.own_code: not a builtin, the standard
library's or an installed package's); one instance per episode. It may have ``reset(model, data)``, called once the robot is
placed; it must have ``control(command, model, data)``, called every control tick with the
planner's command (vx, vy, wz: m/s and rad/s in the robot frame, after the drive's limits); it
returns the actuator controls (``model.nu`` numbers) or None when it wrote ``data.ctrl`` itself.
Loops faster than the control rate belong in MuJoCo's own actuators (velocity or position servos).
``control()`` runs under the episode's tick limit; whatever goes wrong in the controller is a
BodyControllerError, which the episode turns into a subject error (sim/episode.RidingEpisode).
"""
from __future__ import annotations

import math
import os
import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from ...core.errors import NavScenarioError, ScenarioError, SubjectLoadError
from ...core.interrupts import from_the_user
from .base import ROBOT_GROUP, FreeBase

START_GAP = 0.002   # m between the lowest geom and the ground at the start
EMPTY_PREFIX = "Attaching a spec with an empty prefix"


@contextmanager
def kept_names():
    """Attach, compile or save a spec holding the user's robot attached without a prefix (so their
    controller finds its actuators by their own names) without MuJoCo's warning that an empty
    prefix "may prevent the model from being saved correctly": names are unique (MuJoCo refuses a
    clash when compiling), and the model saves (``body_world.model_xml``, tested)."""
    handler = mujoco.get_mju_user_warning()

    def forward(message: str) -> None:
        if EMPTY_PREFIX not in message and handler is not None:
            handler(message)

    mujoco.set_mju_user_warning(forward)
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=EMPTY_PREFIX)
            yield
    finally:
        mujoco.set_mju_user_warning(handler)


class BodyControllerError(NavScenarioError):
    """The user's body controller raised, or answered something that is not actuator controls."""


def mjcf_path(scenario) -> Path:
    """The MJCF file of the scenario's body (the loader has checked the path rules)."""
    folder = Path(scenario.source).parent if scenario.source else Path.cwd()
    return (folder / scenario.robot.body.file).resolve()


def _fail(scenario, message: str, field: str, hint: str | None) -> ScenarioError:
    from ...scenario.loader import field_line
    return ScenarioError(message, path=scenario.source, line=field_line(scenario.source, field),
                         field=field, hint=hint)


def read_robot(scenario) -> tuple[mujoco.MjSpec, str]:
    """(the MJCF's spec, its base body's name): ScenarioError with MuJoCo's own message and the
    file when it does not load or compile, or has no free base."""
    path = mjcf_path(scenario)
    field = "robot.body.file"
    _same_files(scenario, path)
    try:
        child = mujoco.MjSpec.from_file(os.fspath(path))
        child.compile()
    except Exception as exc:   # MuJoCo raises ValueError with its parser's or compiler's message
        raise _fail(scenario, f"MuJoCo cannot load {path}: {str(exc).strip()}", field,
                    "fix the MJCF file (it must load in MuJoCo on its own)") from None
    wanted = scenario.robot.body.base
    free = [b.name for b in child.bodies if any(j.type == mujoco.mjtJoint.mjJNT_FREE for j in b.joints)]
    if wanted is not None:
        body = child.body(wanted)
        if body is None:
            names = ", ".join(b.name for b in child.bodies if b.name and b.name != "world")
            raise _fail(scenario, f"{path} has no body named {wanted!r} (it has: {names})", "robot.body.base",
                        "name the robot's base body, or leave base out for the first body with a free joint")
        if wanted not in free:
            raise _fail(scenario, f"body {wanted!r} of {path} has no free joint: it cannot be the robot's base",
                        "robot.body.base", "give the base a <freejoint/>, or name the body that has one")
        return child, wanted
    if not free:
        raise _fail(scenario, f"{path} has no body with a free joint (a free base): the robot must move freely",
                    field, "give the robot's base body a <freejoint/>")
    return child, free[0]


def _same_files(scenario, path: Path) -> None:
    """The robot's files checked again just before MuJoCo opens them (scenario/mjcf_files.py: inside
    the scenario's folder, regular files) and hashed: ScenarioError when they changed since the
    scenario was loaded, so an edited MJCF or included file never runs under the old content hash."""
    from ...scenario.mjcf_files import MjcfFileError, robot_digest

    folder = Path(scenario.source).parent if scenario.source else Path.cwd()
    field, fix = "robot.body.file", "keep the robot's files in the scenario's folder, named by relative paths"
    try:
        now = robot_digest(path, folder)
    except (MjcfFileError, OSError) as exc:
        raise _fail(scenario, str(exc), field, fix) from None
    loaded = scenario.robot.body.digest
    if loaded and now != loaded:
        raise _fail(scenario, f"{path} or a file it names changed after the scenario was loaded (content "
                              f"{loaded}, now {now}): its results would carry the old content hash", field,
                    "load the scenario again (run it again) once the robot's files are as you want them")


def load_controller(scenario) -> Any:
    """The controller factory ``robot.body.controller`` names (ScenarioError when it cannot be had)."""
    from ...core.user_code import load_object, own_code

    spec = scenario.robot.body.controller
    project = [os.getcwd()]
    if scenario.source and Path(scenario.source).resolve().parent != Path.cwd().resolve():
        project.append(os.fspath(Path(scenario.source).resolve().parent))
    try:
        return own_code(load_object(spec, what="body controller", project=project), spec,
                        what="body controller")
    except SubjectLoadError as exc:
        raise _fail(scenario, str(exc), "robot.body.controller", None) from None


# The file's <option> attributes that concern the robot's contacts (friction cone, impedance
# ratio, no-slip passes): kept, since a legged robot tuned with them sags without them (issue #36).
ROBOT_OPTIONS = ("cone", "impratio", "noslip_iterations", "noslip_tolerance")


class MjcfModel(FreeBase):
    """A ``MjcfBody`` in MuJoCo (see the module docstring)."""

    def __init__(self, scenario):
        super().__init__(scenario)
        self.child, self.base_name = read_robot(scenario)
        self.factory = load_controller(scenario)
        self.ground_offset = _ground_offset(self.child, self.base_name)
        self.contact_sensor = (mujoco.mjtObj.mjOBJ_XBODY, self.base_name)   # the whole robot's contacts

    def build(self, spec: mujoco.MjSpec) -> None:
        child = self.child.copy()
        child.modelname = f"{spec.modelname}:robot"        # no attach conflict with the scenario's name
        for name in ROBOT_OPTIONS:               # the file's contact options rule the world (#36)
            setattr(spec.option, name, getattr(self.child.option, name))
        for name in dir(spec.option):            # then the world's options in the child: no attach conflict
            if not name.startswith("_"):
                setattr(child.option, name, getattr(spec.option, name))
        if self.child.memory > spec.memory:      # the file's <size memory> (attach would drop it)
            spec.memory = self.child.memory
        base = child.body(self.base_name)
        robot = _subtree_geoms(base)
        meets_world = _world_bit(robot)
        if not meets_world:
            raise _fail(self.scenario, f"the geoms of {mjcf_path(self.scenario)} use every collision bit from 16 "
                                       f"up: the scenario's world needs one", "robot.body.file",
                        "leave one contype/conaffinity bit from 16 up unused")
        for geom in spec.geoms:                  # the terrain and the obstacles, before the robot comes
            if geom.contype or geom.conaffinity:
                geom.contype |= meets_world
        for geom in robot:
            geom.group = ROBOT_GROUP
            if (geom.contype | geom.conaffinity) & 1:      # it would meet a default floor (1, 1)
                geom.conaffinity |= meets_world
        base.pos = [0.0, 0.0, 0.0]
        base.quat = [1.0, 0.0, 0.0, 0.0]
        frame = spec.worldbody.add_frame()
        with kept_names():
            frame.attach_body(base, "", "")     # the user's names kept: their controller uses them

    def bind(self, model: mujoco.MjModel) -> None:
        self.base_body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, self.base_name)
        joint = next(j for j in range(model.body_jntadr[self.base_body],
                                      model.body_jntadr[self.base_body] + model.body_jntnum[self.base_body])
                     if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE)
        self.qadr = int(model.jnt_qposadr[joint])
        self.vadr = int(model.jnt_dofadr[joint])
        subtree = {b for b in range(model.nbody) if _under(model, b, self.base_body)}
        self.robot_geoms = frozenset(g for g in range(model.ngeom) if model.geom_bodyid[g] in subtree)
        rigid = {b for b in subtree if _welded(model, b, self.base_body)}
        self.chassis_geoms = frozenset(g for g in self.robot_geoms if model.geom_bodyid[g] in rigid)
        self.model = model

    def start_height(self, ground_z: float) -> float:
        return ground_z + self.ground_offset + START_GAP

    def begin(self, d: mujoco.MjData) -> "MjcfControl":
        return MjcfControl(self, d)

    def command(self, ctrl, setpoint, state=None) -> None:   # pragma: no cover - the controller commands
        raise RuntimeError("an MJCF body is commanded through its controller (begin)")


class MjcfControl:
    """One episode's controller instance and the model and data it drives."""

    def __init__(self, body: MjcfModel, d: mujoco.MjData):
        self.body, self.model, self.data = body, body.model, d
        spec = body.scenario.robot.body.controller
        self.spec = spec
        self.controller = _call(spec, body.factory, when=" when made or reset")
        reset = getattr(self.controller, "reset", None)
        if reset is not None:
            _call(spec, reset, self.model, d, when=" when made or reset")
        self.control = getattr(self.controller, "control", None)
        if self.control is None:
            raise BodyControllerError(f"body controller {spec!r} has no control(command, model, data) method")

    deadline = None    # the episode's TickDeadline (sim/deadline.py): control() is bounded like act()

    def command(self, ctrl: np.ndarray, setpoint: tuple[float, float, float], state: Any) -> None:
        out = _call(self.spec, self.control, setpoint, self.model, self.data, deadline=self.deadline)
        if out is None:
            return
        try:
            values = np.asarray(out, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            text = repr(out) if len(repr(out)) <= 60 else repr(out)[:57] + "..."
            raise BodyControllerError(
                f"body controller {self.spec!r} returned {text} (a {type(out).__name__}): return model.nu "
                f"finite numbers (a list or array), or None after writing data.ctrl") from None
        if values.shape != ctrl.shape or not np.isfinite(values).all():
            raise BodyControllerError(
                f"body controller {self.spec!r} returned {values.size} controls "
                f"({'not all finite' if values.shape == ctrl.shape else f'the model has {ctrl.size} actuators'}): "
                f"return model.nu finite numbers, or None after writing data.ctrl")
        ctrl[:] = values


def _call(spec: str, fn: Any, *args: Any, when: str = "", deadline: Any = None) -> Any:
    """Call the user's controller code: whatever it raises, ``sys.exit()`` and its own
    ``KeyboardInterrupt`` included, is a BodyControllerError that ends the episode, not the run (as
    for planners: ``sim/command.call_planner``); a user's Ctrl-C passes. Under ``deadline`` (the
    episode's per-tick limit) a call that overruns is a BodyControllerError too."""
    from ..deadline import PlannerTimeout
    try:
        if deadline is None:
            return fn(*args)
        deadline.arm()
        try:
            out = fn(*args)
        except BaseException:
            try:
                deadline.disarm()
            except PlannerTimeout:
                pass
            raise
        deadline.disarm()
        return out
    except PlannerTimeout as exc:
        raise BodyControllerError(f"body controller {spec!r}: {str(exc).replace('planner', 'control()')} "
                                  f"(--nav-tick-limit bounds the controller's tick as the planner's)") from None
    except (SystemExit, KeyboardInterrupt, GeneratorExit) as exc:
        if from_the_user(exc):
            raise
        raise BodyControllerError(f"body controller {spec!r} raised {type(exc).__name__}: {exc}{when} "
                                  f"(a controller ends its episode, not the test run)") from exc
    except Exception as exc:
        raise BodyControllerError(f"body controller {spec!r} raised {type(exc).__name__}: {exc}{when}") from exc


def _world_bit(robot_geoms: list) -> int:
    """A collision bit that none of the robot's geoms uses and the world's scheme (sim/ground/terrain.py:
    1, 2, 4, 8) does not either: the world's geoms get it in ``contype``, each robot geom that
    would meet a default MuJoCo floor (contype 1, conaffinity 1) in ``conaffinity``. So the robot
    meets the ground and the obstacles whatever its own bits (MuJoCo Menagerie's robots have
    contype 0, conaffinity 1: they meet their scene's floor but not themselves), and its own
    geoms meet each other exactly as in its file."""
    used = 0
    for geom in robot_geoms:
        used |= int(geom.contype) | int(geom.conaffinity)
    return next((1 << bit for bit in range(4, 31) if not used & (1 << bit)), 0)


def _subtree_geoms(body: Any) -> list:
    out = list(body.geoms)
    for child in body.bodies:
        out += _subtree_geoms(child)
    return out


def _under(model: mujoco.MjModel, b: int, root: int) -> bool:
    while b > 0:
        if b == root:
            return True
        b = int(model.body_parentid[b])
    return False


def _welded(model: mujoco.MjModel, b: int, root: int) -> bool:
    """``b`` is ``root`` or fixed to it (no joint between them): part of the chassis, as a bumper or
    a sensor mast of the base's own; wheels, casters and legs hang on joints."""
    while b != root:
        if model.body_jntnum[b] or b <= 0:
            return False
        b = int(model.body_parentid[b])
    return True


def _ground_offset(child: mujoco.MjSpec, base_name: str) -> float:
    """The base's height above the lowest point of the robot's colliding geoms, at the model's
    reference pose with the base level at the origin."""
    spec = child.copy()
    base = spec.body(base_name)
    base.pos, base.quat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
    model = spec.compile()
    d = mujoco.MjData(model)
    mujoco.mj_kinematics(model, d)
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, base_name)
    lowest = math.inf
    for g in range(model.ngeom):
        if not _under(model, int(model.geom_bodyid[g]), root):
            continue
        if model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0:
            continue        # visual only
        lowest = min(lowest, _lowest_point(model, d, g))
    base_z = float(d.xpos[root][2])
    return 0.0 if not math.isfinite(lowest) else base_z - lowest


def _lowest_point(model: mujoco.MjModel, d: mujoco.MjData, g: int) -> float:
    """The lowest z of geom ``g`` (exact for spheres, capsules, boxes, cylinders; a mesh or other
    shape by its bounding box)."""
    z, rot, size = float(d.geom_xpos[g][2]), d.geom_xmat[g].reshape(3, 3), model.geom_size[g]
    kind = model.geom_type[g]
    r2 = rot[2]                    # how each geom axis projects on world z
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return z - size[0]
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return z - abs(r2[2]) * size[1] - size[0]
    if kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return z - abs(r2[2]) * size[1] - size[0] * math.sqrt(max(0.0, 1.0 - r2[2] ** 2))
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        return z - float(np.abs(r2) @ size)
    centre, half = model.geom_aabb[g][:3], model.geom_aabb[g][3:]
    return z + float(r2 @ centre) - float(np.abs(r2) @ half)
