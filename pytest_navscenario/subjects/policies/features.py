"""From observations to a policy's input rows, and from its output rows to commands, for a whole
batch of episodes in array operations (one row per episode), as a declaration says (declaration.py).

Each value is computed element by element (no reduction across episodes), so an episode's row,
and so its command, has the same bits whether it is computed alone or in a batch of any size.

The lidar the policy sees: ``beams`` beams over ``fov`` degrees, laid out as the simulated lidar
lays out its own (a full circle: evenly spaced from -180 degrees, no beam at +180; a partial field
of view: from -fov/2 to +fov/2, both ends included; one beam: straight ahead). Each of them reads
the scenario's lidar through an index table made once per scenario lidar: ``min``, the shortest
range among the scenario's beams within half a beam spacing of its direction (the nearest beam
when none is that close: more beams than the scenario's), or ``nearest``, the nearest beam's range.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from ...scenario.model import Scenario
from .declaration import Declaration, Feature

TWO_PI = 2.0 * math.pi


class ObservationMismatch(ValueError):
    """A scenario cannot give the observation the policy was trained on (e.g. a narrower lidar)."""


def policy_beam_angles(beams: int, fov_deg: float) -> tuple[np.ndarray, float]:
    """(the policy's beam directions in rad, robot frame; the half width of each beam's sector)."""
    if beams <= 1:
        return np.zeros(1), math.radians(fov_deg) / 2.0
    if fov_deg >= 360.0:
        return -math.pi + TWO_PI * np.arange(beams) / beams, math.pi / beams
    fov = math.radians(fov_deg)
    return np.linspace(-fov / 2.0, fov / 2.0, beams), fov / (2.0 * (beams - 1))


def resample_table(source: np.ndarray, beams: int, fov_deg: float, method: str) -> np.ndarray:
    """(beams, k) indices into the scenario's beams ``source`` (rad): the policy's beam ``b`` reads
    the minimum of ``ranges[table[b]]`` (see the module docstring). Rows are padded by repeating
    their first index, which leaves a minimum unchanged."""
    angles, half = policy_beam_angles(beams, fov_deg)
    source = np.asarray(source, dtype=np.float64)
    # angular distance from every policy beam to every scenario beam, wrapped to [0, pi]
    gap = np.abs((source[None, :] - angles[:, None] + math.pi) % TWO_PI - math.pi)
    nearest = np.argmin(gap, axis=1)
    if method == "nearest":
        return nearest[:, None].astype(np.intp)
    members = [np.flatnonzero(row <= half * (1.0 + 1e-9)) for row in gap]
    width = max(1, max(len(m) for m in members))
    table = np.empty((beams, width), dtype=np.intp)
    for b, m in enumerate(members):
        if not len(m):
            m = nearest[b:b + 1]
        table[b, :len(m)] = m
        table[b, len(m):] = m[0]
    return table


class Episode:
    """What one episode keeps between ticks: its lidar table, its action scale, the last command."""
    __slots__ = ("scale", "previous", "table", "table_key")

    def __init__(self, scale: np.ndarray):
        self.scale = scale                       # (action width,) multiplier of the clipped output
        self.previous = np.zeros(3)              # the command answered last tick (vx, vy, wz)
        self.table: np.ndarray | None = None     # the lidar index table, at the first tick
        self.table_key: bytes | None = None


class Featurizer:
    """Builds input rows and commands for a declaration (one per loaded model)."""

    def __init__(self, decl: Declaration, dtype: Any = np.float32):
        self.decl = decl
        self.dtype = dtype
        self.width = decl.width
        self._tables: dict[tuple, np.ndarray] = {}
        spans, start = [], 0
        for f in decl.observation:
            spans.append((f, slice(start, start + f.width)))
            start += f.width
        self.spans: list[tuple[Feature, slice]] = spans
        # the whole row's clip bounds and normalisation, applied once per batch
        lo = np.full(self.width, -np.inf)
        hi = np.full(self.width, np.inf)
        mean = np.zeros(self.width)
        std = np.ones(self.width)
        for f, s in spans:
            if f.clip is not None:
                lo[s] = [c[0] for c in f.clip]
                hi[s] = [c[1] for c in f.clip]
            mean[s] = f.mean
            std[s] = f.std
        self.lo, self.hi, self.mean, self.std = lo, hi, mean, std
        self.clipped = bool(np.isfinite(lo).any() or np.isfinite(hi).any())
        self.normalised = bool((mean != 0).any() or (std != 1).any())
        action = decl.action
        self.out_components = list(action.components)
        self.out_lo = np.array([c[0] for c in action.clip]) if action.clip else None
        self.out_hi = np.array([c[1] for c in action.clip]) if action.clip else None
        self.lidar = [f for f in decl.observation if f.kind == "lidar"]

    # ------------------------------------------------------------------ episodes
    def start(self, scenario: Scenario) -> Episode:
        """An episode's state; ObservationMismatch when the scenario cannot feed the policy."""
        lidar = scenario.robot.lidar
        for f in self.lidar:
            if f.fov > lidar.fov + 1e-9:
                raise ObservationMismatch(
                    f"the policy was trained on a {f.fov:g} degree lidar ({self.decl.source}, {f.where}.fov) "
                    f"but this scenario's lidar covers {lidar.fov:g} degrees (robot.lidar.fov): "
                    f"the policy's beams outside it would read nothing; run it on scenarios whose lidar "
                    f"covers at least {f.fov:g} degrees")
        scale = self.decl.action.scale
        if scale == "limits":
            limits = scenario.robot.limits
            full = (limits.max_speed, limits.max_lateral_speed, math.radians(limits.max_yaw_rate))
            row = np.array([full[c] for c in self.out_components])
        else:
            row = np.array(scale, dtype=np.float64)
        return Episode(row)

    def _table(self, ep: Episode, f: Feature, angles: np.ndarray) -> np.ndarray:
        if ep.table is None:
            key = (f.beams, f.fov, f.resample, angles.tobytes())
            table = self._tables.get(key)
            if table is None:
                table = self._tables[key] = resample_table(angles, f.beams, f.fov, f.resample)
            ep.table, ep.table_key = table, key[3]
        return ep.table

    # ------------------------------------------------------------------ rows
    def rows(self, episodes: Sequence[Episode], observations: Sequence[Any]) -> np.ndarray:
        """The model's input rows (len(observations), width) in its dtype."""
        n = len(observations)
        x = np.empty((n, self.width))
        poses = None
        for f, s in self.spans:
            kind = f.kind
            if kind == "lidar":
                self._lidar_into(x, s, f, episodes, observations)
            elif kind == "target" or kind == "goal":
                if poses is None:
                    poses = np.array([o.pose for o in observations], dtype=np.float64).reshape(n, 3)
                if kind == "target":
                    points = np.array([o.target for o in observations], dtype=np.float64).reshape(n, 2)
                else:
                    points = np.array([o.goal[:2] for o in observations], dtype=np.float64).reshape(n, 2)
                dx = points[:, 0] - poses[:, 0]
                dy = points[:, 1] - poses[:, 1]
                c, si = np.cos(poses[:, 2]), np.sin(poses[:, 2])
                fx = c * dx + si * dy              # the point in the robot frame
                fy = c * dy - si * dx
                if f.form == "polar":
                    x[:, s.start] = np.hypot(fx, fy)
                    x[:, s.start + 1] = np.arctan2(fy, fx)
                else:
                    x[:, s.start] = fx
                    x[:, s.start + 1] = fy
            elif kind == "velocity":
                v = np.array([o.velocity for o in observations], dtype=np.float64).reshape(n, 3)
                x[:, s] = v[:, f.components]
            else:   # previous_command
                p = np.array([ep.previous for ep in episodes]).reshape(n, 3)
                x[:, s] = p[:, f.components]
        if self.clipped:
            np.clip(x, self.lo, self.hi, out=x)
        if self.normalised:
            x -= self.mean
            x /= self.std
        return x.astype(self.dtype, copy=False)

    def _lidar_into(self, x: np.ndarray, s: slice, f: Feature, episodes: Sequence[Episode],
                    observations: Sequence[Any]) -> None:
        groups: dict[int, list[int]] = {}
        tables = []
        for k, (ep, o) in enumerate(zip(episodes, observations)):
            table = self._table(ep, f, o.angles)
            members = groups.get(id(table))
            if members is None:
                groups[id(table)] = members = []
                tables.append(table)
            members.append(k)
        for table in tables:
            members = groups[id(table)]
            ranges = np.array([observations[k].ranges for k in members], dtype=np.float64)
            picked = ranges[:, table]                       # (episodes, beams, k)
            values = picked[:, :, 0] if table.shape[1] == 1 else picked.min(axis=2)
            if len(members) == len(observations):
                x[:, s] = values
            else:
                x[members, s] = values

    # ------------------------------------------------------------------ commands
    def commands(self, episodes: Sequence[Episode], outputs: np.ndarray) -> np.ndarray:
        """(len(episodes), 3) commands (vx, vy, wz) from the model's output rows, clipped and scaled
        as declared; each episode's is kept as its previous command. NaN stays NaN (the harness
        then ends that episode as a subject error)."""
        out = np.asarray(outputs, dtype=np.float64)
        if self.out_lo is not None:
            out = np.clip(out, self.out_lo, self.out_hi)
        scale = np.array([ep.scale for ep in episodes]).reshape(out.shape)
        out = out * scale
        cmd = np.zeros((len(episodes), 3))
        cmd[:, self.out_components] = out
        for ep, row in zip(episodes, cmd):
            ep.previous = row
        return cmd
