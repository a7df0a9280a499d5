"""The warp batch engine's loop (sim/batching/warp_engine.py): the CPU lockstep loop (lockstep.py) with the
physics, the contact checks, the state recording and the lidar's ray casts of every episode done
on a MuJoCo Warp device, a control tick at a time (warp_worlds.py).

What stays on the host, per episode, is the ``Episode``'s own code, so that it means exactly what
it means on the CPU engine: the start pose's contact check (``Episode.place``, one ``mj_step1``),
the mission (waypoints, goal, time limit, stuck), the lidar's noise (drawn from the episode's
seed, on the device's distances), the safety layer, sensor faults, the drive's limits, the
records and the result. The planner gets one ``act_batch`` call a tick, as on the CPU engine, and
its failures mean the same (``Lockstep._act``).
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..episode import EpisodeOver
from .lockstep import Lockstep
from ..moving import describe_collision
from ..trajectory import Collision
from .warp_worlds import DeviceWorlds, group_key


class DeviceOverflow(RuntimeError):
    """MuJoCo Warp ran out of contact or constraint slots in an episode's world."""


class _Group:
    """A ``DeviceWorlds`` and the host's copies of its worlds' current states and scans."""

    def __init__(self, members: list[int], worlds: DeviceWorlds):
        self.members, self.worlds = members, worlds
        self.position = {i: w for w, i in enumerate(members)}
        eps = worlds.eps
        self.qpos = np.array([ep.qpos for ep in eps], dtype=float)     # the start states, exactly
        self.qvel = np.array([ep.qvel for ep in eps], dtype=float)
        self.dist, self.geom = worlds.rays()
        self.ctrl = np.zeros((worlds.n, eps[0].model.nu))
        self.mocap = (np.zeros((worlds.n, worlds.spt + 1, worlds.nmocap, 3)) if worlds.nmocap else None)


class _DeviceScan:
    """An episode's ``lidar.scan`` fed by the device's ray casts: the distances of its world's
    last scan, then the CPU lidar's own recording and noise (``Lidar._record``)."""

    def __init__(self, lidar: Any, group: _Group, w: int):
        self.lidar, self.group, self.w = lidar, group, w

    def __call__(self, tick: int, x: float, y: float, c: float, s: float) -> np.ndarray:
        lidar = self.lidar
        geom, dist = lidar.geom, lidar.dist
        geom[:] = self.group.geom[self.w]
        dist[:] = self.group.dist[self.w]
        geom[dist > lidar.range_max] = -1     # beyond the range: no return (mj_multiRay's cutoff)
        return lidar._record(tick, dist, lidar.range_min, lidar.range_max)


class WarpLockstep(Lockstep):
    """One batch on the device: ``run()`` returns each request's SimResult or exception."""

    def __init__(self, requests: Sequence[Any], planner: Any, device: Any = None, graph: bool = True):
        super().__init__(requests, planner)
        self.device, self.graph = device, graph
        self.device_seconds = 0.0

    def _form_cohorts(self, running: list[int]) -> None:
        """The started episodes grouped into device models (``group_key``), their start states'
        kinematics and scans computed, each episode's state and lidar read from its group."""
        keys: dict[tuple, list[int]] = {}
        for i in running:
            keys.setdefault(group_key(self.episodes[i]), []).append(i)
        self.groups: list[_Group] = []
        for members in keys.values():
            worlds = DeviceWorlds([self.episodes[i] for i in members], self.device, self.graph)
            seconds = worlds.start()
            self.device_seconds += seconds
            group = _Group(members, worlds)
            for w, i in enumerate(members):
                ep = self.episodes[i]
                ep.t_rays += seconds / len(members)
                ep.qpos, ep.qvel = group.qpos[w], group.qvel[w]
                ep.lidar.scan = _DeviceScan(ep.lidar, group, w)
            self.groups.append(group)

    def _tick(self, running: list[int], steps: dict, deadline: Any) -> list[int]:
        """One control tick: observe and check on the host, one planner call, the physics of
        every group with a running episode on the device, the records on the host."""
        seen = [item for item in (self._observe(i, steps) for i in running) if item is not None]
        if not seen:
            return []
        answers = self._act([i for i, _, _ in seen], [obs for _, _, obs in seen])
        setpoints: dict[int, tuple] = {}
        for (i, state, obs), answer in zip(seen, answers):
            setpoint = self._setpoint(i, answer, state, obs)
            if setpoint is not None:
                setpoints[i] = setpoint
        still = []
        for group in self.groups:
            moving = [i for i in group.members if i in setpoints]
            if moving:
                still += self._step_group(group, moving, setpoints)
        still.sort()
        return still

    def _step_group(self, group: _Group, moving: list[int], setpoints: dict[int, tuple]) -> list[int]:
        """One tick of a group's worlds; the episodes of ``moving`` that go on."""
        group.ctrl[:] = 0.0            # worlds whose episode ended hold still
        for i in moving:
            w = group.position[i]
            group.ctrl[w] = setpoints[i]
            ep = self.episodes[i]
            if group.mocap is not None:
                group.mocap[w] = ep.moving.rows_for_tick(ep.i)
        out = group.worlds.tick(group.ctrl, group.mocap)
        self.device_seconds += out.seconds
        group.dist, group.geom = group.worlds.rays()
        share = out.seconds / len(moving)
        still = []
        for i in moving:
            ep = self.episodes[i]
            ep.t_physics += share
            if self._goes_on(i, self._advance, ep, group, group.position[i], out):
                still.append(i)
        return still

    @staticmethod
    def _advance(ep: Any, group: _Group, w: int, out: Any) -> None:
        """The episode's states of the tick recorded (up to its first collision, which ends it);
        its current state for the next observation."""
        if out.overflow[w]:
            raise DeviceOverflow(
                f"MuJoCo Warp ran out of contact or constraint slots (overflow bits {int(out.overflow[w])}) "
                f"in the world of scenario {ep.scenario.name or '<unnamed>'} by t={(ep.i + ep.spt) * ep.dt:.3f} s: "
                f"its contacts cannot be trusted; run it on the CPU engine (--nav-batch-engine=cpu)")
        spt, i0 = ep.spt, ep.i
        hit = int(out.hit_step[w])
        last = hit if hit >= 0 else spt
        ep.pose_buf[i0 + 1:i0 + last + 1] = out.pose[w, 1:last + 1]
        ep.qvel_buf[i0 + 1:i0 + last + 1] = out.vel[w, 1:last + 1]
        ep.i = i0 + last
        if hit >= 0:
            pos = out.hit_pos[w]
            found = Collision(ep.i * ep.dt, ep.obstacles[int(out.hit_obstacle[w])].name, float(pos[0]),
                              float(pos[1]), float(out.hit_depth[w]))
            ep.collision = describe_collision(found, ep.scenario, ep.qvel_buf[ep.i])
            raise EpisodeOver("collision")
        group.qpos[w] = out.pose[w, spt]
        group.qvel[w] = out.vel[w, spt]
