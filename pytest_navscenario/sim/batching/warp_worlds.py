"""A batch's planar worlds on a MuJoCo Warp device (sim/batching/warp_engine.py): one ``mujoco_warp`` model
and data holding many worlds, stepped a control tick at a time, with the contact checks, the
recording of every physics step's state and the lidar's ray casts done on the device.

Episodes share one device model when their compiled MuJoCo models differ only in fields MuJoCo
Warp holds per world (the fields whose shape starts with ``*`` in ``mujoco_warp.Model``: geom
positions, sizes and bounding boxes, body poses and inertias, actuator gains and force ranges...):
a search's candidates around one seed move and resize the seed's obstacles, so they share one.
``group_key`` says which episodes can; ``DeviceWorlds`` is one such group.

A tick on the device, the order of the CPU episode's ``step_physics`` (sim/episode.py):
``step2`` (finishing the step whose ``step1`` ran at the tick start), then ``spt - 1`` full
``step`` calls, each computing the contacts of the state it starts from, then a ``step1`` for the
contacts and kinematics of the tick's last state. After each of those the contact kernel latches,
per world, the first step whose state has a robot-obstacle penetration and that contact (the
deepest); the record kernel writes every state's qpos and qvel into a (worlds, spt + 1, 3) table.
Moving obstacles (mocap bodies) are written before each state's kinematics from a table the host
fills per tick (``MovingObstacles.rows_for_tick``, the CPU engine's positions). The lidar's beams
are then cast for every world at once (``mujoco_warp.rays``) from the tick's last state. The host
reads back one table of states, the latched collisions, the ray distances and the overflow flags.
"""
from __future__ import annotations

import dataclasses
import hashlib
import logging
from time import perf_counter
from typing import Any, Sequence

import mujoco
import mujoco_warp as mjw
import numpy as np
import warp as wp

log = logging.getLogger(__name__)

CONTACTS_PER_WORLD = 64      # contact slots per world (the robot against the obstacles near it)
CONSTRAINTS_PER_WORLD = 256  # constraint rows per world (a pyramidal contact of condim 3 has 4)

# the MjModel fields MuJoCo Warp holds per world (its Model fields whose shape starts with "*")
PER_WORLD = frozenset(f.name for f in dataclasses.fields(mjw.Model)
                      if (getattr(f.type, "shape", None) or (None,))[0] == "*")
# MjModel fields that MuJoCo Warp's step never reads (names, the host's own BVH and inertia at qpos0)
NOT_ON_DEVICE = frozenset({"names", "names_map", "paths", "text_data", "bvh_aabb", "dof_M0"})


def _model_arrays(model: mujoco.MjModel) -> dict[str, np.ndarray]:
    out = {}
    for name in dir(model):
        if name.startswith("_") or name.startswith("name_") or name in NOT_ON_DEVICE:
            continue
        value = getattr(model, name, None)
        if isinstance(value, np.ndarray):
            out[name] = value
    return out


def _option_values(model: mujoco.MjModel) -> tuple:
    opt = model.opt
    return tuple((name, np.asarray(getattr(opt, name)).tobytes()) for name in sorted(dir(opt))
                 if not name.startswith("_") and isinstance(getattr(opt, name), (int, float, np.ndarray)))


_KEYS: dict[int, tuple[mujoco.MjModel, str]] = {}


def structure_key(model: mujoco.MjModel) -> str:
    """A digest of everything in ``model`` that MuJoCo Warp cannot hold per world: models with the
    same digest can be worlds of one device model (cached per model object)."""
    cached = _KEYS.get(id(model))
    if cached is not None and cached[0] is model:
        return cached[1]
    h = hashlib.sha256()
    for name, value in sorted(_model_arrays(model).items()):
        if name in PER_WORLD:
            h.update(f"{name}:{value.shape}".encode())
        else:
            h.update(name.encode())
            h.update(np.ascontiguousarray(value).tobytes())
    h.update(repr(_option_values(model)).encode())
    key = h.hexdigest()
    if len(_KEYS) > 4096:
        _KEYS.clear()
    _KEYS[id(model)] = (model, key)
    return key


def group_key(ep: Any) -> tuple:
    """Episodes with equal keys can be worlds of one ``DeviceWorlds``: the same physics steps per
    tick and timestep, the same lidar beams and a model structure MuJoCo Warp can batch."""
    return (ep.spt, ep.dt, ep.lidar.beams, ep.lidar.local_dirs.tobytes(), structure_key(ep.model))


# ---------------------------------------------------------------- kernels

