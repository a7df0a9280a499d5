"""One episode of a robot that rides the ground (a wheeled, legged or MJCF body): the
``RidingEpisode``, the planar loop's ``Episode`` (loop.py) with the body's free base, its
controller and the terrain watched every tick.
"""
from __future__ import annotations

import math
from time import perf_counter
from typing import Any

import mujoco
import numpy as np

from ..core.errors import SimulationDivergedError
from ..subjects.protocol import Observation
from .command import planner_traceback
from .ground.ground_safety import ground_safety
from .lidar import base_rotation
from .moving import describe_collision
from .trajectory import SafetyStop, SubjectFailure, Trajectory
from .world import MUJOCO_WARNINGS, TWO_PI, divergence_message
from ..scenario.ground import surface as ground
from .bodies.base import base_state, quat_to_rpy, world_yaw_rate
from .bodies.mjcf import BodyControllerError
from .body_world import compiled_body_world
from .loop import HALT, STILL, Episode, EpisodeOver
from .ground.riding import GroundProbe, TerrainStop, TerrainWatch, resting_pose

_new = object.__new__


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
        self.watch.chassis_on_ground = lambda: world.chassis_on_ground(self.data)
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
        if self.ground is not None or (self.safety is not None and self.safety.low_side):
            safety_check = self.safety_check_ground
        return safety_check, act, step_physics

    def safety_check_ground(self, state: tuple[float, ...]) -> None:
        """The collision layer on the obstacles and the terrain's faces (as ``safety_check``, at
        the base's height: a face is a wall from below), then the ground layer on the ground the
        3D lidar has seen (if it has one): a halt before a drop or a slope the body cannot take."""
        t, x, y, yaw, vx, vy, wz = state
        if abs(vx) > STILL or abs(vy) > STILL or abs(wz) > STILL:
            t0 = perf_counter()
            hit = None
            z = self.state3d[2]
            if self.safety is not None:
                hit = self.safety.check(x, y, yaw, vx, vy, wz,
                                        self.moving.now(self.i) if self.moving is not None else None, z=z)
            ground = (None if hit is not None or self.ground is None
                      else self.ground.check(x, y, z, yaw, vx, vy, wz))
            self.t_safety += perf_counter() - t0
            if hit is not None:
                self._halt(state, hit)
            if ground is not None:
                self.safety_stop = SafetyStop(t, "", math.hypot(vx, vy), ground=ground, yaw_rate=wz)
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
