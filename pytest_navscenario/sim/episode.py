"""The MuJoCo simulation of one episode: the only module that imports mujoco.

The robot is a rigid body on planar joints (slide-x, slide-y, hinge-yaw) with gravity off, driven by
three velocity actuators attached to a site at its centre, so commands act in the robot frame and the
motion has inertia and tracking lag (time constant ``TRACKING_TAU``, force limited). Obstacles are
static world geoms named after the scenario's obstacles. Only robot-obstacle pairs can collide.

``simulate(scenario, planner, seed)`` runs the control loop and returns the raw facts (trajectory,
collision, safety stop, planner failure, goal reached, timings); ``runner.run_scenario`` turns them
into an outcome and metrics. Per control tick: goal/waypoint check, lidar (one ``mj_multiRay``), safety
layer, planner, command validation and limits; then the physics steps one at a time with a contact
check after every step.
"""
from __future__ import annotations

import logging
import math
import time
import traceback
from collections import OrderedDict, deque
from dataclasses import dataclass, field
from typing import Any, Callable

import mujoco
import numpy as np

from .deadline import PlannerTimeout, TickDeadline
from ..core.errors import ScenarioError, SimulationDivergedError
from ..core.interrupts import PlannerExit, from_the_user
from ..subjects.protocol import Command, Observation
from .trajectory import Collision, SafetyStop, SubjectFailure, Trajectory
from .safety import SafetyLayer
from ..scenario.model import BoxObstacle, CylinderObstacle, Footprint, Scenario

ROBOT_MASS = 50.0          # kg (about an ANYmal)
ROBOT_HEIGHT = 0.5         # m; the robot's body spans z in [0, ROBOT_HEIGHT]
LIDAR_HEIGHT = 0.2         # m; the lidar plane. Obstacles lower than this are invisible to it.
TRACKING_TAU = 0.05        # s; velocity tracking time constant of the actuators (kv = inertia / tau)
FORCE_HEADROOM = 1.5       # actuator force limit = inertia * max acceleration * headroom
MODEL_CACHE_SIZE = 64      # compiled models kept (the search and repeats re-run the same layout)
STILL = 1e-3               # m/s and rad/s: below this the robot counts as standing still

TWO_PI = 2.0 * math.pi

log = logging.getLogger(__name__)
_MUJOCO_WARNINGS: deque[str] = deque(maxlen=5)


def _on_mujoco_warning(message: str) -> None:
    """MuJoCo's warning handler: keep the text for SimulationDivergedError and log it, instead of
    MuJoCo's default of printing and appending to MUJOCO_LOG.TXT in the working directory."""
    _MUJOCO_WARNINGS.append(str(message).strip())
    log.warning("MuJoCo: %s", str(message).strip())


if mujoco.get_mju_user_warning() is None:   # leave a handler someone else installed alone
    mujoco.set_mju_user_warning(_on_mujoco_warning)


def wrap_angle(a: float) -> float:
    """Angle in radians wrapped to [-pi, pi)."""
    return (a + math.pi) % TWO_PI - math.pi


def lidar_angles(scenario: Scenario) -> np.ndarray:
    """Beam directions (rad, robot frame, counter-clockwise from the heading), read-only.

    A full circle (fov 360) has ``beams`` evenly spaced beams starting at -pi (no duplicate at +pi);
    a partial fov spans [-fov/2, +fov/2] inclusive (one beam: straight ahead).
    """
    lidar = scenario.robot.lidar
    n = int(lidar.beams)
    fov = lidar.fov_rad
    if n <= 1:
        out = np.zeros(max(n, 0))
    elif lidar.fov >= 360.0:
        out = -math.pi + TWO_PI * np.arange(n) / n
    else:
        out = np.linspace(-fov / 2.0, fov / 2.0, n)
    out.flags.writeable = False
    return out


