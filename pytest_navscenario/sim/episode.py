"""One episode: the control loop that runs a planner against a scenario in the MuJoCo world.

``simulate(scenario, planner, seed)`` runs an ``Episode`` and returns the raw facts (trajectory,
collision, safety stop, planner failure, goal reached, timings); ``harness.runner.run_scenario``
turns them into an outcome and metrics. The episode starts the robot at the start pose and resets
the planner; then each control tick it observes (true state, mission progress, lidar scan), checks
the safety layer, asks the planner to act (under the tick deadline, command validated, drive
limits), records, and steps the physics one step at a time with a contact check after each step.

The loop is the hot path of every suite and search (besides MuJoCo and the planner, ~10 us a tick):
each step is a method that binds its hot values to locals; per-tick facts go into lists,
physics-rate states into preallocated arrays, and the planner sees read-only views of rows written
once. ``benchmarks/bench_episode.py`` measures it, ``benchmarks/check_bit_identical.py`` checks that
a change to it keeps every trajectory's bits.
"""
from __future__ import annotations

import math
from time import perf_counter
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from ..core.errors import SimulationDivergedError, SimulationFatalError
from ..scenario.model import Mission, Scenario
from ..subjects.protocol import Observation
from .command import Drive, call_planner, planner_traceback, validate_command
from .deadline import PlannerTimeout, TickDeadline
from .ground.ground_safety import ground_safety
from .lidar import Lidar, base_rotation
from .lidar3d import CloudLidar, LEVEL
from .faults import Faults
from .moving import MovingObstacles, describe_collision
from .profiler import profiler_off
from .trajectory import Collision, SafetyStop, SubjectFailure, TerrainEvent, Trajectory
from .world import (MUJOCO_WARNINGS, TWO_PI, compiled_world, divergence_message, fatal_message,
                    on_mujoco_warning, steps_per_tick)
from ..scenario.ground import surface as ground
from .bodies.base import base_state, quat_to_rpy, world_yaw_rate
from .bodies.mjcf import BodyControllerError
from .body_world import compiled_body_world, rides_the_ground
from .ground.riding import GroundProbe, TerrainStop, TerrainWatch, resting_pose

__all__ = ["Episode", "RidingEpisode", "SimResult", "simulate", "validate_command"]

_new = object.__new__

STILL = 1e-3               # m/s and rad/s: below this the robot counts as standing still
HALT = (0.0, 0.0, 0.0)     # the command recorded for a tick that ended the episode
STUCK_CELL = 0.25          # m: a robot that enters no new square of this size for stuck_after s is stuck


@dataclass
class SimResult:
    """The raw facts of one episode, before the oracle and the metrics look at them."""
    trajectory: Trajectory
    collision: Collision | None = None
    safety_stop: SafetyStop | None = None
    subject_failure: SubjectFailure | None = None
    goal_reached: bool = False
    end: str = ""              # "goal", "collision", "safety-stop", "subject-error", "timeout", "max-ticks", "stuck",
                               # and on terrain (sim/ground/riding.py) "fell", "tipped", "stuck-terrain"
    ticks: int = 0             # planner ticks run
    timings: dict[str, float] = field(default_factory=dict)  # s: physics, rays, planner, safety, harness, total
    terrain_event: TerrainEvent | None = None   # fell, tipped over, stuck on terrain (sim/ground/riding.py)


