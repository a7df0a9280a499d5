"""What a robot riding the ground meets: the ground height under a point (fast, per tick), the
pose a body rests in on it, and the watch that tells a fall, a tip-over or being stuck on terrain
from the base's state each tick (``riding_episode.RidingEpisode`` runs it). A classification of what the
physics did: nothing here moves the robot.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from ...scenario.ground import surface as ground
from ...scenario.ground.crossing import SPACING, Capability, steep_ground, walk
from ..trajectory import TerrainEvent

ON_GROUND = 0.08          # m: a base this close above the ground under it stands on it
ON_GROUND_SHARE = 0.09    # of the footprint's length, for a smaller robot (a 0.2 m car: 1.8 cm)
STUCK_TIME = 3.0          # s of being driven without moving that make the robot stuck on terrain
STUCK_COMMAND = 0.1       # m/s: a setpoint at least this fast counts as driving
STUCK_MOVING = 0.25       # of the setpoint's speed: slower than this counts as not moving
LOOK_AHEAD = 0.3          # m beyond the footprint's front where a stuck robot's step is measured
EDGE_REACH = 0.1          # m beyond the footprint's ends where an edge a tilted robot hangs on is looked for
                          # (its casters, wheels or chassis may reach past the footprint)
GAP_SPACING = 0.005       # m between the samples that measure a gap the robot is caught in
SIDE_TILT = 6.0           # degrees of roll beyond the ground's own cross-slope: a wheel is off a side edge
FEATURE = Capability(max_step=0.01, max_slope=5.0, max_gap=0.0)   # what counts as a step or a slope there
FEATURE_SHARE = 0.02      # of the footprint's length: a smaller robot's step (a 0.2 m car's: 4 mm)


def _height(h: float) -> str:
    """A step's or edge's height in metres, to the centimetre unless that misstates it by more than
    a fifth (a 1.5 cm sill: "0.015", not "0.01")."""
    return f"{h:.2f}" if abs(round(h, 2) - h) <= 0.2 * h else f"{h:.3f}"


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
    answer as ``scenario.ground.ground_height`` (bit for bit where there are height grids: the
    same operations in the same order; tests/sim/test_ground_probe.py)."""

    def __init__(self, scenario):
        from ...scenario.ground.heightmap import height_grid

        self.scenario = scenario
        self.rows = []
        for p in ground.pieces(scenario.terrain):
            el = scenario.terrain[p.element]
            x, y, c, s = ground.frame(el)
            slope = (p.top1 - p.top0) / (p.u1 - p.u0)
            self.rows.append((x, y, c, s, p.u0, p.u1, el.width / 2, p.top0, slope, p.cut, p.element))
        self.grids = []
        for i in ground.grid_elements(scenario.terrain):
            el = scenario.terrain[i]
            grid = height_grid(el, scenario)
            x, y, c, s = ground.frame(el)
            rows, cols = grid.heights.shape
            length, width = grid.extent
            self.grids.append((x, y, c, s, el.length / 2 + 1e-9, el.width / 2 + 1e-9, float(el.z), grid.heights,
                               length / 2.0, width / 2.0, float(grid.cell[0]), float(grid.cell[1]), rows, cols,
                               ground.grid_low(el, scenario) < ground.FLOOR))
        self.pieces = [(p, scenario.terrain[p.element]) for p in ground.pieces(scenario.terrain)]
        self.exact = all(g[7].dtype == np.float64 for g in self.grids)   # else numpy's promotions differ

    def height(self, px: float, py: float) -> float:
        if self.grids:
            if not self.exact:
                return float(ground.ground_height(self.scenario, px, py))
            return self._height_on_grids(float(px), float(py))
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

    def _height_on_grids(self, px: float, py: float) -> float:
        """``ground.ground_height`` at one point, in plain floats with its operations (its
        pieces' heights as ``ground._piece_height``, the grids' as ``HeightGrid.sample``)."""
        floor, solid = ground.FLOOR, -math.inf
        for piece, el in self.pieces:
            x, y, c, s = ground.frame(el)
            dx, dy = px - x, py - y
            u, v = c * dx + s * dy, -s * dx + c * dy
            if not (u >= piece.u0 - 1e-9 and u <= piece.u1 + 1e-9 and abs(v) <= el.width / 2 + 1e-9):
                continue
            if piece.top0 == piece.top1:
                h = piece.top0
            else:
                h = piece.top0 + (piece.top1 - piece.top0) * (u - piece.u0) / (piece.u1 - piece.u0)
            if piece.cut:
                floor = min(floor, h)
            else:
                solid = _nanmax(solid, h)
        for x, y, c, s, hl, hw, z, h, half_x, half_y, dx_cell, dy_cell, rows, cols, cuts in self.grids:
            dx, dy = px - x, py - y
            u, v = c * dx + s * dy, -s * dx + c * dy
            if not (abs(u) <= hl and abs(v) <= hw):
                continue
            gu, gv = (u + half_x) / dx_cell, (v + half_y) / dy_cell
            if 0 <= gu <= cols - 1 and 0 <= gv <= rows - 1:
                col = min(max(math.floor(gu), 0), cols - 2)
                row = min(max(math.floor(gv), 0), rows - 2)
                fx, fy = min(max(gu - col, 0.0), 1.0), min(max(gv - row, 0.0), 1.0)
                h00, h11 = h.item(row, col), h.item(row + 1, col + 1)
                if fx >= fy:
                    h10 = h.item(row, col + 1)
                    g = h00 + (h10 - h00) * fx + (h11 - h10) * fy
                else:
                    h01 = h.item(row + 1, col)
                    g = h00 + (h11 - h01) * fx + (h01 - h00) * fy
            else:
                g = math.nan
            solid = _nanmax(solid, z + g)
            if cuts:                                  # a grid dipping below the floor cuts it
                floor = -math.inf
        return _nanmax(solid, floor)

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