def steps_per_tick(scenario: Scenario) -> int:
    """Physics steps per control tick: round(1 / (control_rate * timestep)); ScenarioError if < 1."""
    sim = scenario.simulation
    if not (sim.timestep > 0 and sim.control_rate > 0):
        raise ScenarioError(f"timestep and control_rate must be > 0, got {sim.timestep} and "
                            f"{sim.control_rate}", path=scenario.source, field="simulation",
                            hint="e.g. timestep: 0.01, control_rate: 10")
    n = round(1.0 / (sim.control_rate * sim.timestep))
    if n < 1:
        raise ScenarioError(
            f"control_rate {sim.control_rate} Hz is faster than the physics ({1 / sim.timestep:g} Hz)",
            path=scenario.source, field="simulation.control_rate",
            hint="lower control_rate or the timestep so that 1/(control_rate*timestep) >= 1")
    return n


# ---------------------------------------------------------------- model building

def _footprint_inertia(fp: Footprint) -> float:
    """Yaw moment of inertia (kg m^2) of the robot as a uniform box or disc of ROBOT_MASS."""
    if fp.shape == "circle":
        return ROBOT_MASS * fp.radius ** 2 / 2.0
    return ROBOT_MASS * (fp.length ** 2 + fp.width ** 2) / 12.0


def _geom_names(scenario: Scenario) -> list[str]:
    """MuJoCo geom names: the obstacle's name, unless empty or repeated (then ``obstacle<i>``)."""
    seen: set[str] = set()
    names = []
    for i, obs in enumerate(scenario.obstacles):
        name = obs.name if obs.name and obs.name not in seen and obs.name != "robot" else f"obstacle{i}"
        while name in seen:
            name = f"_{name}"
        seen.add(name)
        names.append(name)
    return names