class EpisodeOver(Exception):
    """Raised by the step that ends the episode; ``reason`` is SimResult.end."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


class MissionProgress:
    """The mission as the episode goes: the intermediate waypoints, passed in order (each within
    ``waypoint_tolerance``), then the goal (within the position and, if set, the yaw tolerance)."""

    def __init__(self, mission: Mission):
        wps = np.array([[w.x, w.y] for w in mission.waypoints], dtype=float).reshape(-1, 2)
        wps.flags.writeable = False
        self._points = wps.tolist()         # [x, y] of the waypoints not passed yet
        self._all = wps
        self.left = wps[0:]                 # the waypoints still to pass (read-only, for the planner)
        self.passed_at: list[float] = []    # when each waypoint was passed
        goal = np.array([mission.goal.x, mission.goal.y, mission.goal.yaw_rad])
        goal.flags.writeable = False
        self.goal = goal                    # (x, y, yaw) read-only, for the planner
        self._gx, self._gy, self._gyaw = goal.tolist()
        self._pos_tol = mission.goal_tolerance.position
        yaw_tol = mission.goal_tolerance.yaw
        self._yaw_tol = None if yaw_tol is None else math.radians(yaw_tol)
        self._wp_tol = mission.waypoint_tolerance

    def goal_reached(self, t: float, x: float, y: float, yaw: float) -> bool:
        """Mark the waypoints passed at (x, y) at time t; True once all are passed and the robot is
        at the goal (yaw wrapped to [-pi, pi))."""
        if self._points:
            self._pass_waypoints(t, x, y)
            if self._points:
                return False
        if math.hypot(x - self._gx, y - self._gy) > self._pos_tol:
            return False
        yaw_tol = self._yaw_tol
        return yaw_tol is None or abs((yaw - self._gyaw + math.pi) % TWO_PI - math.pi) <= yaw_tol

    def _pass_waypoints(self, t: float, x: float, y: float) -> None:
        points, tol = self._points, self._wp_tol
        passed = 0
        while passed < len(points) and math.hypot(x - points[passed][0], y - points[passed][1]) <= tol:
            self.passed_at.append(t)
            passed += 1
        if passed:
            del points[:passed]
            self.left = self._all[len(self._all) - len(points):]


class Episode:
    """One episode of ``scenario`` against ``planner``, as the named steps of the control loop.

    ``run()`` calls ``start`` (robot at the start pose, contacts checked, ``planner.reset``), then
    per control tick, until a step ends the episode by raising ``EpisodeOver``:

    1. ``observe``: the true state (a non-finite one raises SimulationDivergedError), the mission's
       progress (the goal reached, or the time up, ends the episode), then what the planner sees:
       the lidar scan and the measured pose and velocity, as an ``Observation``;
    2. ``safety_check``: the safety layer on the true pose and measured velocity (a halt ends it);
    3. ``act``: the planner under the tick deadline, its answer validated (a raise, a timeout or a
       bad answer ends it), then the drive's limits: the new actuator setpoint;
    4. ``record``: the tick's time and setpoint;
    5. ``step_physics``: the tick's physics steps, each state recorded and its contacts checked (a
       collision ends it), then MuJoCo's warnings (a divergence raises).

    ``steps`` chooses the variants once per episode, so a static scenario pays nothing per tick
    for the features it does not use. Moving obstacles (mocap bodies, ``moving.py``): ``start``
    puts them where they are at t = 0, ``step_physics_moving`` before each state's kinematics, so
    every step's contacts and the next tick's scan see them where they are, and
    ``safety_check_moving`` gives the safety layer their offsets and velocities at the tick.
    Without a safety layer the check is ``_unchecked``. Sensor faults (sim/faults.py: latency,
    localisation drift; ``run_ticks_with_faults``) change what the planner is handed, never the
    true state that the safety layer, the mission and the recorded trajectory use.
    """

    world_of = staticmethod(compiled_world)     # the compiled world of a scenario

    def __init__(self, scenario: Scenario, planner: Any, seed: int, max_ticks: int | None = None, *,
                 tick_limit: float | None = None, stuck_after: float | None = None):
        self.t_start = perf_counter()
        self.scenario, self.planner = scenario, planner
        self.obstacles = scenario.obstacles
        self.world = world = self.world_of(scenario)
        self.model, self.safety = world.model, world.safety
        self.dt = dt = scenario.simulation.timestep
        self.spt = spt = steps_per_tick(scenario)
        self.timeout_ticks = max(0, math.ceil(scenario.mission.timeout / (spt * dt) - 1e-9))
        self.n_ticks = self.timeout_ticks if max_ticks is None else min(self.timeout_ticks,
                                                                         max(0, int(max_ticks)))
        self.mission = MissionProgress(scenario.mission)
        self.drive = Drive(scenario.robot, spt * dt)
        self.deadline = TickDeadline(tick_limit) if tick_limit else None
        self.act_fn = getattr(planner, "act", None)
        self.data = d = world.take_data()           # given back by run()
        self.qpos, self.qvel, self.ctrl = d.qpos, d.qvel, d.ctrl
        self.warn_count = d.warning.number         # a live view
        self.own_handler = mujoco.get_mju_user_warning() is on_mujoco_warning
        self.lidar = Lidar(scenario, world, d, self.n_ticks + 1, seed)
        self.cloud = (CloudLidar(scenario, world, d, self.n_ticks + 1, seed)
                      if scenario.robot.lidar3d is not None else None)
        if self.cloud is not None and type(self).observe is Episode.observe:
            self.observe = self.observe_cloud       # the planar body's 3D scan, level at z = 0
        self.moving = (MovingObstacles(scenario, d.mocap_pos, dt, spt) if world.model.nmocap else None)
        self._allocate_records(self.n_ticks * spt + 1)
        robot = scenario.robot
        self.faults = (Faults(scenario, seed, self.seen, spt * dt)
                       if robot.localisation.drifts or robot.latency.observation or robot.latency.command
                       else None)
        self.i = 0              # physics step index of the current state
        self.tick = 0           # control ticks run
        self.t_physics = self.t_rays = self.t_planner = self.t_safety = self.t_cloud = 0.0
        self.collision: Collision | None = None
        self.safety_stop: SafetyStop | None = None
        self.failure: SubjectFailure | None = None
        self.end = ""
        # stuck: no new STUCK_CELL square entered for stuck_ticks ticks ends the episode early
        self.stuck_ticks = max(1, math.ceil(stuck_after / (spt * dt) - 1e-9)) if stuck_after else 0
        self.visited: set[tuple[int, int]] = set()
        self.last_new = 0

    def _allocate_records(self, n_steps: int) -> None:
        """Physics-rate states in preallocated arrays (trimmed at the end), per-tick facts in lists
        (an append is cheaper than a numpy row write), and the rows the planner sees of the state:
        one row write per tick, handed out as read-only views."""
        self.pose_buf = np.empty((n_steps, 3))
        self.qvel_buf = np.empty((n_steps, 3))
        self.tick_times: list[float] = []
        self.commands: list[tuple[float, float, float]] = []
        self.seen = np.empty((self.n_ticks + 1, 6))
        readonly = self.seen.view()
        readonly.flags.writeable = False
        self.seen_pose, self.seen_vel = readonly[:, :3], readonly[:, 3:]
        self.stepping = (self.model, self.data, self.ctrl, self.qpos, self.qvel, self.pose_buf,
                         self.qvel_buf, range(self.spt - 1))   # a range can be iterated again

    # ------------------------------------------------------------ the episode

    def run(self) -> SimResult:
        """Start, then tick until a step ends the episode (call once), MuJoCo's profiler off
        (profiler.py); the MjData goes back to the pool."""
        with profiler_off():
            return self._run()

    def _run(self) -> SimResult:
        deadline = self.deadline
        if deadline is not None:
            deadline.__enter__()
        fatal = False
        try:
            try:
                self.start()
                self.run_ticks()
            except EpisodeOver as over:
                self.end = over.reason
            except mujoco.FatalError as exc:   # mju_error (an arena overflow...): this episode ends
                fatal = True
                raise SimulationFatalError(
                    fatal_message(self.scenario, self.model, exc, self.i * self.dt)) from None
            if self.warn_count.any():   # the authoritative per-data counters, once per episode
                raise SimulationDivergedError(
                    divergence_message(self.scenario, self.data, self.i * self.dt))
        finally:
            if deadline is not None:
                deadline.__exit__(None, None, None)
            if not fatal:                # a data MuJoCo gave up on is not reused
                self.world.give_back(self.data)
        return self.result()

    def start(self) -> None:
        """The robot at the start pose (a collision there ends the episode), the planner reset (the
        tick limit is for act only: reset may build maps)."""
        self.place()
        self._reset_planner()

    def place(self) -> None:
        """The robot at the start pose, its contacts checked: a collision there ends the episode
        before the planner is reset (a batch resets its planner after every episode's place)."""
        m, d, start = self.model, self.data, self.scenario.mission.start
        self.qpos[:] = (start.x, start.y, start.yaw_rad)
        if self.moving is not None:
            self.moving.write(0)
        mujoco.mj_step1(m, d)  # kinematics + contacts of the start state
        self.pose_buf[0] = self.qpos
        self.qvel_buf[0] = self.qvel
        MUJOCO_WARNINGS.clear()
        if d.ncon:
            self.collision = self.world.first_collision(d, self.obstacles, 0.0)
            if self.collision is not None:
                self.collision = describe_collision(self.collision, self.scenario, self.qvel_buf[0])
                raise EpisodeOver("collision")

    def _reset_planner(self) -> None:
        t0 = perf_counter()
        try:
            call_planner(self.planner.reset, self.scenario, None)
        except (Exception, PlannerTimeout) as exc:
            self.t_planner += perf_counter() - t0
            self.failure = SubjectFailure(f"planner.reset raised {type(exc).__name__}: {exc}", 0, 0.0,
                                          planner_traceback(exc))
            raise EpisodeOver("subject-error") from None
        self.t_planner += perf_counter() - t0
        if self.act_fn is None:
            self.failure = SubjectFailure(f"planner {type(self.planner).__name__} has no "
                                          f"act(observation) method", 0, 0.0)
            raise EpisodeOver("subject-error")

    def steps(self) -> tuple[Any, Any, Any]:
        """(safety check, act, physics step) for this episode, chosen once at its start: a static
        scenario's loop never tests for moving obstacles, a safety layer or latency per tick."""
        if self.safety is None:
            safety_check = _unchecked
        else:
            safety_check = self.safety_check if self.moving is None else self.safety_check_moving
        step_physics = self.step_physics if self.moving is None else self.step_physics_moving
        return safety_check, self.act, step_physics

    def run_ticks(self) -> None:
        """Control ticks until one of the steps ends the episode (raises EpisodeOver)."""
        if self.faults is not None:
            return self.run_ticks_with_faults()
        safety_check, act, step_physics = self.steps()
        observe, record = self.observe, self.record
        while True:
            state, obs = observe()
            safety_check(state)
            setpoint = act(obs)
            record(obs.time, setpoint)
            step_physics(setpoint)

    def run_ticks_with_faults(self) -> None:
        """``run_ticks`` with localisation drift and latency (sim/faults.py): the planner gets the
        drifted, delayed observation, its setpoint takes effect later; the truth is recorded."""
        faults = self.faults
        safety_check, act, step_physics = self.steps()
        observe, record = self.observe, self.record
        while True:
            state, obs = observe()
            seen = faults.observation(self.tick, state, obs)
            safety_check(state)
            setpoint = faults.applied(act(seen))
            record(state[0], setpoint)
            step_physics(setpoint)

    # ------------------------------------------------------------ the steps of a tick

    def observe(self) -> tuple[tuple[float, ...], Observation]:
        """(the true state (t, x, y, yaw, vx, vy, wz) with the velocity in the robot frame, what the
        planner sees); ends the episode at the goal or when the time is up."""
        x, y, yaw_raw = self.qpos.tolist()
        wvx, wvy, wz = self.qvel.tolist()
        t = self.i * self.dt
        if not math.isfinite(x + y + yaw_raw + wvx + wvy + wz):
            raise SimulationDivergedError(divergence_message(self.scenario, self.data, t))
        yaw = (yaw_raw + math.pi) % TWO_PI - math.pi
        mission = self.mission
        if mission.goal_reached(t, x, y, yaw):
            raise EpisodeOver("goal")
        tick = self.tick
        if tick >= self.n_ticks:
            raise EpisodeOver("timeout" if tick >= self.timeout_ticks else "max-ticks")
        if self.stuck_ticks:
            self.check_stuck(tick, x, y)
        t0 = perf_counter()
        c, s = math.cos(yaw), math.sin(yaw)
        lidar = self.lidar
        ranges = lidar.scan(tick, x, y, c, s)
        self.t_rays += perf_counter() - t0
        vx, vy = c * wvx + s * wvy, -s * wvx + c * wvy     # measured velocity, robot frame
        self.seen[tick] = (x, y, yaw, vx, vy, wz)
        # Observation(...) without the frozen dataclass's nine object.__setattr__ calls (~1 us a
        # tick); tests/sim pins that this fills exactly the dataclass's fields
        obs = _new(Observation)
        obs.__dict__.update(tick=tick, time=t, pose=self.seen_pose[tick], velocity=self.seen_vel[tick],
                            ranges=ranges, angles=lidar.angles, goal=mission.goal,
                            waypoints=mission.left, obstacles=self.obstacles, points=None, attitude=LEVEL)
        return (t, x, y, yaw, vx, vy, wz), obs

    def observe_cloud(self) -> tuple[tuple[float, ...], Observation]:
        """``observe`` with the 3D lidar's points (the planar body: level, its base at z = 0)."""
        state, obs = Episode.observe(self)
        x, y, yaw = state[1], state[2], state[3]
        c, s = math.cos(yaw), math.sin(yaw)
        obs.__dict__["points"] = self.scan_cloud(obs.tick, np.array([x, y, 0.0]),
                                                 np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]))
        return state, obs

    def scan_cloud(self, tick: int, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """The 3D lidar's points from a base at ``pos`` turned by ``rot`` (world from base), its
        time counted apart (``timings["lidar3d"]``)."""
        t0 = perf_counter()
        points = self.cloud.scan(tick, pos, rot)
        self.t_cloud += perf_counter() - t0
        return points

    def check_stuck(self, tick: int, x: float, y: float) -> None:
        """End the episode ("stuck", a timeout) when the robot has entered no new square of
        STUCK_CELL for ``stuck_after`` seconds: standing still, dithering or circling in place."""
        cell = (math.floor(x / STUCK_CELL), math.floor(y / STUCK_CELL))
        if cell not in self.visited:
            self.visited.add(cell)
            self.last_new = tick
        elif tick - self.last_new >= self.stuck_ticks:
            raise EpisodeOver("stuck")

    def safety_check(self, state: tuple[float, ...]) -> None:
        """The safety layer on the measured velocity: a robot standing still is never halted; one
        whose predicted sweep would hit an obstacle is halted, which ends the episode. (Chosen by
        ``steps`` when the world has a safety layer; without one, ``_unchecked``.)"""
        t, x, y, yaw, vx, vy, wz = state
        if abs(vx) > STILL or abs(vy) > STILL or abs(wz) > STILL:
            t0 = perf_counter()
            hit = self.safety.check(x, y, yaw, vx, vy, wz)
            self.t_safety += perf_counter() - t0
            if hit is not None:
                self._halt(state, hit)

    def safety_check_moving(self, state: tuple[float, ...]) -> None:
        """``safety_check`` with the moving obstacles' offsets and velocities at the tick."""
        t, x, y, yaw, vx, vy, wz = state
        if abs(vx) > STILL or abs(vy) > STILL or abs(wz) > STILL:
            t0 = perf_counter()
            hit = self.safety.check(x, y, yaw, vx, vy, wz, self.moving.now(self.i))
            self.t_safety += perf_counter() - t0
            if hit is not None:
                self._halt(state, hit)

    def _halt(self, state: tuple[float, ...], hit: str) -> None:
        """The safety layer halts the robot before ``hit``: zero control, the episode ends."""
        t, vx, vy = state[0], state[4], state[5]
        self.safety_stop = SafetyStop(t, hit, math.hypot(vx, vy))
        self.ctrl[:] = 0.0
        self.record(t, HALT)
        raise EpisodeOver("safety-stop")

    def act(self, obs: Observation) -> tuple[float, float, float]:
        """The new setpoint: the planner's answer under the tick deadline, validated, within the
        drive's limits. A planner that raises, overruns or answers nonsense ends the episode."""
        t0 = perf_counter()
        try:
            answer = call_planner(self.act_fn, obs, self.deadline)
        except (Exception, PlannerTimeout) as exc:
            self.t_planner += perf_counter() - t0
            self._planner_failed(obs, f"planner.act raised {type(exc).__name__}: {exc}",
                                 planner_traceback(exc))
        self.t_planner += perf_counter() - t0
        cmd = validate_command(answer)
        if type(cmd) is str:
            self._planner_failed(obs, cmd)
        vx, vy, wz = cmd
        return self.drive.setpoint(vx, vy, wz)

    def _planner_failed(self, obs: Observation, message: str, tb: str | None = None) -> None:
        t = self.i * self.dt       # now (a delayed observation is older)
        self.failure = SubjectFailure(message, self.tick, t, tb)
        self.record(t, HALT)
        raise EpisodeOver("subject-error") from None

    def record(self, t: float, setpoint: tuple[float, float, float]) -> None:
        """The tick's time and the setpoint it applied (the lidar recorded its own row)."""
        self.tick_times.append(t)
        self.commands.append(setpoint)
        self.tick += 1

    def step_physics(self, setpoint: tuple[float, float, float]) -> None:
        """The tick's physics, one step at a time, with the contacts of every state checked.

        The state at the tick start has had mj_step1 (positions, contacts) already: finish its step
        with mj_step2, then each mj_step computes the contacts of the state it starts from (checked
        right after it) and advances; a last mj_step1 checks the tick's final state. spt + 1 calls
        instead of 2 * spt; the physics is the same as mj_step's.
        """
        m, d, ctrl, qpos, qvel, pose_buf, qvel_buf, inner = self.stepping   # one load a tick
        step = mujoco.mj_step
        ctrl[0], ctrl[1], ctrl[2] = setpoint     # three scalar writes: cheaper than ctrl[:] = tuple
        t0 = perf_counter()
        collision = None
        mujoco.mj_step2(m, d)
        i = self.i + 1
        pose_buf[i] = qpos
        qvel_buf[i] = qvel
        for _ in inner:
            step(m, d)
            if d.ncon:   # contacts of state i (the data has moved on to i + 1: not recorded)
                collision = self.world.first_collision(d, self.obstacles, i * self.dt)
                if collision is not None:
                    break
            i += 1
            pose_buf[i] = qpos
            qvel_buf[i] = qvel
        else:
            mujoco.mj_step1(m, d)
            if d.ncon:
                collision = self.world.first_collision(d, self.obstacles, i * self.dt)
        self.i = i
        self.t_physics += perf_counter() - t0
        if collision is not None or MUJOCO_WARNINGS or not self.own_handler:
            self._after_physics(collision)

    def _after_physics(self, collision: Collision | None) -> None:
        """End the episode on a collision (with who moved), raise on a divergence."""
        if collision is not None:
            self.collision = describe_collision(collision, self.scenario, self.qvel_buf[self.i])
            raise EpisodeOver("collision")
        # MuJoCo warns (and resets the data or zeroes the control) on NaN/huge values; our
        # handler records the first warning of each kind per episode (a cheap test)
        if MUJOCO_WARNINGS if self.own_handler else self.warn_count.any():
            raise SimulationDivergedError(divergence_message(self.scenario, self.data, self.i * self.dt))

    def step_physics_moving(self, setpoint: tuple[float, float, float]) -> None:
        """``step_physics`` with moving obstacles: before each state's kinematics (mj_step's first
        half, the last mj_step1) the obstacles are put where they are at that state's time, so every
        step's contacts and the next scan see them there."""
        m, d, ctrl, qpos, qvel, pose_buf, qvel_buf, _ = self.stepping
        step = mujoco.mj_step
        mocap_pos = self.moving.mocap_pos
        rows = self.moving.rows_for_tick(self.i)    # rows[k]: step self.i + k
        ctrl[0], ctrl[1], ctrl[2] = setpoint
        t0 = perf_counter()
        collision = None
        mujoco.mj_step2(m, d)
        i = self.i + 1
        pose_buf[i] = qpos
        qvel_buf[i] = qvel
        for k in range(1, self.spt):
            mocap_pos[:] = rows[k]
            step(m, d)
            if d.ncon:
                collision = self.world.first_collision(d, self.obstacles, i * self.dt)
                if collision is not None:
                    break
            i += 1
            pose_buf[i] = qpos
            qvel_buf[i] = qvel
        else:
            mocap_pos[:] = rows[self.spt]
            mujoco.mj_step1(m, d)
            if d.ncon:
                collision = self.world.first_collision(d, self.obstacles, i * self.dt)
        self.i = i
        self.t_physics += perf_counter() - t0
        self._after_physics(collision)

    # ------------------------------------------------------------ the facts

    def trajectory(self) -> Trajectory:
        """The recorded states, trimmed to the steps and ticks run; velocities in the robot frame."""
        n = self.i + 1
        pose = self.pose_buf[:n].copy()
        qv = self.qvel_buf[:n]
        yaw_rec = pose[:, 2]
        pose[:, 2] = (yaw_rec + math.pi) % TWO_PI - math.pi
        cos_y, sin_y = np.cos(yaw_rec), np.sin(yaw_rec)
        velocity = np.empty((n, 3))
        velocity[:, 0] = cos_y * qv[:, 0] + sin_y * qv[:, 1]
        velocity[:, 1] = -sin_y * qv[:, 0] + cos_y * qv[:, 1]
        velocity[:, 2] = qv[:, 2]
        return Trajectory(
            t=np.arange(n) * self.dt, pose=pose, velocity=velocity,
            tick_t=np.array(self.tick_times, dtype=float),
            command=np.array(self.commands, dtype=float).reshape(-1, 3),
            ranges=self.lidar.ranges(self.tick), angles=self.lidar.angles,
            waypoint_times=tuple(self.mission.passed_at),
            believed=None if self.faults is None else self.faults.believed_poses(),
            cloud=None if self.cloud is None else self.cloud.ranges(self.tick))

    def result(self) -> SimResult:
        trajectory = self.trajectory()
        total = perf_counter() - self.t_start
        spent = self.t_physics + self.t_rays + self.t_planner + self.t_cloud
        timings = {"physics": self.t_physics, "rays": self.t_rays, "planner": self.t_planner,
                   "safety": self.t_safety, "harness": total - spent, "total": total}
        if self.cloud is not None:
            timings["lidar3d"] = self.t_cloud      # the 3D lidar's scans, on their own
        return SimResult(trajectory, self.collision, self.safety_stop, self.failure, self.end == "goal",
                         self.end, self.tick, timings)


def _unchecked(state: tuple[float, ...]) -> None:
    """The safety step of a world without a safety layer (disabled, or no obstacles)."""


def simulate(scenario: Scenario, planner: Any, seed: int, max_ticks: int | None = None, *,
             tick_limit: float | None = None, stuck_after: float | None = None) -> SimResult:
    """Run one episode of ``scenario`` against ``planner`` (an object with reset/act).

    Calls ``planner.reset(scenario)`` first. ``seed`` drives the lidar noise. ``max_ticks`` stops
    after that many planner ticks (for quick protocol checks). ``tick_limit`` (s) makes a slower
    planner tick a subject failure. ``stuck_after`` (s) ends the episode early (``end ==
    "stuck"``, a timeout) when the robot has entered no new STUCK_CELL square for that long.
    Raises SimulationDivergedError if the physics blows up. A robot with a body that rides the
    ground (or any terrain) runs as a ``riding.RidingEpisode``.
    """
    if rides_the_ground(scenario):
        return RidingEpisode(scenario, planner, seed, max_ticks, tick_limit=tick_limit,
                             stuck_after=stuck_after).run()
    return Episode(scenario, planner, seed, max_ticks, tick_limit=tick_limit, stuck_after=stuck_after).run()


# ---------------------------------------------------------------- a robot riding the ground

class RidingEpisode(Episode):
    """An ``Episode`` of a robot that rides the ground (a wheeled, legged or MJCF body): the same
    five steps with the body's state read from its free base, its controls written by the body's
    low-level controller, and the terrain watched every tick.

    ``observe`` reads the base (x, y, z, roll, pitch, yaw and velocities,
    ``bodies.base.base_state``), ends the episode at the goal, the time limit or a terrain event
    (``riding.TerrainWatch``: fell, tipped over, stuck on terrain), then scans; ``step_physics``
    has the body turn the setpoint into actuator controls (``body.command``) and steps, recording
    the base's qpos and qvel rows every physics step and looking at the contacts only when the
    chassis touches something (a contact sensor, one float read a step): a contact with an
    obstacle or with a terrain face ends the episode as a collision. The per-tick body work is
    three small calls (``base_state``, ``body.command``, ``watch.check``) so that a batch of
    episodes can be stepped in lockstep later (issue 27).
    """

    world_of = staticmethod(compiled_body_world)

    def __init__(self, scenario, planner, seed, max_ticks=None, *, tick_limit=None, stuck_after=None):
        super().__init__(scenario, planner, seed, max_ticks, tick_limit=tick_limit, stuck_after=stuck_after)
        world = self.world
        self.body = world.body
        self.control = self.body          # the body's controller of this episode (start: body.begin)
        self.base_qpos, self.base_qvel = self.body.views(self.data)
        self.offset = float(self.body.ground_offset)   # the base's origin above its ground (MJCF bodies)
        self.mount = float(scenario.robot.lidar.mount_height) - self.offset
        self.probe = GroundProbe(scenario)
        self.watch = TerrainWatch(scenario, self.body, self.spt * self.dt, self.probe)
        self.sensordata, self.chassis_sensor = self.data.sensordata, world.chassis_sensor
        self.setpoint = (0.0, 0.0, 0.0)
        self.stepping = (self.model, self.data, self.ctrl, self.base_qpos, self.base_qvel, self.pose_buf,
                         self.qvel_buf, range(self.spt - 1))
        # the safety layer's view of the ground, from the 3D lidar's scans (sim/ground/ground_safety.py)
        self.ground = ground_safety(scenario, self.body.drop_limit) if self.cloud is not None else None

    def _allocate_records(self, n_steps: int) -> None:
        super()._allocate_records(n_steps)
        self.pose_buf = np.empty((n_steps, 7))      # the base's qpos rows (x, y, z, quaternion)
        self.qvel_buf = np.empty((n_steps, 6))      # its qvel rows (world linear, local angular)

    def start(self) -> None:
        """The body placed level on the ground at the start pose (on the highest ground under its
        footprint), a collision there ends the episode, then the planner reset."""
        m, d, start = self.model, self.data, self.scenario.mission.start
        z, roll, pitch = resting_pose(self.scenario, start.x, start.y, start.yaw_rad)
        self.body.place(d, start.x, start.y, start.yaw_rad, self.body.start_height(z), roll, pitch)
        try:
            self.control = self.body.begin(d)
        except BodyControllerError as exc:   # the user's controller: a subject error, as a planner's
            self._controller_failed(exc)
        if hasattr(self.control, "deadline"):
            self.control.deadline = self.deadline
        if self.moving is not None:
            self.moving.write(0)
        mujoco.mj_step1(m, d)
        self.pose_buf[0] = self.base_qpos
        self.qvel_buf[0] = self.base_qvel
        MUJOCO_WARNINGS.clear()
        if self.sensordata[self.chassis_sensor] > 0.0:
            self.collision = self.world.first_collision(d, self.obstacles, 0.0)
            if self.collision is not None:
                self.collision = describe_collision(self.collision, self.scenario, self.qvel_buf[0, [0, 1, 5]])
                raise EpisodeOver("collision")
        self._reset_planner()

    def observe(self) -> tuple[tuple[float, ...], Observation]:
        state = base_state(self.base_qpos, self.base_qvel)
        if self.offset:
            state = state[:2] + (state[2] - self.offset,) + state[3:]
        x, y, z, roll, pitch, yaw, vx, vy, vz, wz = state
        t = self.i * self.dt
        if not math.isfinite(x + y + z + yaw + vx + vy + vz + wz):
            raise SimulationDivergedError(divergence_message(self.scenario, self.data, t))
        self.state3d = state
        mission = self.mission
        if mission.goal_reached(t, x, y, yaw):
            raise EpisodeOver("goal")
        tick = self.tick
        if tick >= self.n_ticks:
            raise EpisodeOver("timeout" if tick >= self.timeout_ticks else "max-ticks")
        try:
            self.watch.check(t, state, self.setpoint, self.sensordata[self.chassis_sensor] > 0.0)
        except TerrainStop as stop:
            raise EpisodeOver(stop.reason) from None
        if self.stuck_ticks:
            self.check_stuck(tick, x, y)
        t0 = perf_counter()
        pos, rot = self.base_qpos[:3].copy(), base_rotation(self.base_qpos[3:7])
        lidar = self.lidar
        # the scan plane is the base's, tilted with it: a ramp ahead reads as a wall, a drop is unseen
        ranges = lidar.scan_posed(tick, pos + rot[:, 2] * self.mount, rot)
        self.t_rays += perf_counter() - t0
        self.seen[tick] = (x, y, yaw, vx, vy, wz)
        attitude = np.array([roll, pitch])
        attitude.flags.writeable = False
        points = None
        if self.cloud is not None:   # mounted above the base's ground point, as the 2D lidar
            points = self.scan_cloud(tick, pos - rot[:, 2] * self.offset if self.offset else pos, rot)
            if self.ground is not None:
                t1 = perf_counter()
                self.ground.see(self.cloud.last_origin, self.cloud.world_points(), z)
                self.t_safety += perf_counter() - t1
        obs = _new(Observation)
        obs.__dict__.update(tick=tick, time=t, pose=self.seen_pose[tick], velocity=self.seen_vel[tick],
                            ranges=ranges, angles=lidar.angles, goal=mission.goal,
                            waypoints=mission.left, obstacles=self.obstacles, points=points, attitude=attitude)
        return (t, x, y, yaw, vx, vy, wz), obs

    def steps(self) -> tuple[Any, Any, Any]:
        """``Episode.steps``, with the ground layer's check where a 3D lidar feeds one."""
        safety_check, act, step_physics = super().steps()
        if self.ground is not None:
            safety_check = self.safety_check_ground
        return safety_check, act, step_physics

    def safety_check_ground(self, state: tuple[float, ...]) -> None:
        """The collision layer on the obstacles (as ``safety_check``), then the ground layer on the
        ground the 3D lidar has seen: a halt before a drop or a slope the body cannot take."""
        t, x, y, yaw, vx, vy, wz = state
        if abs(vx) > STILL or abs(vy) > STILL or abs(wz) > STILL:
            t0 = perf_counter()
            hit = None
            if self.safety is not None:
                hit = self.safety.check(x, y, yaw, vx, vy, wz,
                                        self.moving.now(self.i) if self.moving is not None else None)
            ground = None if hit is not None else self.ground.check(x, y, self.state3d[2], yaw, vx, vy, wz)
            self.t_safety += perf_counter() - t0
            if hit is not None:
                self._halt(state, hit)
            if ground is not None:
                self.safety_stop = SafetyStop(t, "", math.hypot(vx, vy), ground=ground)
                self.ctrl[:] = 0.0
                self.record(t, HALT)
                raise EpisodeOver("safety-stop")

    def step_physics(self, setpoint: tuple[float, float, float]) -> None:
        """The tick's physics: the body's controls for the setpoint, then one step at a time, each
        state's base recorded; the contacts are looked at only when the chassis touches something."""
        m, d, ctrl, qpos7, qvel6, pose_buf, qvel_buf, inner = self.stepping
        self.setpoint = setpoint
        try:
            self.control.command(ctrl, setpoint, self.state3d)
        except BodyControllerError as exc:
            self._controller_failed(exc)
        rows = self.moving.rows_for_tick(self.i) if self.moving is not None else None
        mocap = self.moving.mocap_pos if rows is not None else None
        sensordata, k_chassis = self.sensordata, self.chassis_sensor
        step = mujoco.mj_step
        t0 = perf_counter()
        collision = None
        level = self.watch.level          # a face under the ground it stood on is an edge it goes over
        mujoco.mj_step2(m, d)
        i = self.i + 1
        pose_buf[i] = qpos7
        qvel_buf[i] = qvel6
        for k in inner:
            if mocap is not None:
                mocap[:] = rows[k + 1]
            step(m, d)
            if sensordata[k_chassis] > 0.0:
                collision = self.world.first_collision(d, self.obstacles, i * self.dt, level)
                if collision is not None:
                    break
            i += 1
            pose_buf[i] = qpos7
            qvel_buf[i] = qvel6
        else:
            if mocap is not None:
                mocap[:] = rows[self.spt]
            mujoco.mj_step1(m, d)
            if sensordata[k_chassis] > 0.0:
                collision = self.world.first_collision(d, self.obstacles, i * self.dt, level)
        self.i = i
        self.t_physics += perf_counter() - t0
        if collision is not None:
            self.collision = describe_collision(collision, self.scenario, self.qvel_buf[self.i, [0, 1, 5]])
            raise EpisodeOver("collision")
        if MUJOCO_WARNINGS if self.own_handler else self.warn_count.any():
            raise SimulationDivergedError(divergence_message(self.scenario, self.data, self.i * self.dt))

    step_physics_moving = step_physics

    def _controller_failed(self, exc: Exception) -> None:
        """The MJCF body's controller raised, overran its tick or answered nonsense: the episode
        ends as a subject error with its message and traceback (a record in the results file)."""
        cause = exc.__cause__ if exc.__cause__ is not None else exc
        self.failure = SubjectFailure(str(exc), max(0, self.tick - 1), self.i * self.dt, planner_traceback(cause))
        raise EpisodeOver("subject-error") from None

    def trajectory(self) -> Trajectory:
        """The base's recorded rows as x, y, yaw and velocities in the heading frame, plus the
        height, roll and pitch of every physics step."""
        n = self.i + 1
        q, v = self.pose_buf[:n], self.qvel_buf[:n]
        roll, pitch, yaw = quat_to_rpy(q[:, 3], q[:, 4], q[:, 5], q[:, 6])
        pose = np.column_stack([q[:, 0], q[:, 1], (yaw + math.pi) % TWO_PI - math.pi])
        c, s = np.cos(yaw), np.sin(yaw)
        velocity = np.column_stack([c * v[:, 0] + s * v[:, 1], -s * v[:, 0] + c * v[:, 1],
                                    world_yaw_rate(q[:, 3:7], v[:, 3:6])])
        return Trajectory(
            t=np.arange(n) * self.dt, pose=pose, velocity=velocity,
            tick_t=np.array(self.tick_times, dtype=float),
            command=np.array(self.commands, dtype=float).reshape(-1, 3),
            ranges=self.lidar.ranges(self.tick), angles=self.lidar.angles,
            waypoint_times=tuple(self.mission.passed_at),
            believed=None if self.faults is None else self.faults.believed_poses(),
            z=q[:, 2] - self.offset, roll=np.asarray(roll), pitch=np.asarray(pitch),
            cloud=None if self.cloud is None else self.cloud.ranges(self.tick))

    def result(self):
        out = super().result()
        out.terrain_event = self.watch.event
        return out