@wp.kernel
def _beams(qpos: wp.array2d(dtype=float), local: wp.array(dtype=wp.vec3), height: wp.array(dtype=float),
           pnt: wp.array2d(dtype=wp.vec3), vec: wp.array2d(dtype=wp.vec3)):
    """Each world's beam origins and directions from its robot's pose (the lidar of sim/lidar.py)."""
    w, b = wp.tid()
    yaw = qpos[w, 2]
    c = wp.cos(yaw)
    s = wp.sin(yaw)
    d = local[b]
    pnt[w, b] = wp.vec3(qpos[w, 0], qpos[w, 1], height[w])
    vec[w, b] = wp.vec3(d[0] * c - d[1] * s, d[0] * s + d[1] * c, 0.0)


@wp.kernel
def _record(qpos: wp.array2d(dtype=float), qvel: wp.array2d(dtype=float), k: int,
            pose: wp.array3d(dtype=float), vel: wp.array3d(dtype=float)):
    """Row ``k`` of the tick's state table: each world's (x, y, yaw) and its velocities."""
    w, j = wp.tid()
    pose[w, k, j] = qpos[w, j]
    vel[w, k, j] = qvel[w, j]


@wp.kernel
def _set_mocap(table: wp.array3d(dtype=wp.vec3), k: int, mocap_pos: wp.array2d(dtype=wp.vec3)):
    """The moving obstacles where they are at the tick's step ``k``."""
    w, j = wp.tid()
    mocap_pos[w, j] = table[w, k, j]


@wp.kernel
def _deepest(nacon: wp.array(dtype=int), dist: wp.array(dtype=float), geom: wp.array(dtype=wp.vec2i),
             worldid: wp.array(dtype=int), robot_geom: int, obstacle_of_geom: wp.array(dtype=int),
             deepest: wp.array(dtype=float)):
    """Per world, the deepest robot-obstacle penetration among the current contacts."""
    c = wp.tid()
    if c >= nacon[0]:
        return
    d = dist[c]
    if d >= 0.0:
        return
    g = geom[c]
    other = int(-1)
    if g[0] == robot_geom:
        other = g[1]
    elif g[1] == robot_geom:
        other = g[0]
    if other < 0:
        return
    if obstacle_of_geom[other] < 0:
        return
    wp.atomic_min(deepest, worldid[c], d)


@wp.kernel
def _which(nacon: wp.array(dtype=int), dist: wp.array(dtype=float), geom: wp.array(dtype=wp.vec2i),
           worldid: wp.array(dtype=int), robot_geom: int, deepest: wp.array(dtype=float),
           chosen: wp.array(dtype=int)):
    """Per world, the (highest) index of a robot contact as deep as the deepest."""
    c = wp.tid()
    if c >= nacon[0]:
        return
    g = geom[c]
    if g[0] != robot_geom and g[1] != robot_geom:
        return
    w = worldid[c]
    if dist[c] == deepest[w]:
        wp.atomic_max(chosen, w, c)


@wp.kernel
def _latch(step: int, chosen: wp.array(dtype=int), geom: wp.array(dtype=wp.vec2i), pos: wp.array(dtype=wp.vec3),
           robot_geom: int, obstacle_of_geom: wp.array(dtype=int), deepest: wp.array(dtype=float),
           hit_step: wp.array(dtype=int), hit_obstacle: wp.array(dtype=int), hit_pos: wp.array(dtype=wp.vec3),
           hit_depth: wp.array(dtype=float)):
    """A world's first collision of the tick (its step, obstacle, point and depth), kept; the
    per-step scratch cleared."""
    w = wp.tid()
    c = chosen[w]
    if c >= 0 and hit_step[w] < 0:
        g = geom[c]
        other = g[1]
        if g[1] == robot_geom:
            other = g[0]
        hit_step[w] = step
        hit_obstacle[w] = obstacle_of_geom[other]
        hit_pos[w] = pos[c]
        hit_depth[w] = -deepest[w]
    chosen[w] = -1
    deepest[w] = 1.0e30


# ---------------------------------------------------------------- the worlds of a group

@dataclasses.dataclass
class TickOut:
    """What the host reads back after a tick (numpy arrays, one row per world)."""
    pose: np.ndarray        # (worlds, spt + 1, 3) qpos of the tick's states (row 0: its start)
    vel: np.ndarray         # (worlds, spt + 1, 3) their qvel
    hit_step: np.ndarray    # (worlds,) the tick's step (1..spt) whose state collided first, or -1
    hit_obstacle: np.ndarray
    hit_pos: np.ndarray     # (worlds, 3)
    hit_depth: np.ndarray
    overflow: np.ndarray    # (worlds,) MuJoCo Warp's overflow bits (contacts, constraints...)
    seconds: float          # device time of the tick (launches and read-back)


