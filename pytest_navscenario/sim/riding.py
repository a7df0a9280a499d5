"""An episode of a robot that rides the ground (a wheeled, legged or MJCF body): the planar loop of
``episode.py`` with the body's state read from its free base, its controls written by the body's
low-level controller, and the terrain watched every tick.

Per tick (the same five steps as ``Episode``): ``observe`` reads the base (x, y, z, roll, pitch,
yaw and velocities, ``bodies.base.base_state``), ends the episode at the goal, the time limit, or a
terrain event (``TerrainWatch``: fell, tipped over, stuck on terrain), then scans; ``act`` asks the
planner; ``step_physics`` has the body turn the setpoint into actuator controls (``body.command``)
and steps, recording the base's qpos and qvel rows every physics step and looking at the contacts
only when the chassis touches something (a contact sensor, read each step for a float): a contact
with an obstacle, or with a terrain face, ends the episode as a collision.

The per-tick body work is three small calls (``base_state``, ``body.command``, the watch's
``check``) so that a batch of episodes can be stepped in lockstep later (issue 27).
"""
from __future__ import annotations

import math
from collections import deque
from time import perf_counter
from typing import Any

import mujoco
import numpy as np

from ..core.errors import SimulationDivergedError
from ..scenario import ground
from ..subjects.protocol import Observation
from .bodies.base import base_state, quat_to_rpy, world_yaw_rate
from .episode import Episode, EpisodeOver
from .moving import describe_collision
from .trajectory import TerrainEvent, Trajectory
from .world import MUJOCO_WARNINGS, TWO_PI, divergence_message

_new = object.__new__

ON_GROUND = 0.08          # m: a base this close above the ground under it stands on it
STUCK_TIME = 3.0          # s of being driven without moving that make the robot stuck on terrain
STUCK_COMMAND = 0.1       # m/s: a setpoint at least this fast counts as driving
STUCK_MOVING = 0.25       # of the setpoint's speed: slower than this counts as not moving
LOOK_AHEAD = 0.3          # m beyond the footprint's front where a stuck robot's step is measured


def resting_pose(scenario, x: float, y: float, yaw: float) -> tuple[float, float, float]:
    """(z, roll, pitch) of a body resting on the ground at (x, y, yaw): the plane through the ground
    under the footprint's corners and centre (least squares), raised until no corner is below the
    ground, so a robot starting on a ramp starts on it, not above it."""
    fp = scenario.robot.footprint
    hl, hw = (fp.length / 2, fp.width / 2) if fp.shape == "box" else (fp.radius, fp.radius)
    local = np.array([(hl, hw), (-hl, hw), (-hl, -hw), (hl, -hw), (0.0, 0.0), (hl, 0.0), (-hl, 0.0),
                      (0.0, hw), (0.0, -hw)])
    c, s = math.cos(yaw), math.sin(yaw)
    g = ground.ground_height(scenario, x + c * local[:, 0] - s * local[:, 1], y + s * local[:, 0] + c * local[:, 1])
    a = np.column_stack([np.ones(len(local)), local])
    (z0, gx, gy), *_ = np.linalg.lstsq(a, g, rcond=None)
    z0 += max(0.0, float((g - a @ np.array([z0, gx, gy])).max()))
    return float(z0), float(math.atan(gy)), float(-math.atan(gx))


class GroundProbe:
    """The ground height at one point, fast (plain floats; called a few times a tick): the same
    answer as ``scenario.ground.ground_height``."""

    def __init__(self, scenario):
        self.scenario = scenario
        self.rows = []
        for p in ground.pieces(scenario.terrain):
            el = scenario.terrain[p.element]
            x, y, c, s = ground.frame(el)
            slope = (p.top1 - p.top0) / (p.u1 - p.u0)
            self.rows.append((x, y, c, s, p.u0, p.u1, el.width / 2, p.top0, slope, p.cut, p.element))
        self.grids = bool(ground.grid_elements(scenario.terrain))

    def height(self, px: float, py: float) -> float:
        if self.grids:
            return float(ground.ground_height(self.scenario, px, py))
        solid, floor = -math.inf, 0.0
        for x, y, c, s, u0, u1, hw, top0, slope, cut, _ in self.rows:
            dx, dy = px - x, py - y
            u = c * dx + s * dy
            if u < u0 - 1e-9 or u > u1 + 1e-9 or abs(-s * dx + c * dy) > hw + 1e-9:
                continue
            h = top0 + slope * (u - u0)
            if cut:
                floor = h if h < floor else floor
            elif h > solid:
                solid = h
        return solid if solid > floor else floor

    def element(self, px: float, py: float) -> int | None:
        """The element whose top is the ground at (px, py) (None: the floor)."""
        best, best_h = None, -math.inf
        for x, y, c, s, u0, u1, hw, top0, slope, cut, i in self.rows:
            dx, dy = px - x, py - y
            u = c * dx + s * dy
            if u0 - 1e-9 <= u <= u1 + 1e-9 and abs(-s * dx + c * dy) <= hw + 1e-9:
                h = top0 + slope * (u - u0)
                if best is None or h > best_h or (cut and h < 0.0 and best_h <= 0.0):
                    best, best_h = i, h
        if best is None and self.grids:
            return ground.element_at(self.scenario, px, py)
        return best