def build_spec(scenario: Scenario) -> mujoco.MjSpec:
    """The MjSpec of a scenario: planar robot with velocity actuators, static obstacle geoms."""
    fp = scenario.robot.footprint
    limits = scenario.robot.limits
    spec = mujoco.MjSpec()
    spec.modelname = scenario.name or "navscenario"
    spec.compiler.degree = False              # every angle below is in radians
    spec.option.gravity = [0.0, 0.0, 0.0]     # planar: no gravity, no floor
    spec.option.timestep = scenario.simulation.timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST  # stable with stiff kv

    robot = spec.worldbody.add_body(name="robot", pos=[0.0, 0.0, ROBOT_HEIGHT / 2.0])
    robot.add_joint(name="x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
    robot.add_joint(name="y", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
    robot.add_joint(name="yaw", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    if fp.shape == "circle":
        robot.add_geom(name="footprint", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                       size=[fp.radius, ROBOT_HEIGHT / 2.0, 0.0], mass=ROBOT_MASS,
                       contype=1, conaffinity=2, rgba=[0.2, 0.4, 0.9, 1])
    else:
        robot.add_geom(name="footprint", type=mujoco.mjtGeom.mjGEOM_BOX,
                       size=[fp.length / 2.0, fp.width / 2.0, ROBOT_HEIGHT / 2.0], mass=ROBOT_MASS,
                       contype=1, conaffinity=2, rgba=[0.2, 0.4, 0.9, 1])
    robot.add_site(name="centre", pos=[0.0, 0.0, 0.0])

    inertia = _footprint_inertia(fp)
    lin_force = ROBOT_MASS * limits.max_accel * FORCE_HEADROOM
    yaw_torque = inertia * math.radians(limits.max_yaw_accel) * FORCE_HEADROOM
    for name, gear, kv, limit in (
            ("vx", [1, 0, 0, 0, 0, 0], ROBOT_MASS / TRACKING_TAU, lin_force),
            ("vy", [0, 1, 0, 0, 0, 0], ROBOT_MASS / TRACKING_TAU, lin_force),
            ("wz", [0, 0, 0, 0, 0, 1], inertia / TRACKING_TAU, yaw_torque)):
        act = spec.add_actuator(name=name, trntype=mujoco.mjtTrn.mjTRN_SITE, target="centre", gear=gear)
        act.set_to_velocity(kv=kv)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-limit, limit]

    for obs, gname in zip(scenario.obstacles, _geom_names(scenario)):
        h = obs.height
        if isinstance(obs, BoxObstacle):
            yaw = obs.yaw_rad
            spec.worldbody.add_geom(
                name=gname, type=mujoco.mjtGeom.mjGEOM_BOX, pos=[obs.x, obs.y, h / 2.0],
                quat=[math.cos(yaw / 2.0), 0.0, 0.0, math.sin(yaw / 2.0)],
                size=[obs.length / 2.0, obs.width / 2.0, h / 2.0], contype=2, conaffinity=1,
                rgba=[0.6, 0.6, 0.6, 1])
        elif isinstance(obs, CylinderObstacle):
            spec.worldbody.add_geom(
                name=gname, type=mujoco.mjtGeom.mjGEOM_CYLINDER, pos=[obs.x, obs.y, h / 2.0],
                size=[obs.radius, h / 2.0, 0.0], contype=2, conaffinity=1, rgba=[0.6, 0.6, 0.6, 1])
        else:
            raise ScenarioError(f"unknown obstacle type {type(obs).__name__}", path=scenario.source,
                                field=f"obstacles[{obs.name}]", hint="use a box or a cylinder")
    return spec


def model_xml(scenario: Scenario) -> str:
    """The scenario's MuJoCo model as MJCF text (to keep beside a frozen failure, or view it)."""
    spec = build_spec(scenario)
    spec.compile()
    return spec.to_xml()


@dataclass
class World:
    """A compiled model and the lookups the loop needs, shared by episodes (the model is never
    changed; only the pool of MjData to reuse is)."""
    model: mujoco.MjModel
    robot_body: int
    robot_geom: int
    obstacle_of_geom: dict[int, int]   # geom id -> index in scenario.obstacles
    safety: SafetyLayer | None
    free_data: list = field(default_factory=list)  # MjData pool: creating one costs ~1 ms

    def take_data(self) -> mujoco.MjData:
        """A freshly reset MjData (mj_resetData gives exactly the state of a new one)."""
        try:
            d = self.free_data.pop()
        except IndexError:
            return mujoco.MjData(self.model)
        mujoco.mj_resetData(self.model, d)
        return d

    def give_back(self, d: mujoco.MjData) -> None:
        if len(self.free_data) < 2:
            self.free_data.append(d)


_CACHE: OrderedDict[Any, World] = OrderedDict()


def _cache_key(scenario: Scenario) -> Any:
    # Everything the compiled model (and the safety geometry) depends on, names included (the
    # content hash ignores names, but contacts must map to the right name).
    robot = scenario.robot
    return (robot.footprint, robot.limits, robot.safety, scenario.obstacles,
            scenario.simulation.timestep)


def compiled_world(scenario: Scenario) -> World:
    """The compiled World for a scenario, from a small LRU cache."""
    key = _cache_key(scenario)
    world = _CACHE.get(key)
    if world is not None:
        _CACHE.move_to_end(key)
        return world
    spec = build_spec(scenario)
    try:
        model = spec.compile()
    except Exception as exc:  # mujoco.FatalError / ValueError with MuJoCo's own text
        raise ScenarioError(f"MuJoCo could not build the model: {exc}", path=scenario.source,
                            hint="check obstacle sizes and heights (> 0) and the robot footprint") from exc
    robot_body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "robot")
    robot_geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "footprint")
    obstacle_of_geom = {mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, gname): i
                        for i, gname in enumerate(_geom_names(scenario))}
    safety = SafetyLayer(scenario) if scenario.robot.safety.enabled and scenario.obstacles else None
    world = World(model, robot_body, robot_geom, obstacle_of_geom, safety)
    _CACHE[key] = world
    if len(_CACHE) > MODEL_CACHE_SIZE:
        _CACHE.popitem(last=False)
    return world


def clear_model_cache() -> None:
    _CACHE.clear()


# ---------------------------------------------------------------- the episode

@dataclass
class SimResult:
    """The raw facts of one episode, before the oracle and the metrics look at them."""
    trajectory: Trajectory
    collision: Collision | None = None
    safety_stop: SafetyStop | None = None
    subject_failure: SubjectFailure | None = None
    goal_reached: bool = False
    end: str = ""              # "goal", "collision", "safety-stop", "subject-error", "timeout", "max-ticks"
    ticks: int = 0             # planner ticks run
    timings: dict[str, float] = field(default_factory=dict)  # s: physics, rays, planner, safety, harness, total


