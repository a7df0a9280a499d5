"""The observation step of a batch's episodes done for many at once (sim/batching/lockstep.py): a cohort is
the episodes of a batch that share the planar body, their physics steps per tick and timestep and
their lidar's beam layout, in static worlds, without sensor faults or lidar noise.

What ``Episode.observe`` and ``Episode.safety_check`` do per episode, a cohort does per tick with
one array operation for all its running episodes where that cannot change a bit, and with the
episode's own scalar code where it could:

* the records live in cohort-wide arrays (each episode's ``pose_buf``, ``qvel_buf``, ``seen`` and
  lidar record are views of them), so a tick's seen rows and lidar rows are one write each;
* the lidar: the beams' world directions are one stacked matrix product (numpy calls BLAS once per
  episode with exactly ``Lidar.scan``'s shapes), the ray cast is MuJoCo's ``mj_multiRay`` per
  episode (one C call each, into rows of one array), the clamping is one pass;
* the mission (waypoints, goal, time limit, stuck) and the heading's cosine and sine are the
  episode's own Python float code (``math`` and numpy's hypot and arctan2 can differ in the last
  bit, so no vector version of them decides anything);
* the physics: the episodes whose models share MuJoCo's size signature step a tick in one
  ``mujoco.rollout`` call (``step``), their states written into the records in one pass.
"""
from __future__ import annotations

import math
from time import perf_counter
from typing import Any, Callable

import mujoco
import numpy as np

from ...core.errors import SimulationDivergedError
from ...subjects.protocol import Observation
from ..episode import Episode, EpisodeOver
from ..lidar3d import LEVEL
from ..world import CONTACT_SENSOR, LIDAR_HEIGHT, MUJOCO_WARNINGS, TWO_PI, divergence_message

_new = object.__new__
USE_ROLLOUT = True     # step cohorts with mujoco.rollout (False: each episode's own step_physics)


def cohort_key(ep: Episode) -> tuple | None:
    """What the episodes of one cohort share, or None for an episode that runs its own steps."""
    if (type(ep) is not Episode or ep.moving is not None or ep.faults is not None or ep.lidar.rng is not None
            or ep.cloud is not None):     # a 3D lidar's scan is the episode's own observe_cloud
        return None
    return (ep.spt, ep.dt, id(ep.lidar.local_dirs))