class TerrainWatch:
    """Per tick, from the base's state: a fall (the base dropped more than the body's
    ``drop_limit`` below the ground it last stood on), a tip-over (roll or pitch past its
    ``tip_angle``) or being stuck on terrain (driven at STUCK_COMMAND or more for STUCK_TIME
    seconds and getting less than STUCK_MOVING of the way those setpoints asked for: rocking back
    and forth at the foot of a slope counts). Each raises EpisodeOver with the event
    kept in ``event``. A classification of what the physics did: nothing here moves the robot."""

    def __init__(self, scenario, body, tick_dt: float, probe: GroundProbe):
        self.scenario, self.body, self.probe = scenario, body, probe
        self.drop_limit = float(body.drop_limit)
        self.tip = math.radians(body.tip_angle)
        self.stuck_ticks = max(1, round(STUCK_TIME / tick_dt))
        self.level = None           # the ground height it last stood on, and where
        self.level_at = (0.0, 0.0)
        self.pushing = 0            # ticks driven in a row
        self.tick_dt = tick_dt
        self.trail: deque = deque(maxlen=self.stuck_ticks + 1)   # (x, y, setpoint speed) of those ticks
        self.event: TerrainEvent | None = None
        fp = scenario.robot.footprint
        self.front = fp.length / 2 if fp.shape == "box" else fp.radius

    def check(self, t: float, state: tuple[float, ...], setpoint: tuple[float, float, float],
              touching: bool) -> None:
        x, y, z, roll, pitch, yaw, vx, vy, vz, wz = state
        g = self.probe.height(x, y)
        if self.level is None or z - g < ON_GROUND:
            self.level, self.level_at = g, (x, y)
        elif self.level - z > self.drop_limit:
            self._end(TerrainEvent("fell", t, self._fell_from(x, y), x, y, z, drop=self.level - g,
                                   roll=math.degrees(roll), pitch=math.degrees(pitch)))
        if abs(roll) > self.tip or abs(pitch) > self.tip:
            el = self.probe.element(x, y)
            self._end(TerrainEvent("tipped", t, self._name(el), x, y, z, roll=math.degrees(roll),
                                   pitch=math.degrees(pitch)))
        speed = abs(setpoint[0]) + abs(setpoint[1])
        if speed < STUCK_COMMAND:
            self.pushing = 0
            self.trail.clear()
            return
        self.pushing += 1
        self.trail.append((x, y, speed))
        if self.pushing >= self.stuck_ticks:
            x0, y0, _ = self.trail[0]
            asked = sum(v for _, _, v in self.trail) * self.tick_dt
            if math.hypot(x - x0, y - y0) < STUCK_MOVING * asked:
                self._stuck(t, x, y, z, roll, pitch, yaw, setpoint, touching)

    def _name(self, element: int | None) -> str:
        return "" if element is None else ground.describe_element(self.scenario.terrain[element])

    def _fell_from(self, x: float, y: float) -> str:
        """"off platform 'dock'" (the raised element it stood on), "into pit 'p'" (the hole it is
        over), or "" (an edge of the plain floor)."""
        below = self.probe.element(x, y)
        if below is not None and self.probe.height(x, y) < 0.0:
            return "into " + self._name(below)
        above = self.probe.element(*self.level_at)
        return "off " + self._name(above) if above is not None else ""

    def _stuck(self, t, x, y, z, roll, pitch, yaw, setpoint, touching) -> None:
        """What holds the robot: a step ahead (measured on the ground along its way), the slope it
        is on, or its chassis resting on the ground (high-centred)."""
        ahead = 1.0 if setpoint[0] >= 0 else -1.0
        c, s = math.cos(yaw), math.sin(yaw)
        here = self.probe.height(x, y)
        best, where = here, None
        for k in range(1, 7):
            d = ahead * (self.front + LOOK_AHEAD * k / 6)
            h = self.probe.height(x + c * d, y + s * d)
            if h > best:
                best, where = h, (x + c * d, y + s * d)
        slope = math.degrees(max(abs(pitch), abs(roll)))
        if where is not None and best - here > 0.01:
            el = self.probe.element(*where)
            detail = f"cannot climb the {best - here:.2f} m step"
        elif slope > 3.0:
            el = self.probe.element(x, y)
            detail = f"cannot climb the {slope:.0f} deg slope"
        else:
            el = self.probe.element(x, y)
            detail = "high-centred: its chassis rests on the ground" if touching else "its wheels slip"
        self._end(TerrainEvent("stuck", t, self._name(el), x, y, z, roll=math.degrees(roll),
                               pitch=math.degrees(pitch), detail=detail))

    def _end(self, event: TerrainEvent) -> None:
        self.event = event
        raise EpisodeOver("stuck-terrain" if event.kind == "stuck" else event.kind)