def _describe(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def validate_command(cmd: Any) -> tuple[float, float, float] | str:
    """(vx, vy, wz) as floats, or a plain-words message saying what is wrong with ``cmd``."""
    expected = "expected a Command(vx, vy, wz) or a sequence of 3 finite floats"
    if (type(cmd) is Command or type(cmd) is tuple) and len(cmd) == 3:   # the common case, fast
        try:
            vx, vy, wz = float(cmd[0]), float(cmd[1]), float(cmd[2])
        except (TypeError, ValueError):
            pass
        else:
            if math.isfinite(vx + vy + wz):
                return vx, vy, wz
    if type(cmd) is Command or type(cmd) is tuple:
        items = cmd
    elif isinstance(cmd, np.ndarray):
        if cmd.shape != (3,):
            return f"planner.act returned an array of shape {cmd.shape}, expected shape (3,) (vx, vy, wz)"
        items = cmd.tolist()
    elif isinstance(cmd, (str, bytes, dict)) or cmd is None or not hasattr(cmd, "__len__"):
        return f"planner.act returned {type(cmd).__name__} {_describe(cmd)}; {expected}"
    else:
        items = cmd
    try:
        n = len(items)
    except TypeError:
        return f"planner.act returned {type(cmd).__name__} {_describe(cmd)}; {expected}"
    if n != 3:
        return (f"planner.act returned a {type(cmd).__name__} of length {n} ({_describe(cmd)}); "
                f"{expected}")
    try:
        vx, vy, wz = (float(v) for v in items)
    except (TypeError, ValueError):
        types = ", ".join(type(v).__name__ for v in items)
        return f"planner.act returned a {type(cmd).__name__} of ({types}) {_describe(cmd)}; {expected}"
    if not (math.isfinite(vx) and math.isfinite(vy) and math.isfinite(wz)):
        return f"planner.act returned a non-finite command (vx={vx}, vy={vy}, wz={wz}); {expected}"
    return vx, vy, wz


def _planner_traceback(exc: BaseException) -> str:
    """The planner's own traceback: the harness's frames (simulate, _call_planner) are dropped."""
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None and tb.tb_frame.f_code.co_filename == __file__:
        tb = tb.tb_next
    return "".join(traceback.format_exception(type(exc), exc, tb))


def _call_planner(fn: Callable[[Any], Any], arg: Any, deadline: TickDeadline | None) -> Any:
    """The ONE place the planner's code is called (reset or act), under the optional tick limit.
    SystemExit/KeyboardInterrupt raised by the planner's own code become PlannerExit (an ordinary
    subject error with the planner's frames); a user's Ctrl-C passes (core/interrupts.py)."""
    try:
        if deadline is None:
            return fn(arg)
        deadline.arm()
        try:
            out = fn(arg)
        except BaseException:
            try:
                deadline.disarm()
            except PlannerTimeout:
                pass
            raise
        deadline.disarm()  # raises PlannerTimeout when the tick took longer than the limit
        return out
    except (SystemExit, KeyboardInterrupt, GeneratorExit) as exc:
        if from_the_user(exc):
            raise
        raise PlannerExit(exc).with_traceback(exc.__traceback__) from None


_BEAM_TABLES: dict[Any, tuple[np.ndarray, np.ndarray]] = {}


def _beam_table(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """(beam angles, their unit directions (beams, 3) in the robot frame), both read-only and
    shared by the episodes of a lidar configuration (computing them costs ~15 us per episode)."""
    lidar = scenario.robot.lidar
    table = _BEAM_TABLES.get(lidar)
    if table is None:
        angles = lidar_angles(scenario)
        dirs = np.zeros((len(angles), 3))
        dirs[:, 0] = np.cos(angles)
        dirs[:, 1] = np.sin(angles)
        dirs.flags.writeable = False
        if len(_BEAM_TABLES) >= MODEL_CACHE_SIZE:
            _BEAM_TABLES.clear()
        table = _BEAM_TABLES[lidar] = (angles, dirs)
    return table


class _Lidar:
    """The episode's lidar: one ``mj_multiRay`` from the robot centre per tick, with the noise of
    the episode seed; the ranges are recorded as float32 rows and the planner gets each row as a
    read-only view (its base is read-only too, so a planner cannot make it writeable).

    Everything is computed or allocated once per episode, and a scan makes as few numpy calls as
    it can: in the loop, between MuJoCo's steps and the planner, numpy's code and data are out of
    the CPU caches and each call costs a few microseconds (profiled; several times what a tight
    benchmark of the same call says).
    """

    def __init__(self, scenario: Scenario, world: World, d: mujoco.MjData, n_rows: int, seed: int):
        lidar = scenario.robot.lidar
        angles, self.local_dirs = _beam_table(scenario)
        self.angles = angles.view()              # read-only, like its base
        self.beams = beams = len(angles)
        self.rot = np.zeros((3, 3))              # world dirs = local dirs @ rot (one matmul)
        self.dirs = np.zeros((beams, 3))
        self.dirs_flat = self.dirs.reshape(-1)
        self.pnt = np.array([0.0, 0.0, LIDAR_HEIGHT])
        self.geom = np.empty(beams, dtype=np.int32)
        self.dist = np.empty(beams)
        self.hit = np.empty(beams, dtype=bool)
        self.range_min, self.range_max = float(lidar.range_min), float(lidar.range_max)
        self.sigma, self.dropout = float(lidar.noise_sigma), float(lidar.dropout)
        # the generator is made only when there is noise to draw (seeding it costs ~20 us)
        self.rng = (np.random.Generator(np.random.PCG64(int(seed) & 0xFFFFFFFFFFFFFFFF))
                    if self.sigma > 0.0 or self.dropout > 0.0 else None)
        self.record = np.full((n_rows, beams), self.range_max, dtype=np.float32)
        self.readonly = self.record.view()
        self.readonly.flags.writeable = False
        self.model, self.data, self.body = world.model, d, world.robot_body

    def scan(self, tick: int, x: float, y: float, c: float, s: float) -> np.ndarray:
        """Ranges (read-only float32) of the robot at (x, y) with heading (cos, sin) = (c, s),
        recorded as row ``tick``; no return reads as range_max."""
        dist, rmin, rmax = self.dist, self.range_min, self.range_max
        rot = self.rot
        rot[0, 0] = rot[1, 1] = c     # four scalar writes: cheaper than one from a nested tuple
        rot[0, 1], rot[1, 0] = s, -s
        np.dot(self.local_dirs, rot, out=self.dirs)
        pnt = self.pnt
        pnt[0], pnt[1] = x, y
        if self.beams:
            mujoco.mj_multiRay(self.model, self.data, pnt, self.dirs_flat, None, 1, self.body,
                               self.geom, dist, None, self.beams, rmax)
        row = self.record[tick]
        if self.rng is None:
            # Without noise a beam without a return reads float32(range_max) whatever the clamp
            # does, so the row starts as that and only the hits are clamped into it (no copy of
            # range_max into the distances first: one numpy call less).
            np.greater_equal(self.geom, 0, out=self.hit)
            np.maximum(dist, rmin, out=dist)
            np.minimum(dist, rmax, out=row, where=self.hit, casting="same_kind")
        else:
            np.putmask(dist, self.geom < 0, rmax)
            if self.sigma > 0.0:
                dist += self.rng.normal(0.0, self.sigma, self.beams)
            if self.dropout > 0.0:
                np.putmask(dist, self.rng.random(self.beams) < self.dropout, rmax)
            np.maximum(dist, rmin, out=dist)
            np.minimum(dist, rmax, out=row, casting="same_kind")
        return self.readonly[tick]


def simulate(scenario: Scenario, planner: Any, seed: int, max_ticks: int | None = None, *,
             tick_limit: float | None = None) -> SimResult:
    """Run one episode of ``scenario`` against ``planner`` (an object with reset/act).

    Calls ``planner.reset(scenario)`` first. ``seed`` drives the lidar noise. ``max_ticks`` stops
    after that many planner ticks (for quick protocol checks). ``tick_limit`` (s) makes a slower
    planner tick a subject failure. Raises SimulationDivergedError if the physics blows up.
    """
    t_start = time.perf_counter()
    world = compiled_world(scenario)
    m = world.model
    d = world.take_data()
    sim = scenario.simulation
    mission = scenario.mission
    robot = scenario.robot
    limits = robot.limits

    dt = sim.timestep
    spt = steps_per_tick(scenario)
    tick_dt = spt * dt
    timeout_ticks = max(0, math.ceil(mission.timeout / tick_dt - 1e-9))
    n_ticks = timeout_ticks if max_ticks is None else min(timeout_ticks, max(0, int(max_ticks)))
    n_steps = n_ticks * spt + 1

    # records: physics-rate states in preallocated arrays (trimmed at the end), per-tick facts in
    # lists (an append is cheaper than a numpy row write)
    pose_buf = np.empty((n_steps, 3))
    qvel_buf = np.empty((n_steps, 3))
    tick_times: list[float] = []
    commands: list[tuple[float, float, float]] = []
    lidar = _Lidar(scenario, world, d, n_ticks + 1, seed)
    angles = lidar.angles
    # what the planner sees of the state: one row write per tick, read-only views of it
    seen = np.empty((n_ticks + 1, 6))
    seen_readonly = seen.view()
    seen_readonly.flags.writeable = False
    seen_pose, seen_vel = seen_readonly[:, :3], seen_readonly[:, 3:]

    # mission
    wps = np.array([[w.x, w.y] for w in mission.waypoints], dtype=float).reshape(-1, 2)
    wps.flags.writeable = False
    n_wp = len(wps)
    wp_index = 0
    wp_left = wps[0:]
    wp_times: list[float] = []
    goal = np.array([mission.goal.x, mission.goal.y, mission.goal.yaw_rad])
    goal.flags.writeable = False
    gx, gy, gyaw = float(goal[0]), float(goal[1]), float(goal[2])
    pos_tol = mission.goal_tolerance.position
    yaw_tol = None if mission.goal_tolerance.yaw is None else math.radians(mission.goal_tolerance.yaw)
    wp_tol = mission.waypoint_tolerance
    obstacles = scenario.obstacles

    # limits and setpoint
    omni = robot.drive == "omni"
    max_v = limits.max_speed
    max_vy = limits.max_lateral_speed if omni else 0.0
    max_w = math.radians(limits.max_yaw_rate)
    dv = limits.max_accel * tick_dt
    dw = math.radians(limits.max_yaw_accel) * tick_dt
    sp_vx = sp_vy = sp_wz = 0.0

    qpos, qvel, ctrl = d.qpos, d.qvel, d.ctrl
    qpos[:] = (mission.start.x, mission.start.y, mission.start.yaw_rad)
    mujoco.mj_step1(m, d)  # kinematics + contacts of the start state
    pose_buf[0] = qpos
    qvel_buf[0] = qvel

    safety = world.safety
    warn_count = d.warning.number   # a live view
    own_handler = mujoco.get_mju_user_warning() is _on_mujoco_warning
    _MUJOCO_WARNINGS.clear()
    deadline = TickDeadline(tick_limit) if tick_limit else None
    step, step1, step2 = mujoco.mj_step, mujoco.mj_step1, mujoco.mj_step2
    perf = time.perf_counter
    t_physics = t_rays = t_planner = t_safety = 0.0
    collision = safety_stop = failure = None
    goal_reached = False
    end = ""
    i = 0       # physics step index of the current state
    tick = 0
    fn_act = getattr(planner, "act", None)

    if deadline is not None:
        deadline.__enter__()
    try:
        # collision already at the start?
        if d.ncon:
            collision = _first_collision(d, world, obstacles, 0.0)
        if collision is not None:
            end = "collision"
        else:
            t0 = perf()
            try:
                _call_planner(planner.reset, scenario, None)   # the tick limit is for act only
            except (Exception, PlannerTimeout) as exc:
                failure = SubjectFailure(f"planner.reset raised {type(exc).__name__}: {exc}", 0, 0.0,
                                         _planner_traceback(exc))
                end = "subject-error"
            t_planner += perf() - t0
            if fn_act is None and failure is None:
                failure = SubjectFailure(f"planner {type(planner).__name__} has no act(observation) "
                                         f"method", 0, 0.0)
                end = "subject-error"

        while not end:
            t = i * dt
            x, y, yaw_raw = qpos.tolist()
            wvx, wvy, wz = qvel.tolist()
            if not math.isfinite(x + y + yaw_raw + wvx + wvy + wz):
                raise SimulationDivergedError(_divergence_message(scenario, d, t))
            # waypoints (in order), then the goal
            if wp_index < n_wp:
                while wp_index < n_wp and math.hypot(x - wps[wp_index, 0], y - wps[wp_index, 1]) <= wp_tol:
                    wp_times.append(t)
                    wp_index += 1
                wp_left = wps[wp_index:]
            yaw = (yaw_raw + math.pi) % TWO_PI - math.pi
            if wp_index == n_wp and math.hypot(x - gx, y - gy) <= pos_tol and (
                    yaw_tol is None or abs((yaw - gyaw + math.pi) % TWO_PI - math.pi) <= yaw_tol):
                goal_reached, end = True, "goal"
                break
            if tick >= n_ticks:
                end = "timeout" if tick >= timeout_ticks else "max-ticks"
                break

            t0 = perf()
            c, s = math.cos(yaw), math.sin(yaw)
            ranges = lidar.scan(tick, x, y, c, s)
            t1 = perf()
            t_rays += t1 - t0

            # measured velocity, robot frame
            vx, vy = c * wvx + s * wvy, -s * wvx + c * wvy
            tick_times.append(t)

            # safety layer on the measured velocity
            if safety is not None and (abs(vx) > STILL or abs(vy) > STILL or abs(wz) > STILL):
                hit = safety.check(x, y, yaw, vx, vy, wz)
                t2 = perf()
                t_safety += t2 - t1
                t1 = t2
                if hit is not None:
                    safety_stop = SafetyStop(t, hit, math.hypot(vx, vy))
                    ctrl[:] = 0.0
                    commands.append((0.0, 0.0, 0.0))
                    tick += 1
                    end = "safety-stop"
                    break

            seen[tick] = (x, y, yaw, vx, vy, wz)
            obs = Observation(tick, t, seen_pose[tick], seen_vel[tick], ranges, angles, goal, wp_left,
                              obstacles)
            t2 = perf()
            try:
                answer = _call_planner(fn_act, obs, deadline)
            except (Exception, PlannerTimeout) as exc:
                t_planner += perf() - t2
                failure = SubjectFailure(f"planner.act raised {type(exc).__name__}: {exc}", tick, t,
                                         _planner_traceback(exc))
                commands.append((0.0, 0.0, 0.0))
                tick += 1
                end = "subject-error"
                break
            t3 = perf()
            t_planner += t3 - t2
            cmd = validate_command(answer)
            if type(cmd) is str:
                failure = SubjectFailure(cmd, tick, t)
                commands.append((0.0, 0.0, 0.0))
                tick += 1
                end = "subject-error"
                break
            cvx, cvy, cwz = cmd
            # clip to the drive's limits, then rate-limit the setpoint by the accelerations
            cvx = max_v if cvx > max_v else (-max_v if cvx < -max_v else cvx)
            cvy = max_vy if cvy > max_vy else (-max_vy if cvy < -max_vy else cvy)
            cwz = max_w if cwz > max_w else (-max_w if cwz < -max_w else cwz)
            sp_vx += min(dv, max(-dv, cvx - sp_vx))
            sp_vy += min(dv, max(-dv, cvy - sp_vy))
            sp_wz += min(dw, max(-dw, cwz - sp_wz))
            setpoint = (sp_vx, sp_vy, sp_wz)
            ctrl[:] = setpoint
            commands.append(setpoint)
            tick += 1

            # Physics, one step at a time, with the contacts of every state checked. The state
            # at the tick start has had mj_step1 (positions, contacts) already: finish its step
            # with mj_step2, then each mj_step computes the contacts of the state it starts from
            # (checked right after it) and advances; a last mj_step1 checks the tick's final state.
            # spt + 1 calls instead of 2 * spt; the physics is the same as mj_step's.
            t4 = perf()
            step2(m, d)
            i += 1
            pose_buf[i] = qpos
            qvel_buf[i] = qvel
            for _ in range(spt - 1):
                step(m, d)
                if d.ncon:   # contacts of state i (the data has moved on to i + 1: not recorded)
                    collision = _first_collision(d, world, obstacles, i * dt)
                    if collision is not None:
                        break
                i += 1
                pose_buf[i] = qpos
                qvel_buf[i] = qvel
            else:
                step1(m, d)
                if d.ncon:
                    collision = _first_collision(d, world, obstacles, i * dt)
            t_physics += perf() - t4
            if collision is not None:
                end = "collision"
                break
            # MuJoCo warns (and resets the data or zeroes the control) on NaN/huge values; our
            # handler records the first warning of each kind per episode (a cheap test)
            if _MUJOCO_WARNINGS if own_handler else warn_count.any():
                raise SimulationDivergedError(_divergence_message(scenario, d, i * dt))
        if warn_count.any():   # the authoritative per-data counters, once per episode
            raise SimulationDivergedError(_divergence_message(scenario, d, i * dt))
    finally:
        if deadline is not None:
            deadline.__exit__(None, None, None)
        world.give_back(d)

    n = i + 1
    pose = pose_buf[:n].copy()
    qv = qvel_buf[:n]
    yaw_rec = pose[:, 2]
    pose[:, 2] = (yaw_rec + math.pi) % TWO_PI - math.pi
    cos_y, sin_y = np.cos(yaw_rec), np.sin(yaw_rec)
    velocity = np.empty((n, 3))
    velocity[:, 0] = cos_y * qv[:, 0] + sin_y * qv[:, 1]
    velocity[:, 1] = -sin_y * qv[:, 0] + cos_y * qv[:, 1]
    velocity[:, 2] = qv[:, 2]
    trajectory = Trajectory(
        t=np.arange(n) * dt, pose=pose, velocity=velocity, tick_t=np.array(tick_times, dtype=float),
        command=np.array(commands, dtype=float).reshape(-1, 3), ranges=lidar.record[:tick].copy(),
        angles=angles, waypoint_times=tuple(wp_times))
    total = time.perf_counter() - t_start
    timings = {"physics": t_physics, "rays": t_rays, "planner": t_planner, "safety": t_safety,
               "harness": total - t_physics - t_rays - t_planner, "total": total}
    return SimResult(trajectory, collision, safety_stop, failure, goal_reached, end, tick, timings)


def _first_collision(d: mujoco.MjData, world: World, obstacles: tuple, t: float) -> Collision | None:
    """The deepest robot-obstacle penetration among the current contacts, or None."""
    best = None
    contacts = d.contact
    for k in range(d.ncon):
        dist = float(contacts.dist[k])
        if dist >= 0.0:
            continue
        g1, g2 = int(contacts.geom[k][0]), int(contacts.geom[k][1])
        other = g2 if g1 == world.robot_geom else (g1 if g2 == world.robot_geom else -1)
        idx = world.obstacle_of_geom.get(other)
        if idx is None:
            continue
        if best is None or dist < best[0]:
            best = (dist, idx, k)
    if best is None:
        return None
    dist, idx, k = best
    pos = contacts.pos[k]
    return Collision(t, obstacles[idx].name, float(pos[0]), float(pos[1]), -dist)


def _divergence_message(scenario: Scenario, d: mujoco.MjData, t: float) -> str:
    where = scenario.name or "<unnamed scenario>"
    if scenario.source:
        where += f" ({scenario.source})"
    warned = [f"{mujoco.mjtWarning(k).name} (x{int(w.number)}, info {int(w.lastinfo)})"
              for k, w in enumerate(d.warning) if w.number]
    state = f"qpos={np.array2string(d.qpos, precision=3)}, qvel={np.array2string(d.qvel, precision=3)}"
    why = ("MuJoCo warnings: " + ", ".join(warned)) if warned else "non-finite state"
    if _MUJOCO_WARNINGS:
        why += f" ({_MUJOCO_WARNINGS[-1]})"
    return (f"simulation diverged in scenario {where} by t={t:.3f} s: {why}; {state}. "
            f"The physics cannot be trusted: check robot.limits (huge speeds or accelerations) and "
            f"simulation.timestep (try 0.01 s or smaller).")