class DeviceWorlds:
    """Episodes ``eps`` (all of one ``group_key``) as the worlds of one MuJoCo Warp model on
    ``device``. ``start()`` computes the start states' kinematics and scans; ``tick(ctrl, mocap)``
    steps every world one control tick; ``rays()`` gives the last scans."""

    def __init__(self, eps: Sequence[Any], device: Any = None, graph: bool = True):
        self.eps = list(eps)
        self.n = n = len(self.eps)
        first = self.eps[0]
        self.spt, self.dt = first.spt, first.dt
        self.device = wp.get_device(device)
        models = [ep.model for ep in self.eps]
        mjm = models[0]
        self.nmocap = mjm.nmocap
        beams = first.lidar.beams
        with wp.ScopedDevice(self.device):
            varying = _varying_fields(models)
            self.m = mjw.put_model(mjm, batch_sizes={name: n for name in varying})
            for name, stacked in varying.items():
                field = getattr(self.m, name)
                field.assign(stacked.reshape(field.shape + tuple(getattr(field.dtype, "_shape_", ()))))
            self.d = mjw.make_data(mjm, nworld=n, naconmax=n * CONTACTS_PER_WORLD, njmax=CONSTRAINTS_PER_WORLD)
            self._adopt_host_states()
            self.robot_geom = first.world.robot_geom
            lookup = np.full(mjm.ngeom, -1, dtype=np.int32)
            for g, i in first.world.obstacle_of_geom.items():
                lookup[g] = i
            self.obstacle_of_geom = wp.array(lookup, dtype=int)
            self.local = wp.array(np.asarray(first.lidar.local_dirs, dtype=np.float32), dtype=wp.vec3)
            self.height = wp.array(np.array([ep.lidar.mount for ep in self.eps], dtype=np.float32), dtype=float)
            self.pnt = wp.zeros((n, beams), dtype=wp.vec3)
            self.vec = wp.zeros((n, beams), dtype=wp.vec3)
            self.dist = wp.zeros((n, beams), dtype=float)
            self.geomid = wp.zeros((n, beams), dtype=int)
            self.normal = wp.zeros((n, beams), dtype=wp.vec3)
            self.exclude = wp.array(np.full(beams, first.world.robot_body, dtype=np.int32), dtype=int)
            self.groups = _ray_groups(first.lidar.groups)
            self.pose = wp.zeros((n, self.spt + 1, 3), dtype=float)
            self.vel = wp.zeros((n, self.spt + 1, 3), dtype=float)
            self.ctrl = wp.zeros((n, mjm.nu), dtype=float)
            self.mocap = wp.zeros((n, self.spt + 1, max(self.nmocap, 1)), dtype=wp.vec3)
            self.deepest = wp.full(n, 1.0e30, dtype=float)
            self.chosen = wp.full(n, -1, dtype=int)
            self.hit_step = wp.full(n, -1, dtype=int)
            self.hit_obstacle = wp.full(n, -1, dtype=int)
            self.hit_pos = wp.zeros(n, dtype=wp.vec3)
            self.hit_depth = wp.zeros(n, dtype=float)
        self.graph = None
        self.use_graph = graph and self.device.is_cuda

    def _adopt_host_states(self) -> None:
        """Each world's state from its episode's host data after ``Episode.place`` (qpos, mocap
        bodies, and the frames of the bodies and geoms MuJoCo Warp computes once and never again:
        ``make_data`` copies the first model's static geom frames into every world, and a world
        whose obstacles stand elsewhere must have its own)."""
        datas = [ep.data for ep in self.eps]
        d = self.d

        def put(field: Any, values: list) -> None:
            field.assign(np.array(values, dtype=np.float32).reshape(field.shape + tuple(getattr(field.dtype, "_shape_", ()))))

        put(d.qpos, [x.qpos for x in datas])
        put(d.xpos, [x.xpos for x in datas])
        put(d.xquat, [x.xquat for x in datas])
        put(d.xmat, [x.xmat for x in datas])
        put(d.ximat, [x.ximat for x in datas])
        put(d.geom_xpos, [x.geom_xpos for x in datas])
        put(d.geom_xmat, [x.geom_xmat for x in datas])
        if self.nmocap:
            put(d.mocap_pos, [x.mocap_pos for x in datas])
            put(d.mocap_quat, [x.mocap_quat for x in datas])

    # ------------------------------------------------------------ launches

    def _check(self, k: int) -> None:
        d, n = self.d, self.n
        con = d.contact
        wp.launch(_deepest, dim=d.naconmax, inputs=[d.nacon, con.dist, con.geom, con.worldid, self.robot_geom,
                                                   self.obstacle_of_geom, self.deepest])
        wp.launch(_which, dim=d.naconmax, inputs=[d.nacon, con.dist, con.geom, con.worldid, self.robot_geom,
                                                 self.deepest, self.chosen])
        wp.launch(_latch, dim=n, inputs=[k, self.chosen, con.geom, con.pos, self.robot_geom, self.obstacle_of_geom,
                                        self.deepest, self.hit_step, self.hit_obstacle, self.hit_pos,
                                        self.hit_depth])

    def _record(self, k: int) -> None:
        wp.launch(_record, dim=(self.n, 3), inputs=[self.d.qpos, self.d.qvel, k, self.pose, self.vel])

    def _mocap(self, k: int) -> None:
        if self.nmocap:
            wp.launch(_set_mocap, dim=(self.n, self.nmocap), inputs=[self.mocap, k, self.d.mocap_pos])

    def _scan(self) -> None:
        wp.launch(_beams, dim=(self.n, self.local.shape[0]), inputs=[self.d.qpos, self.local, self.height,
                                                                      self.pnt, self.vec])
        if self.local.shape[0]:
            mjw.rays(self.m, self.d, self.pnt, self.vec, self.groups, True, self.exclude, self.dist,
                     self.geomid, self.normal)

    def _tick_launches(self) -> None:
        """One control tick of every world (see the module docstring)."""
        m, d = self.m, self.d
        wp.copy(d.ctrl, self.ctrl)
        self.hit_step.fill_(-1)
        self._record(0)
        mjw.step2(m, d)
        self._record(1)
        for k in range(1, self.spt):
            self._mocap(k)
            mjw.step(m, d)
            self._check(k)
            self._record(k + 1)
        self._mocap(self.spt)
        mjw.step1(m, d)
        self._check(self.spt)
        self._scan()

    # ------------------------------------------------------------ the host's calls

    def start(self) -> float:
        """Kinematics, contacts and scans of the start states (the host checked their contacts
        already: ``Episode.place``); the device seconds."""
        t0 = perf_counter()
        with wp.ScopedDevice(self.device):
            mjw.step1(self.m, self.d)
            self._scan()
            wp.synchronize_device(self.device)
        return perf_counter() - t0

    def tick(self, ctrl: np.ndarray, mocap: np.ndarray | None) -> TickOut:
        """Step every world one control tick with actuator setpoints ``ctrl`` (worlds, nu) and the
        moving obstacles at ``mocap`` (worlds, spt + 1, nmocap, 3), then read back."""
        t0 = perf_counter()
        with wp.ScopedDevice(self.device):
            self.ctrl.assign(ctrl.astype(np.float32, copy=False))
            if mocap is not None:
                self.mocap.assign(mocap.astype(np.float32, copy=False))
            if self.use_graph:
                self._tick_graph()
            else:
                self._tick_launches()
            out = TickOut(self.pose.numpy(), self.vel.numpy(), self.hit_step.numpy(), self.hit_obstacle.numpy(),
                          self.hit_pos.numpy(), self.hit_depth.numpy(), self.d.overflow.numpy(), 0.0)
        out.seconds = perf_counter() - t0
        return out

    def _tick_graph(self) -> None:
        """The tick's launches captured once as a CUDA graph and replayed (one launch a tick); if
        the capture fails, plain launches from then on."""
        if self.graph is None:
            try:
                with wp.ScopedCapture(device=self.device) as capture:
                    self._tick_launches()
            except Exception as exc:    # nothing captured ran: this tick and the next ones launch
                log.warning("MuJoCo Warp tick not captured as a CUDA graph (%s: %s); launching its kernels "
                            "one by one", type(exc).__name__, exc)
                self.use_graph = False
                self._tick_launches()
                return
            self.graph = capture.graph
        wp.capture_launch(self.graph)

    def rays(self) -> tuple[np.ndarray, np.ndarray]:
        """(distances, geom ids) of the last scans, (worlds, beams) each; geom id -1: no hit."""
        with wp.ScopedDevice(self.device):
            return self.dist.numpy(), self.geomid.numpy()


def _varying_fields(models: Sequence[mujoco.MjModel]) -> dict[str, np.ndarray]:
    """The per-world fields whose values differ between ``models``: name -> stacked values."""
    first = _model_arrays(models[0])
    out = {}
    for name in sorted(PER_WORLD):
        ref = first.get(name)
        if ref is None:
            continue
        values = [getattr(m, name) for m in models]
        if all(v is ref or np.array_equal(v, ref) for v in values):
            continue
        out[name] = np.stack(values)
    return out


def _ray_groups(groups: np.ndarray | None) -> Any:
    """MuJoCo Warp's geom-group mask for the lidar (-1 everywhere: every group) from the CPU
    engine's ``mj_multiRay`` mask (1: cast against the group)."""
    if groups is None:
        return _vec6i(-1, -1, -1, -1, -1, -1)
    return _vec6i(*[int(g) for g in groups])


_vec6i = wp.types.vector(length=6, dtype=int)   # mujoco_warp.rays' geomgroup