class RidingEpisode(Episode):
    """An ``Episode`` of a body that rides the ground (see the module docstring)."""

    def __init__(self, scenario, planner, seed, max_ticks=None, *, tick_limit=None, stuck_after=None):
        super().__init__(scenario, planner, seed, max_ticks, tick_limit=tick_limit, stuck_after=stuck_after)
        world = self.world
        self.body = world.body
        self.base_qpos, self.base_qvel = self.body.views(self.data)
        self.mount = float(scenario.robot.lidar.mount_height)
        self.probe = GroundProbe(scenario)
        self.watch = TerrainWatch(scenario, self.body, self.spt * self.dt, self.probe)
        self.sensordata, self.chassis_sensor = self.data.sensordata, world.chassis_sensor
        self.setpoint = (0.0, 0.0, 0.0)
        self.stepping = (self.model, self.data, self.ctrl, self.base_qpos, self.base_qvel, self.pose_buf,
                         self.qvel_buf, range(self.spt - 1))

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

    def _reset_planner(self) -> None:
        from .command import call_planner, planner_traceback
        from .deadline import PlannerTimeout
        from .trajectory import SubjectFailure
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

    def observe(self) -> tuple[tuple[float, ...], Observation]:
        state = base_state(self.base_qpos, self.base_qvel)
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
        self.watch.check(t, state, self.setpoint, self.sensordata[self.chassis_sensor] > 0.0)
        if self.stuck_ticks:
            self.check_stuck(tick, x, y)
        t0 = perf_counter()
        c, s = math.cos(yaw), math.sin(yaw)
        lidar = self.lidar
        lidar.pnt[2] = z + self.mount          # the scan plane rides with the base (level: sim/lidar.py)
        ranges = lidar.scan(tick, x, y, c, s)
        self.t_rays += perf_counter() - t0
        self.seen[tick] = (x, y, yaw, vx, vy, wz)
        obs = _new(Observation)
        obs.__dict__.update(tick=tick, time=t, pose=self.seen_pose[tick], velocity=self.seen_vel[tick],
                            ranges=ranges, angles=lidar.angles, goal=mission.goal,
                            waypoints=mission.left, obstacles=self.obstacles)
        return (t, x, y, yaw, vx, vy, wz), obs

    def step_physics(self, setpoint: tuple[float, float, float]) -> None:
        """The tick's physics: the body's controls for the setpoint, then one step at a time, each
        state's base recorded; the contacts are looked at only when the chassis touches something."""
        m, d, ctrl, qpos7, qvel6, pose_buf, qvel_buf, inner = self.stepping
        self.setpoint = setpoint
        self.body.command(ctrl, setpoint, self.state3d)
        rows = self.moving.rows_for_tick(self.i) if self.moving is not None else None
        mocap = self.moving.mocap_pos if rows is not None else None
        sensordata, k_chassis = self.sensordata, self.chassis_sensor
        step = mujoco.mj_step
        t0 = perf_counter()
        collision = None
        mujoco.mj_step2(m, d)
        i = self.i + 1
        pose_buf[i] = qpos7
        qvel_buf[i] = qvel6
        for k in inner:
            if mocap is not None:
                mocap[:] = rows[k + 1]
            step(m, d)
            if sensordata[k_chassis] > 0.0:
                collision = self.world.first_collision(d, self.obstacles, i * self.dt)
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
                collision = self.world.first_collision(d, self.obstacles, i * self.dt)
        self.i = i
        self.t_physics += perf_counter() - t0
        if collision is not None:
            self.collision = describe_collision(collision, self.scenario, self.qvel_buf[self.i, [0, 1, 5]])
            raise EpisodeOver("collision")
        if MUJOCO_WARNINGS if self.own_handler else self.warn_count.any():
            raise SimulationDivergedError(divergence_message(self.scenario, self.data, self.i * self.dt))

    step_physics_moving = step_physics

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
            z=q[:, 2].copy(), roll=np.asarray(roll), pitch=np.asarray(pitch))

    def result(self):
        out = super().result()
        out.terrain_event = self.watch.event
        return out