def _nanmax(a: float, b: float) -> float:
    """``np.maximum`` of two floats: NaN if either is."""
    return a if (a != a or a >= b) and b == b else b


class TerrainStop(Exception):
    """Raised by ``TerrainWatch.check``: the episode ends on ``event``."""

    def __init__(self, event: TerrainEvent):
        super().__init__(event.kind)
        self.event = event
        self.reason = "stuck-terrain" if event.kind in ("stuck", "still") else event.kind


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
        self.trail: deque = deque(maxlen=self.stuck_ticks + 1)   # (x, y) of those ticks
        self.speeds: deque = deque(maxlen=self.stuck_ticks + 1)  # and their setpoint speeds
        self.event: TerrainEvent | None = None
        # () -> whether the chassis itself touches the ground: set by the episode (the world's
        # contacts); None: the ``touching`` that ``check`` is given (the chassis sensor)
        self.chassis_on_ground = None
        fp = scenario.robot.footprint
        self.front = fp.length / 2 if fp.shape == "box" else fp.radius
        # at the robot's scale: a sill that holds a car on 3 cm wheels is under a centimetre, and a
        # step 0.3 m ahead of a 0.2 m robot is not what holds it (a 0.9 m robot's: unchanged)
        self.feature = Capability(max_step=min(FEATURE.max_step, FEATURE_SHARE * 2 * self.front),
                                  max_slope=FEATURE.max_slope, max_gap=0.0)
        self.look_ahead = min(LOOK_AHEAD, self.front)
        self.on_ground = min(ON_GROUND, ON_GROUND_SHARE * 2 * self.front)

    def check(self, t: float, state: tuple[float, ...], setpoint: tuple[float, float, float],
              touching: bool) -> None:
        x, y, z, roll, pitch, yaw, vx, vy, vz, wz = state
        g = self.probe.height(x, y)
        if self.level is None or z - g < self.on_ground:
            self.level, self.level_at = g, (x, y)
        elif self.level - z > self.drop_limit:
            self._end(TerrainEvent("fell", t, self._fell_from(x, y), x, y, z, drop=self.level - g,
                                   roll=math.degrees(roll), pitch=math.degrees(pitch)))
        if abs(roll) > self.tip or abs(pitch) > self.tip:
            edge = self._over_edge(x, y, g, yaw)
            if edge is not None:               # pitching off an edge: the fall it is (issue 36)
                self._end(TerrainEvent("fell", t, self._fell_from(x, y, edge[:2]), x, y, z, drop=edge[2] - g,
                                       roll=math.degrees(roll), pitch=math.degrees(pitch)))
            el = self.probe.element(x, y)
            where = self._name(el)
            if el is None and (edge := self._edge_under(x, y, math.cos(yaw), math.sin(yaw))) is not None \
                    and edge[0] is not None:
                where = "off the edge of " + self._name(edge[0])   # its centre just past it (a drop of its limit)
            self._end(TerrainEvent("tipped", t, where, x, y, z, roll=math.degrees(roll),
                                   pitch=math.degrees(pitch)))
        speed = abs(setpoint[0]) + abs(setpoint[1])
        if speed < STUCK_COMMAND:
            self.pushing = 0
            self.trail.clear()
            self.speeds.clear()
            return
        self.pushing += 1
        self.trail.append((x, y))
        self.speeds.append(speed)
        if self.pushing >= self.stuck_ticks:
            x0, y0 = self.trail[0]
            asked = sum(self.speeds) * self.tick_dt         # in order: the same sum, without a generator
            if math.hypot(x - x0, y - y0) < STUCK_MOVING * asked:
                self._stuck(t, x, y, z, roll, pitch, yaw, setpoint, touching)

    def _name(self, element: int | None) -> str:
        return "" if element is None else ground.describe_element(self.scenario.terrain[element])

    def _over_edge(self, x: float, y: float, g: float, yaw: float) -> tuple[float, float, float] | None:
        """(x, y, ground height) of where the robot stood above an edge it is going over, or None:
        its centre is over ground more than ``drop_limit`` below the ground it last stood on, or
        below the ground under one end of its footprint (a short robot that noses down onto the
        lower ground while its rear is still on the edge), past a drop steeper than its
        ``tip_angle`` on the line from there. A robot tipping there is going over the edge: a fall,
        whichever of its tilt or its drop passes its limit first (a short robot pitches nose down
        before its base has dropped, a long one drops first). Tipping on a slope, or on the ground
        it stands on, is a tip-over."""
        c, s = math.cos(yaw), math.sin(yaw)
        ends = [(x - c * self.front, y - s * self.front), (x + c * self.front, y + s * self.front)]
        edge = Capability(max_step=self.drop_limit, max_slope=self.body.tip_angle, max_gap=0.0)
        for x0, y0, h0 in [(*self.level_at, self.level)] + [(a, b, self.probe.height(a, b)) for a, b in ends]:
            if h0 - g <= self.drop_limit:
                continue
            length = math.hypot(x - x0, y - y0)
            n = int(length / SPACING) + 2
            h = ground.ground_height(self.scenario, np.linspace(x0, x, n), np.linspace(y0, y, n)).tolist()
            _, barrier = walk(h, length / (n - 1), h0, edge)
            if barrier is not None and barrier.kind == "drop":
                return x0, y0, h0
        return None

    def _fell_from(self, x: float, y: float, stood: tuple[float, float] | None = None) -> str:
        """"off platform 'dock'" (the raised element it stood on, at ``stood`` or where it last
        stood), "into pit 'p'" (the hole it is over), or "" (an edge of the plain floor)."""
        below = self.probe.element(x, y)
        if below is not None and self.probe.height(x, y) < 0.0:
            return "into " + self._name(below)
        above = self.probe.element(*(stood or self.level_at))
        return "off " + self._name(above) if above is not None else ""
    def _stuck(self, t, x, y, z, roll, pitch, yaw, setpoint, touching) -> None:
        """What holds the robot: the first step or slope along its way (the ground from under its
        centre to its look-ahead past its front, walked with its feature: ``scenario/ground/crossing.py``), the
        slope it is on, or its chassis resting on the ground (high-centred)."""
        ahead = 1.0 if setpoint[0] >= 0 else -1.0
        c, s = math.cos(yaw), math.sin(yaw)
        d = ahead * np.arange(int((self.front + self.look_ahead) / SPACING) + 1) * SPACING
        px, py = x + c * d, y + s * d
        steep = self._steep_ahead(x, y, c, s, d)
        if steep is not None:
            el = self.probe.element(*steep[:2])
            self._end(TerrainEvent("stuck", t, self._name(el), x, y, z, roll=math.degrees(roll),
                                   pitch=math.degrees(pitch),
                                   detail=f"cannot walk the {steep[2]:.0f} deg slope across its way"))
        gap = self._gap_under(x, y, c, s)
        if gap is not None:
            who = "its wheels are" if self.body.kind_name == "wheeled" else "it is"
            self._end(TerrainEvent("stuck", t, self._name(gap[1]), x, y, z, roll=math.degrees(roll),
                                   pitch=math.degrees(pitch), detail=f"{who} caught in the {gap[0]:.2f} m gap"))
        side = self._off_the_side(x, y, c, s, roll)
        if side is not None:
            self._end(TerrainEvent("stuck", t, self._name(side[1]), x, y, z, roll=math.degrees(roll),
                                   pitch=math.degrees(pitch), detail=side[0]))
        h = ground.ground_height(self.scenario, px, py).tolist()
        _, barrier = walk(h, SPACING, h[0], self.feature)
        slope = math.degrees(max(abs(pitch), abs(roll)))
        if barrier is not None and barrier.kind != "drop":
            k = min(barrier.index + 1, len(h) - 1)
            el = self.probe.element(float(px[k]), float(py[k]))
            if barrier.kind == "step":
                detail = f"cannot climb the {_height(barrier.height)} m step"
            else:
                angle = math.degrees(math.atan2(barrier.height, barrier.width + SPACING))
                detail = f"cannot climb the {angle:.0f} deg slope"
        elif slope > 3.0 and (edge := self._edge_under(x, y, ahead * c, ahead * s)) is not None:
            el, height, up = edge        # its own tilt over an edge, not a slope of the ground (issue 36)
            detail = (f"cannot climb the {_height(height)} m step" if up     # its rear at the riser
                      else f"pitched {slope:.0f} deg over the {_height(height)} m edge")
        elif slope > 3.0:
            el = self.probe.element(x, y)
            detail = f"cannot climb the {slope:.0f} deg slope"
        else:
            el = self.probe.element(x, y)
            if self.chassis_on_ground is not None:     # the chassis's own contacts, not the wheels'
                touching = self.chassis_on_ground()
            if not touching and self._level_around(x, y, px, py):
                self._not_held(t, x, y, z, roll, pitch)
                return
            slips = "its wheels slip" if self.body.kind_name == "wheeled" else "it makes no headway"
            detail = "high-centred: its chassis rests on the ground" if touching else slips
        self._end(TerrainEvent("stuck", t, self._name(el), x, y, z, roll=math.degrees(roll),
                               pitch=math.degrees(pitch), detail=detail))

    def _edge_under(self, x: float, y: float, c: float, s: float) -> tuple[int | None, float, bool] | None:
        """(element, height, up) of an edge under the footprint, from EDGE_REACH behind its rear to
        EDGE_REACH past its front end along its way (c, s) (a step or drop above its feature's): a
        robot tilted across one is hung over it, its tilt its own, not the ground's slope; ``up``
        where the ground rises along its way there (its front on top, its rear at the riser: a step
        it is climbing). None where the ground under it has no edge."""
        reach = self.front + EDGE_REACH
        d = np.arange(-reach, reach + SPACING / 2, SPACING)
        px, py = x + c * d, y + s * d
        h = ground.ground_height(self.scenario, px, py).tolist()
        _, barrier = walk(h, SPACING, h[0], self.feature)
        if barrier is None or barrier.kind not in ("step", "drop"):
            return None
        k = min(barrier.index + 1, len(h) - 1)
        upper = k if h[k] >= h[barrier.index] else barrier.index    # the edge belongs to the higher side
        return (self.probe.element(float(px[upper]), float(py[upper])), float(barrier.height),
                barrier.kind == "step")

    def _level_around(self, x: float, y: float, px: np.ndarray, py: np.ndarray) -> bool:
        """The ground under the robot and along its way is level (within its feature's step): no
        terrain there can hold it."""
        h = ground.ground_height(self.scenario, np.append(px, x), np.append(py, y))
        return float(np.ptp(h)) <= self.feature.max_step

    def _not_held(self, t, x, y, z, roll, pitch) -> None:
        """Driven on level ground without getting anywhere: nothing of the terrain holds it. A
        robot that went to and fro as it was told (a planner dithering) goes on, the episode's
        timeout or the stuck check judges it; one that did not move at all ends as "still": its
        drive or controller did not follow the setpoints (issue 36: not "stuck on terrain")."""
        pts = np.asarray(self.trail, dtype=float)
        travelled = float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0
        asked = sum(self.speeds) * self.tick_dt
        if travelled >= STUCK_MOVING * asked:
            self.pushing = 0
            self.trail.clear()
            self.speeds.clear()
            return
        self._end(TerrainEvent("still", t, "", x, y, z, roll=math.degrees(roll), pitch=math.degrees(pitch),
                               detail=f"driven for {STUCK_TIME:g} s on level ground, it covered {travelled:.2f} m "
                                      f"of the {asked:.2f} m asked: its drive or controller did not follow the "
                                      f"setpoints"))

    def _off_the_side(self, x, y, c, s, roll) -> tuple[str, int | None] | None:
        """(detail, element) when the robot rolls SIDE_TILT degrees more than the ground under its
        centre slopes across its way (a wheel off a ramp's side edge): the element's own slope
        along its way (a ramp's, else the ground's) and the tilt; None otherwise."""
        e = 0.05
        h = ground.ground_height(self.scenario, np.array([x - s * e, x + s * e, x + c * e, x - c * e]),
                                 np.array([y + c * e, y - c * e, y + s * e, y - s * e]))
        across = math.degrees(math.atan(abs(h[0] - h[1]) / (2 * e)))
        tilt = abs(math.degrees(roll))
        if tilt - across <= SIDE_TILT:
            return None
        el = self.probe.element(x, y)
        slope = getattr(self.scenario.terrain[el], "slope", None) if el is not None else None
        if slope is None:
            slope = math.degrees(math.atan(abs(h[2] - h[3]) / (2 * e)))
        if slope < FEATURE.max_slope:          # level ground (a platform, a dock): its side edge, not a slope
            return f"tilted {tilt:.0f} deg over the side edge", el
        return f"tilted {tilt:.0f} deg off the side of the {slope:.1f} deg slope", el

    def _gap_under(self, x, y, c, s) -> tuple[float, int | None] | None:
        """(width along the heading, element) of a gap the robot's centre is over: ground lower by
        more than FEATURE's step than the ground on both sides within its reach (a trench, a
        narrow pit its wheels dropped into); None when there is ground on one side only (a drop)."""
        reach = self.front + self.look_ahead
        d = np.arange(-round(reach / GAP_SPACING), round(reach / GAP_SPACING) + 1) * GAP_SPACING
        h = ground.ground_height(self.scenario, x + c * d, y + s * d)
        mid = len(d) // 2
        low = h < min(h[0], h[-1]) - self.feature.max_step
        if not low[mid]:
            return None
        lows = np.flatnonzero(~low)
        before, after = lows[lows < mid], lows[lows > mid]
        if not len(before) or not len(after):
            return None
        return float((after[0] - before[-1] - 1) * GAP_SPACING), self.probe.element(x, y)

    def _steep_ahead(self, x, y, c, s, d) -> tuple[float, float, float] | None:
        """(x, y, slope in degrees) of the first steep ground (``crossing.steep_ground``, for a
        body that declares what it crosses: ``cap``) ahead of the centre or a foot, when it stands
        off it and that ground is within max_slope along its way (across it or diagonally: a
        slope straight ahead is described by the walk below); None otherwise."""
        cap = getattr(self.body, "cap", None)
        if cap is None or not self.scenario.terrain:
            return None
        feet = getattr(self.body, "feet", np.zeros((0, 2)))
        ox = np.concatenate([[0.0], c * feet[:, 0] - s * feet[:, 1]])[:, None]
        oy = np.concatenate([[0.0], s * feet[:, 0] + c * feet[:, 1]])[:, None]
        px, py = x + ox + c * d, y + oy + s * d
        steep = steep_ground(self.scenario, cap, px, py)
        first = [int(np.argmax(row)) for row in steep if row.any() and not row[0]]
        if not first or steep[:, 0].any():
            return None
        row = next(i for i, r in enumerate(steep) if r.any() and not r[0] and int(np.argmax(r)) == min(first))
        k = min(min(first) + 2, steep.shape[1] - 1)
        qx, qy, e = float(px[row, k]), float(py[row, k]), 0.005
        h = ground.ground_height(self.scenario, np.array([qx + e, qx - e, qx, qx]), np.array([qy, qy, qy + e, qy - e]))
        along = abs((h[0] - h[1]) * c + (h[2] - h[3]) * s) / (2 * e)
        if math.degrees(math.atan(along)) > cap.max_slope:
            return None                     # too steep along its way as well: a slope it cannot climb
        slope = math.degrees(math.atan(math.hypot(h[0] - h[1], h[2] - h[3]) / (2 * e)))
        return float(px[row, min(first)]), float(py[row, min(first)]), slope

    def _end(self, event: TerrainEvent) -> None:
        self.event = event
        raise TerrainStop(event)