class Cohort:
    """Episodes ``eps`` (positions in the batch: ``members``) observed together."""

    def __init__(self, members: list[int], eps: list[Episode]):
        self.members, self.eps = members, eps
        k = len(eps)
        first = eps[0]
        self.spt, self.dt = first.spt, first.dt
        self.local_dirs = first.lidar.local_dirs
        beams = self.beams = first.lidar.beams
        self.pose = np.empty((k, max(len(ep.pose_buf) for ep in eps), 3))
        self.qvel = np.empty_like(self.pose)
        self.seen = np.empty((k, max(len(ep.seen) for ep in eps), 6))
        self.record = np.empty((k, max(len(ep.lidar.record) for ep in eps), beams), dtype=np.float32)
        for j, ep in enumerate(eps):
            self._adopt(j, ep)
        seen_ro = self.seen.view()
        seen_ro.flags.writeable = False
        self.seen_pose, self.seen_vel = seen_ro[:, :, :3], seen_ro[:, :, 3:]
        self.record_ro = self.record.view()
        self.record_ro.flags.writeable = False
        self.rmin_col = np.array([ep.lidar.range_min for ep in eps])[:, None]
        self.rmax_col = np.array([ep.lidar.range_max for ep in eps])[:, None]
        self.rot = np.zeros((k, 3, 3))
        self.dirs = np.empty((k, beams, 3))
        self.pnt = np.empty((k, 3))
        self.pnt[:, 2] = LIDAR_HEIGHT
        self.geom = np.empty((k, beams), dtype=np.int32)
        self.dist = np.empty((k, beams))
        self.seen_now = np.empty((k, 6))
        # the arguments of each mj_multiRay call, made once: the episode's (model, data, groups,
        # body, range_max), and the row views of the n-th scan of a tick (pnt, dirs, geom, dist)
        self.rays = [(ep.lidar.model, ep.lidar.data, ep.lidar.groups, ep.lidar.body, ep.lidar.range_max)
                     for ep in eps]
        self.slots = [(self.pnt[n], self.dirs[n].reshape(-1), self.geom[n], self.dist[n]) for n in range(k)]
        self.safety_checks = [ep.steps()[0] for ep in eps]
        self._physics_tables()

    def _adopt(self, j: int, ep: Episode) -> None:
        """Make the episode's records views of the cohort's arrays (keeping what place() wrote)."""
        n = len(ep.pose_buf)
        done = ep.i + 1                  # the states recorded so far (place(): the start)
        self.pose[j, :done] = ep.pose_buf[:done]
        self.qvel[j, :done] = ep.qvel_buf[:done]
        ep.pose_buf, ep.qvel_buf = self.pose[j, :n], self.qvel[j, :n]
        ep.stepping = ep.stepping[:5] + (ep.pose_buf, ep.qvel_buf, ep.stepping[7])
        ep.seen = self.seen[j, :len(ep.seen)]
        lidar = ep.lidar
        rows = len(lidar.record)
        self.record[j, :ep.tick] = lidar.record[:ep.tick]    # the scans so far (none at the start)
        lidar.record = self.record[j, :rows]
        lidar.readonly = lidar.record.view()
        lidar.readonly.flags.writeable = False

    def _physics_tables(self) -> None:
        """The rollout groups (episodes whose models share MuJoCo's size signature step in one
        ``mujoco.rollout`` call), a scratch MjData per group, and each episode's state now."""
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        first = self.eps[0].model
        self.nstate = mujoco.mj_stateSize(first, spec)
        self.nq, self.nv, self.nu = first.nq, first.nv, first.nu
        self.sensor = int(first.sensor_adr[mujoco.mj_name2id(first, mujoco.mjtObj.mjOBJ_SENSOR, CONTACT_SENSOR)])
        self.state = np.empty((len(self.eps), self.nstate))
        for j, ep in enumerate(self.eps):
            mujoco.mj_getState(ep.model, ep.data, self.state[j], spec)
        self.alone: set[int] = set()      # cohort positions stepping their own data from now on
        self.scratch: dict[int, mujoco.MjData] = {}
        self.models = [ep.model for ep in self.eps]
        self.sig = [m.signature for m in self.models]     # MuJoCo's size signature of each model
        for sig, model in zip(self.sig, self.models):
            if sig not in self.scratch:
                self.scratch[sig] = mujoco.MjData(model)
        # a tick's rollout buffers, made once (a cohort's planar models share nu and nstate)
        k, n = len(self.eps), self.spt + 1
        self.control = np.empty((k, n, self.nu))
        self.states = np.empty((k, n, self.nstate))
        self.sensors = {sig: np.empty((k, n, model.nsensordata)) for sig, model in zip(self.sig, self.models)}

    # ------------------------------------------------------------ one tick

    def observe(self, running: list[int], finish: Callable[[int, str], None],
                fail: Callable[[int, Exception], None]) -> list[tuple[int, tuple, Observation]]:
        """``Episode.observe`` then ``safety_check`` for the cohort positions ``running``: the
        (batch index, state, observation) of each episode that goes on; the others are finished
        (``finish(index, reason)``) or failed (``fail(index, exception)``)."""
        eps = self.eps
        tick = eps[running[0]].tick
        i = tick * self.spt
        t = i * self.dt                  # every running episode is at step i (lockstep)
        idx = np.array(running, dtype=np.intp)
        raw = np.concatenate([self.pose[idx, i], self.qvel[idx, i]], axis=1)
        finite = bool(np.isfinite(raw).all())
        # the heading wrapped to [-pi, pi) as Python's float % does it (np.remainder is the same
        # fmod-and-adjust, bit for bit), for all at once
        raw[:, 2] = (raw[:, 2] + math.pi) % TWO_PI - math.pi
        rows = raw.tolist()
        go: list[int] = []               # cohort positions that scan this tick
        facts: list[tuple] = []          # (x, y, yaw, c, s, wvx, wvy, wz)
        cos, sin = math.cos, math.sin
        for j, row in zip(running, rows):
            x, y, yaw, wvx, wvy, wz = row
            ep = eps[j]
            try:
                if not finite and not math.isfinite(x + y + yaw + wvx + wvy + wz):
                    raise SimulationDivergedError(divergence_message(ep.scenario, ep.data, t))
                if ep.mission.goal_reached(t, x, y, yaw):
                    raise EpisodeOver("goal")
                if tick >= ep.n_ticks:
                    raise EpisodeOver("timeout" if tick >= ep.timeout_ticks else "max-ticks")
                if ep.stuck_ticks:
                    ep.check_stuck(tick, x, y)
            except EpisodeOver as over:
                finish(self.members[j], over.reason)
                continue
            except Exception as exc:
                fail(self.members[j], exc)
                continue
            go.append(j)
            facts.append((x, y, yaw, cos(yaw), sin(yaw), wvx, wvy, wz))
        if not go:
            return []
        k = len(go)
        f = np.array(facts)                                   # (k, 8)
        t1 = perf_counter()
        ranges = self._scan(go, f, tick)
        share = (perf_counter() - t1) / k
        c, s, wvx, wvy = f[:, 3], f[:, 4], f[:, 5], f[:, 6]
        seen = self.seen_now[:k]
        seen[:, 0:3] = f[:, 0:3]
        seen[:, 3] = c * wvx + s * wvy                         # measured velocity, robot frame
        seen[:, 4] = -s * wvx + c * wvy
        seen[:, 5] = f[:, 7]
        self.seen[go, tick] = seen
        seen_rows = seen.tolist()
        seen_pose, seen_vel, members, checks = self.seen_pose, self.seen_vel, self.members, self.safety_checks
        out = []
        for n, j in enumerate(go):
            ep = eps[j]
            ep.t_rays += share
            state = (t, *seen_rows[n])
            try:
                checks[j](state)   # the safety layer, its own code (a vectorised pre-test cost more than it saved)
            except EpisodeOver as over:
                finish(members[j], over.reason)
                continue
            except Exception as exc:
                fail(members[j], exc)
                continue
            obs = _new(Observation)
            obs.__dict__.update(tick=tick, time=t, pose=seen_pose[j, tick], velocity=seen_vel[j, tick],
                                ranges=ranges[n], angles=ep.lidar.angles, goal=ep.mission.goal,
                                waypoints=ep.mission.left, obstacles=ep.obstacles, points=None, attitude=LEVEL)
            out.append((members[j], state, obs))
        return out

    def _scan(self, go: list[int], f: np.ndarray, tick: int) -> list[np.ndarray]:
        """``Lidar.scan`` (no noise) of the cohort positions ``go`` at the rows ``f`` of (x, y,
        yaw, cos, sin, ...): their read-only ranges rows."""
        k = len(go)
        rot = self.rot[:k]
        rot[:, 0, 0] = rot[:, 1, 1] = f[:, 3]
        rot[:, 0, 1] = f[:, 4]
        rot[:, 1, 0] = -f[:, 4]
        np.matmul(self.local_dirs, rot, out=self.dirs[:k])     # one BLAS call per episode, as np.dot
        self.pnt[:k, 0:2] = f[:, 0:2]
        if self.beams:
            ray, beams, slots, rays = mujoco.mj_multiRay, self.beams, self.slots, self.rays
            for n, j in enumerate(go):
                model, data, groups, body, rmax = rays[j]
                pnt, dirs, geom, dist = slots[n]
                ray(model, data, pnt, dirs, groups, 1, body, geom, dist, None, beams, rmax)
        geom, dist = self.geom[:k], self.dist[:k]
        if k == len(self.eps) and go[-1] == k - 1:       # everyone: no gathering
            rmin, rmax, rows = self.rmin_col, self.rmax_col, self.record[:, tick]
            np.maximum(dist, rmin, out=dist)
            np.minimum(dist, rmax, out=dist)
            np.copyto(rows, np.where(geom >= 0, dist, rmax), casting="same_kind")
        else:
            rmin, rmax = self.rmin_col[go], self.rmax_col[go]
            np.maximum(dist, rmin, out=dist)
            np.minimum(dist, rmax, out=dist)
            self.record[go, tick] = np.where(geom >= 0, dist, rmax)
        ro = self.record_ro
        return [ro[j, tick] for j in go]

    def step(self, items: list[tuple[int, tuple[float, float, float]]], finish: Callable[[int, str], None],
             fail: Callable[[int, Exception], None]) -> list[int]:
        """``Episode.step_physics`` for the cohort positions and setpoints ``items``: the batch
        indexes still running after it. The episodes whose models share a size signature take one
        ``mujoco.rollout`` call (spt + 1 steps: the last one only for the contacts of the tick's
        final state, as step_physics's closing mj_step1; its state is dropped). A tick with a contact
        at any of its states, or a MuJoCo warning, is stepped again by the episode's own
        ``step_physics`` from the tick's start (exactly as alone: the state and contacts at the start
        are those of the last tick, which had none), and that episode steps its own data from then on."""
        t0 = perf_counter()
        still: list[int] = []
        replay: list[tuple[int, tuple]] = []
        if self.alone or not USE_ROLLOUT or len(self.scratch) > 1:
            groups: dict[int, list[tuple[int, tuple]]] = {}
            for item in items:
                j = item[0]
                if j in self.alone or not USE_ROLLOUT:
                    replay.append(item)
                else:
                    groups.setdefault(self.sig[j], []).append(item)
        else:
            groups = {self.sig[0]: items}
        spt, nq, nv, eps, members_of = self.spt, self.nq, self.nv, self.eps, self.members
        for sig, members in groups.items():
            k = len(members)
            go = [j for j, _ in members]
            control, states, sensors = self.control[:k], self.states[:k], self.sensors[sig][:k]
            control[:] = np.array([sp for _, sp in members])[:, None, :]
            MUJOCO_WARNINGS.clear()
            scratch = self.scratch[sig]
            _rollout_pool().rollout([self.models[j] for j in go], [scratch], spt + 1,
                                    _CTRL, self.state[go], None, control, states, sensors, None)
            if MUJOCO_WARNINGS or scratch.warning.number.any():   # whose? each steps alone below
                mujoco.mj_resetData(eps[go[0]].model, scratch)
                replay += members
                continue
            touched = sensors[:, 1:, self.sensor].max(axis=1) > 0.0
            if touched.any():
                ok = (~touched).tolist()
                replay += [m for m, good in zip(members, ok) if not good]
                members = [m for m, good in zip(members, ok) if good]
                go = [j for j, _ in members]
                states = states[~touched]
                if not members:
                    continue
            i = eps[go[0]].i
            self.pose[go, i + 1:i + 1 + spt] = states[:, :spt, 1:1 + nq]
            self.qvel[go, i + 1:i + 1 + spt] = states[:, :spt, 1 + nq:1 + nq + nv]
            self.state[go] = states[:, spt - 1]
            i += spt
            for j in go:
                eps[j].i = i
                still.append(members_of[j])
        share = (perf_counter() - t0) / max(1, len(items))
        for j, _ in items:
            eps[j].t_physics += share
        for j, setpoint in replay:
            still += self._step_alone(j, setpoint, finish, fail)
        return still

    def _step_alone(self, j: int, setpoint: tuple, finish, fail) -> list[int]:
        """The tick by the episode's own step_physics (its data brought to the tick's start first,
        the first time): its batch index if it goes on."""
        ep = self.eps[j]
        if j not in self.alone:
            self.alone.add(j)
            mujoco.mj_setState(ep.model, ep.data, self.state[j], mujoco.mjtState.mjSTATE_FULLPHYSICS)
            mujoco.mj_step1(ep.model, ep.data)
        MUJOCO_WARNINGS.clear()
        try:
            ep.step_physics(setpoint)
        except EpisodeOver as over:
            finish(self.members[j], over.reason)
            return []
        except Exception as exc:
            fail(self.members[j], exc)
            return []
        return [self.members[j]]


_ROLLOUT = None
_CTRL = int(mujoco.mjtState.mjSTATE_CTRL)


def _rollout_pool() -> Any:
    global _ROLLOUT
    if _ROLLOUT is None:
        from mujoco import _rollout
        _ROLLOUT = _rollout.Rollout(nthread=0)
    return _ROLLOUT
