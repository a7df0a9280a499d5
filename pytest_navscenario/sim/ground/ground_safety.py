"""The safety layer's view of the ground, for a robot that rides it: what it predicts with, and why
it can stop before a pit it sees and cannot before a drop it does not.

The collision safety layer (``safety.py``) predicts with the obstacles the 2D lidar sees, as on the
real robot, and keeps doing so on terrain. A 2D lidar does not see the ground: a drop-off, a pit or
a stairwell going down lies below its plane, so with a 2D lidar alone the layer cannot stop the
robot before one (it drives off the edge and the episode ends in a fall).

Where a 3D lidar is fitted the layer also keeps a map of the ground it has seen (``GroundMap``,
cells of ``CELL`` metres, world frame, from every scan of the episode: the ground right in front of
the robot is below the lowest ring and was seen from further away) and, each tick, predicts the
footprint's sweep over ``safety.horizon`` as the collision layer does and halts the robot when the
sweep would enter

* the shadow of an edge: cells that a beam ending more than the body's drop limit below the
  ground the robot stands on crossed below that ground's level (a beam that dives into a pit, or
  past a platform's edge to the floor below) and that no beam has hit;
* a step down: a cell seen lower than the robot's ground by more than the drop limit next to a cell
  higher than it by more than that (a ramp or a slope down the body can take has no such jump);
* ground sloping more steeply than the body's slope limit (between neighbouring ground cells).

The body's limits (``limits_of``): a drop deeper than the body lands from (the simulation's own
fall threshold for it), a slope steeper than the body climbs (a legged body's ``max_slope``; a
wheeled body's torque limit: sin(slope) = driven wheels x max_wheel_torque / (mass g radius), and
never more than its tip angle). What the lidar never saw the layer does not know: it stops for the
ground it has seen, never for ground it has not.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
import numpy as np

from ...scenario.model import Scenario
from ..safety import SAMPLE_SPACING, twist_poses

CELL = 0.1                # m, the ground map's cells
MARGIN_CELLS = 60         # cells of map beyond the scenario's extent (6 m) on every side
HOLE_LEVEL = 0.02         # m: below the robot's ground by this, a beam is in a hole's shadow
SLOPE_REACH = 0.3         # m above the robot's ground: higher returns are obstacles, not a slope
GRAVITY = 9.81


@dataclass(frozen=True)
class GroundLimits:
    """What the body can meet: the deepest drop (m) it survives, the steepest slope (degrees)."""
    drop: float
    slope: float


def limits_of(scenario: Scenario, drop_limit: float) -> GroundLimits:
    """The body's limits; ``drop_limit`` is the simulation's fall threshold for it (the body
    model's ``drop_limit``)."""
    body = scenario.robot.body
    tip = float(getattr(body, "tip_angle", 45.0))
    if body.kind == "legged":
        slope = min(float(body.max_slope), tip)
    elif body.kind == "wheeled":
        driven = 2 if body.drive_wheels == "diff" else 4
        grip = driven * body.max_wheel_torque / (body.mass * GRAVITY * body.wheel_radius)
        slope = min(math.degrees(math.asin(min(grip, 1.0))), tip)
    else:
        slope = tip
    return GroundLimits(float(drop_limit), slope)


class GroundMap:
    """The ground the 3D lidar has seen in an episode: per cell the lowest return (NaN: none) and
    whether a beam passed through it too low for the robot (a hole)."""

    def __init__(self, bounds: tuple[float, float, float, float]):
        x0, y0, x1, y1 = bounds
        self.x0, self.y0 = x0 - MARGIN_CELLS * CELL, y0 - MARGIN_CELLS * CELL
        self.nx = int(math.ceil((x1 - x0) / CELL)) + 2 * MARGIN_CELLS
        self.ny = int(math.ceil((y1 - y0) / CELL)) + 2 * MARGIN_CELLS
        self.low = np.full(self.nx * self.ny, np.nan)
        self.hole = np.zeros(self.nx * self.ny, dtype=bool)

    def cells(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(flat cell index, inside the map) of world points."""
        i = np.floor((np.asarray(x) - self.x0) / CELL).astype(np.intp)
        j = np.floor((np.asarray(y) - self.y0) / CELL).astype(np.intp)
        inside = (i >= 0) & (i < self.nx) & (j >= 0) & (j < self.ny)
        return np.where(inside, j * self.nx + i, 0), inside

    def see(self, origin: np.ndarray, points: np.ndarray, ground_z: float, drop: float) -> None:
        """Add a scan's returns (world frame, from ``origin``) taken from ground at ``ground_z``:
        the lowest return of each cell, and as holes the cells a beam that ended more than ``drop``
        below the ground crossed below the ground's level (no ground there at the robot's level:
        the shadow behind an edge, the inside of a pit)."""
        if not len(points):
            return
        k, inside = self.cells(points[:, 0], points[:, 1])
        np.fmin.at(self.low, k[inside], points[inside, 2])
        deep = points[:, 2] < ground_z - drop
        if not deep.any():
            return
        p, o = points[deep], np.asarray(origin, dtype=float)
        d = p - o
        level = ground_z - HOLE_LEVEL
        start = np.clip((level - o[2]) / np.where(d[:, 2] < 0, d[:, 2], -1e-12), 0.0, 1.0)
        length = np.hypot(d[:, 0], d[:, 1]) * (1.0 - start)
        n = np.maximum(1, np.ceil(length / (CELL / 2.0)).astype(np.intp)) + 1
        ray = np.repeat(np.arange(len(p)), n)
        step = np.arange(len(ray)) - np.repeat(np.cumsum(n) - n, n)
        f = start[ray] + (1.0 - start[ray]) * step / (n[ray] - 1).clip(1)
        k, inside = self.cells(o[0] + d[ray, 0] * f, o[1] + d[ray, 1] * f)
        self.hole[k[inside]] = True


class GroundSafety:
    """Per tick: would the predicted sweep enter a hole or too steep ground the map has seen?"""

    def __init__(self, scenario: Scenario, limits: GroundLimits, bounds: tuple[float, float, float, float]):
        self.scenario = scenario
        safety = scenario.robot.safety
        self.horizon, self.margin = float(safety.horizon), float(safety.margin)
        fp = scenario.robot.footprint
        if fp.shape == "circle":
            r = fp.radius + self.margin
            g = np.arange(-r, r + 1e-9, CELL / 2.0)
            gx, gy = np.meshgrid(g, g)
            keep = np.hypot(gx, gy) <= r
            self.samples = np.column_stack([gx[keep], gy[keep]])
            self.reach = r
        else:
            hl, hw = fp.length / 2.0 + self.margin, fp.width / 2.0 + self.margin
            gx, gy = np.meshgrid(np.linspace(-hl, hl, max(2, int(math.ceil(2 * hl / (CELL / 2.0))) + 1)),
                                 np.linspace(-hw, hw, max(2, int(math.ceil(2 * hw / (CELL / 2.0))) + 1)))
            self.samples = np.column_stack([gx.ravel(), gy.ravel()])
            self.reach = math.hypot(hl, hw)
        self.limits = limits
        self.tan_slope = math.tan(math.radians(limits.slope))
        self.map = GroundMap(bounds)

    def see(self, origin: np.ndarray, points_world: np.ndarray, ground_z: float) -> None:
        """Add a 3D scan (world frame) taken while the robot stood on ground at ``ground_z``."""
        self.map.see(origin, points_world, ground_z, self.limits.drop)

    def check(self, x: float, y: float, ground_z: float, yaw: float, vx: float, vy: float,
              wz: float) -> str | None:
        """What the sweep over the horizon would enter (a readable phrase), or None."""
        speed = math.hypot(vx, vy)
        travel = (speed + abs(wz) * self.reach) * self.horizon
        n = int(min(64, max(1, math.ceil(travel / SAMPLE_SPACING))))
        poses = twist_poses(x, y, yaw, vx, vy, wz, np.linspace(0.0, self.horizon, n + 1)[1:])
        c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
        px = poses[:, 0:1] + c * self.samples[:, 0] - s * self.samples[:, 1]
        py = poses[:, 1:2] + s * self.samples[:, 0] + c * self.samples[:, 1]
        m = self.map
        k, inside = m.cells(px.ravel(), py.ravel())
        k = np.unique(k[inside])
        low = m.low[k]
        # 1. the shadow of an edge: cells a beam passed through below the robot's ground on its way
        # deeper, that no beam has hit (where a beam hit, the ground is seen: rules 2 and 3)
        shadow = m.hole[k] & np.isnan(low)
        if shadow.any():
            return (f"a drop ahead{self._where(k[shadow][0])} (no ground within {self.limits.drop:g} m "
                    f"below the robot where the lidar's beams dived past an edge)")
        # 2. a step down: a cell lower than the robot's ground by more than the drop limit, next to
        # one higher by more than that (a gentle slope down never is: its neighbours are close)
        seen = np.isfinite(low)
        jump = self.limits.drop + self.tan_slope * CELL
        deep = seen & (low < ground_z - self.limits.drop)
        if deep.any():
            kd, ld = k[deep], low[deep]
            top = np.full(len(kd), -np.inf)
            for step in (1, -1, m.nx, -m.nx):
                np.fmax(top, m.low[np.clip(kd + step, 0, len(m.low) - 1)], out=top)
            down = top - ld > jump
            if down.any():
                worst = int(np.argmax(np.where(down, top - ld, -np.inf)))
                return (f"a drop of {top[worst] - ld[worst]:.2f} m ahead{self._where(kd[worst])}")
        # 3. ground sloping down more steeply than the body takes (ground-level cells only: what
        # rises above the robot's ground is an obstacle's side or a climb, not a fall)
        top = ground_z + SLOPE_REACH
        return self._slope(k[seen & (low <= top)], top)

    def _where(self, cell: int) -> str:
        """", at pit 'hole'": the terrain element under a map cell, for the message (the layer
        sees only points; the scenario names the place)."""
        from ...scenario.ground.surface import describe_element, element_at

        m = self.map
        x = m.x0 + (cell % m.nx + 0.5) * CELL
        y = m.y0 + (cell // m.nx + 0.5) * CELL
        i = element_at(self.scenario, x, y, margin=CELL)
        return "" if i is None else f" at {describe_element(self.scenario.terrain[i])}"

    def _slope(self, k: np.ndarray, top: float) -> str | None:
        """Ground too steep for the body under the sweep: three cells in a row (along x or y), all
        seen and at ground level (lowest return at most ``top``: an obstacle's side is no slope),
        rising or falling steadily by more than the slope limit over the two cells (a single odd
        cell, a spurious return, is a bump, not a slope)."""
        m = self.map
        last = len(m.low) - 1
        for step in (1, m.nx):
            a = m.low[k]
            b = m.low[np.minimum(k + step, last)]
            c = m.low[np.minimum(k + 2 * step, last)]
            ok = np.isfinite(a) & np.isfinite(b) & np.isfinite(c) & (b <= top) & (c <= top)
            if not ok.any():
                continue
            d1, d2 = (b - a)[ok], (c - b)[ok]
            rise = np.abs(c - a)[ok]
            steady = (d1 * d2 > 0) & (np.minimum(np.abs(d1), np.abs(d2)) > self.tan_slope * CELL * 0.5)
            steep = steady & (rise > self.tan_slope * 2 * CELL)
            if steep.any():
                angle = math.degrees(math.atan(rise[steep].max() / (2 * CELL)))
                return f"a slope of {angle:.0f} degrees ahead (the body climbs {self.limits.slope:.0f})"
        return None


def scenario_bounds(scenario: Scenario) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1) around the mission, the obstacles and the terrain."""
    xs = [scenario.mission.start.x, scenario.mission.goal.x] + [w.x for w in scenario.mission.waypoints]
    ys = [scenario.mission.start.y, scenario.mission.goal.y] + [w.y for w in scenario.mission.waypoints]
    for item in tuple(scenario.obstacles) + tuple(scenario.terrain):
        r = math.hypot(getattr(item, "length", 0.0) or 0.0, getattr(item, "width", 0.0) or 0.0) / 2.0 \
            + (getattr(item, "radius", 0.0) or 0.0)
        xs += [item.x - r, item.x + r]
        ys += [item.y - r, item.y + r]
    return min(xs), min(ys), max(xs), max(ys)


def ground_safety(scenario: Scenario, drop_limit: float) -> GroundSafety | None:
    """The ground layer of an episode: only with the safety layer on and a 3D lidar fitted."""
    if not scenario.robot.safety.enabled or scenario.robot.lidar3d is None:
        return None
    return GroundSafety(scenario, limits_of(scenario, drop_limit), scenario_bounds(scenario))
