"""The search space around a seed scenario, and the public Hypothesis strategy over it.

A candidate is the seed plus a vector of *offsets*, one per mutable parameter (obstacle
dx/dy, size change, yaw change; optionally start, goal and waypoint offsets). An all-zero
vector is the seed itself, so when Hypothesis shrinks offsets toward zero it shrinks a
failure toward the hand-written seed: the minimal failure is the smallest change to the
seed that still fails.

Defaults can be overridden in the seed's YAML ``search:`` mapping::

    search:
      obstacle_dx: 0.5          # m: offsets drawn from [-0.5, 0.5]; or a pair [lo, hi]
      obstacle_dy: [-0.2, 0.5]
      obstacle_size: [-0.1, 0.3]  # m added to box length/width and cylinder radius
      obstacle_yaw: 30          # degrees (boxes only)
      start_dx: 0               # 0 (the default) = the start is not mutated
      start_dy: 0
      start_yaw: 0
      goal_dx: 0
      goal_dy: 0
      goal_yaw: 0
      waypoint_dx: 0            # every waypoint gets its own dx/dy offsets
      waypoint_dy: 0
      min_size: 0.05            # m: sizes never shrink below this
      frozen: [wall_left, start]  # obstacle and terrain element names, start, goal, waypoints, waypoints[i]
      insert: 2                 # at most this many new box obstacles (0 = none)
      insert_size: [0.3, 1.0]   # m: side length of an inserted box
      insert_margin: 1.0        # m: inserted boxes lie in the route's bounding box grown by this
      remove: 0                 # at most this many of the seed's obstacles may be removed
      polygon_vertex: 0.2       # m: each polygon corner's own dx/dy (default 0: off)
      motion_start: [-5, 5]     # s added to a moving obstacle's start time (never below 0)
      motion_speed: 0.5         # m/s added to a moving obstacle's speed (never below MIN_SPEED)
      drift_per_metre: [0, 0.1] # sensor and localisation faults (default 0: off): lidar_noise_per_metre,
                                # lidar_dropout_at_max, lidar_spurious, drift_per_metre,
                                # drift_per_second, yaw_drift_per_metre; added to the seed's value
      terrain_dx: 1.0           # m: each terrain element moved (a platform's edge, a ramp's place)
      terrain_dy: 1.0
      terrain_yaw: 0            # degrees (default 0: off)
      terrain_size: 0           # m added to length and width (default 0: off)
      terrain_slope: 5          # degrees added to a ramp's slope, its high end kept where it is
      terrain_rise: [-0.05, 0.1]  # m added to a step's rise, a platform's height, a pit's depth
      terrain_roughness: [-0.02, 0.05]  # m added to rough ground's amplitude

A moving obstacle's dx/dy shift its whole path (every point, or its start for a constant
velocity); its motion_start and motion_speed move when and how fast it goes. A polygon or mesh is
moved and turned like a box (no size change). Fault parameters live on the part ``robot``. A
terrain element (part ``terrain:<name>``) is moved, and by its kind made steeper (a ramp), higher
(a step, a platform, a pit's depth) or rougher; zero is the seed's element, so shrinking brings a
failure back toward the seed's terrain.

Insertion and removal are parameters like the others and zero means "as in the seed": an
inserted obstacle exists when its ``on`` flag is >= 0.5 (flags shrink to 0, so shrinking removes
inserted obstacles), a seed obstacle is removed when its ``removed`` flag is >= 0.5.

The parameter model is open: a parameter kind is a ``Param`` plus a builder (``BUILDERS``) that
yields the params of a seed and an applier (``APPLIERS``) that turns their values into a changed
scenario. Moving obstacles or sensor faults add one builder and one applier each.

Every bound must contain 0 (the seed lies in the space); ``[lo, hi]`` with lo > hi is
inverted and lo == hi != 0 is empty: both are errors naming the seed file and field. Every range
and count has a documented upper limit (scenario/search_keys.py), checked when the seed loads.
A candidate never leaves what the loader accepts: each moved value is kept within its key's range
(positions within the magnitude bound, fault settings within theirs, speeds above MIN_SPEED), and
``invalid_reason`` runs the loader's own checks across keys (``check_scenario``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Mapping, Sequence

from ..scenario.keys import MAX_ABS
from ..scenario.model import BoxObstacle, CylinderObstacle, MeshObstacle, PolygonObstacle, Pose, Scenario
from ..scenario.search_keys import RANGES, SEARCH, SearchSettings
from ..scenario.search_settings import search_settings

# The search: section's keys, ranges, defaults and limits are declared in scenario/search_keys.py
# (read there when the seed loads); these names are kept for the modules and tests that use them.
DEFAULT_BOUNDS: dict[str, tuple[float, float]] = {key.name: key.default for key in RANGES}
MIN_TERRAIN = 0.005     # m: a searched rise, height, depth or amplitude never drops below this
SLOPE_RANGE = (1.0, 80.0)   # degrees a searched ramp's slope stays within
ROBOT_PARAMS = ("lidar_noise_per_metre", "lidar_dropout_at_max", "lidar_spurious", "drift_per_metre",
                "drift_per_second", "yaw_drift_per_metre")
MIN_SPEED = 0.1         # m/s: a moving obstacle's speed never drops below this
APPLY_MEMO = 512        # layouts SearchSpace.apply remembers (a generation's proposals and more) ...
APPLY_MEMO_OBSTACLES = 20_000   # ... fewer for a large seed: at most about this many obstacles held
OTHER_KEYS = tuple(name for name in SEARCH.names if name not in DEFAULT_BOUNDS)
DEFAULT_INSERT = SEARCH["insert"].default
DEFAULT_INSERT_SIZE = SEARCH["insert_size"].default
DEFAULT_INSERT_MARGIN = SEARCH["insert_margin"].default
DEFAULT_REMOVE = SEARCH["remove"].default
INSERT_PREFIX = "navsearch_inserted_"   # names of inserted obstacles (index from 1)
FLAG_ON = 0.5                           # a flag parameter is set when its value is >= this
KNOWN_KEYS = SEARCH.names
DEFAULT_MIN_SIZE = SEARCH["min_size"].default
POSITION_DECIMALS = 4   # candidate values are rounded (0.1 mm, 0.0001 deg) so YAML is short and exact


@dataclass(frozen=True)
class Param:
    """One mutable parameter: ``name`` such as ``obstacles.box2.dx``, offset range [lo, hi]."""
    name: str
    part: str        # "obstacle:<name>", "start", "goal", "waypoints[i]"
    attr: str        # dx, dy, size, yaw
    lo: float
    hi: float
    kind: str = "offset"   # offset: added to a seed value; flag: set when >= FLAG_ON; value: absolute

    @property
    def width(self) -> float:
        return self.hi - self.lo


Limits = SearchSettings     # the checked search: section (bounds and the other settings)


class SearchSpace:
    """The mutable parameters of one seed and how to turn an offset vector into a Scenario."""

    def __init__(self, seed: Scenario, overrides: Mapping[str, Any] | None = None):
        self.seed = seed
        merged: dict[str, Any] = dict(seed.search or {})
        merged.update(overrides or {})
        self.limits = search_settings(seed, merged)
        self.bounds = dict(self.limits.bounds)
        self.frozen, self.min_size = self.limits.frozen, self.limits.min_size
        self.region = _insert_region(seed, self.limits.insert_margin)
        self.params: tuple[Param, ...] = tuple(p for build in BUILDERS for p in build(self))
        self.index = {p.name: i for i, p in enumerate(self.params)}
        self.groups: tuple[tuple[int, ...], ...] = _groups(self.params)
        self._applied: dict[tuple[float, ...], Scenario] = {}   # apply's recent answers, at most:
        self._apply_memo = max(8, min(APPLY_MEMO, APPLY_MEMO_OBSTACLES // (len(seed.obstacles) + self.limits.insert + 1)))

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "_applied": {}}   # a worker's copy starts without the memo

    def range_of(self, key: str) -> tuple[float, float] | None:
        lo, hi = self.bounds[key]
        return (lo, hi) if (lo, hi) != (0.0, 0.0) else None

    # -- use ------------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.params)

    def zero(self) -> tuple[float, ...]:
        return (0.0,) * len(self.params)

    def clip(self, offsets: Sequence[float]) -> tuple[float, ...]:
        return tuple(min(p.hi, max(p.lo, float(v))) for p, v in zip(self.params, offsets))

    def normalised_distance(self, a: Sequence[float], b: Sequence[float]) -> float:
        """Largest per-parameter difference as a fraction of that parameter's range (0..1)."""
        return max((abs(x - y) / p.width for p, x, y in zip(self.params, a, b) if p.width > 0),
                   default=0.0)

    def as_mapping(self, offsets: Sequence[float]) -> dict[str, float]:
        """Non-zero offsets by parameter name (what the search log and provenance show)."""
        return {p.name: round(float(v), POSITION_DECIMALS)
                for p, v in zip(self.params, offsets) if v != 0}

    def by_part(self, offsets: Sequence[float]) -> dict[str, dict[str, float]]:
        """Non-zero values grouped by part (``obstacle:box1``, ``inserted[0]``, ``start``, ...)."""
        out: dict[str, dict[str, float]] = {}
        for p, v in zip(self.params, offsets):
            if v:
                out.setdefault(p.part, {})[p.attr] = float(v)
        return out

    def apply(self, offsets: Sequence[float]) -> Scenario:
        """The seed with ``offsets`` applied (values rounded; sizes clamped to ``min_size``). The
        last APPLY_MEMO answers are remembered (scenarios are frozen: the same offsets, the same
        scenario object)."""
        if len(offsets) != len(self.params):
            raise ValueError(f"expected {len(self.params)} offsets for this space, got {len(offsets)}")
        key = tuple(offsets)
        known = self._applied.get(key)
        if known is not None:   # a proposal is applied by its checks, its ranking and its episode
            return known
        parts = self.by_part(offsets)
        scenario = self.seed
        for applier in APPLIERS:
            scenario = applier(self, scenario, parts)
        if len(self._applied) >= self._apply_memo:
            self._applied.clear()
        self._applied[key] = scenario
        return scenario

    def inserted_slots(self) -> list[int]:
        """Parameter index of each insertion slot's ``on`` flag."""
        return [i for i, p in enumerate(self.params) if p.part.startswith("inserted[") and p.attr == "on"]

    def removal_flags(self) -> list[int]:
        return [i for i, p in enumerate(self.params) if p.attr == "removed"]

    def describe(self) -> str:
        return ", ".join(f"{p.name} in [{p.lo:g}, {p.hi:g}]" for p in self.params) or "(nothing to mutate)"


def _groups(params: Sequence[Param]) -> tuple[tuple[int, ...], ...]:
    parts: dict[str, list[int]] = {}
    for i, p in enumerate(params):
        parts.setdefault(p.part, []).append(i)
    return tuple(tuple(v) for v in parts.values())


def _insert_region(seed: Scenario, margin: float) -> tuple[float, float, float, float]:
    """Bounding box (x0, y0, x1, y1) of start, waypoints and goal, grown by ``margin``."""
    m = seed.mission
    xs = [m.start.x, m.goal.x, *(w.x for w in m.waypoints)]
    ys = [m.start.y, m.goal.y, *(w.y for w in m.waypoints)]
    return (min(xs) - margin, min(ys) - margin, max(xs) + margin, max(ys) + margin)


# -- parameter kinds: builders yield a seed's params, appliers turn values into a scenario -------
def _obstacle_params(space: SearchSpace):
    for obs in space.seed.obstacles:
        if obs.name in space.frozen:
            continue
        outlined = isinstance(obs, (PolygonObstacle, MeshObstacle))
        attrs = ["dx", "dy"] + ([] if outlined else ["size"]) + (
            ["yaw"] if isinstance(obs, (BoxObstacle, PolygonObstacle, MeshObstacle)) else [])
        for attr in attrs:
            r = space.range_of(f"obstacle_{attr}")
            if r:
                yield Param(f"obstacles.{obs.name}.{attr}", f"obstacle:{obs.name}", attr, *r)
        r = space.range_of("polygon_vertex")
        if r and isinstance(obs, PolygonObstacle):
            for k in range(len(obs.points)):
                for axis in ("x", "y"):
                    yield Param(f"obstacles.{obs.name}.points[{k}].d{axis}", f"obstacle:{obs.name}",
                                f"v{k}{axis}", *r)
        if getattr(obs, "motion", None) is not None:
            for attr in ("start", "speed"):
                r = space.range_of(f"motion_{attr}")
                if r:
                    yield Param(f"obstacles.{obs.name}.motion.{attr}", f"obstacle:{obs.name}", attr, *r)
        if space.limits.remove > 0:
            yield Param(f"obstacles.{obs.name}.removed", f"obstacle:{obs.name}", "removed", 0.0, 1.0, "flag")


def _inserted_params(space: SearchSpace):
    x0, y0, x1, y1 = space.region
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    lo, hi = space.limits.insert_size
    for i in range(space.limits.insert):
        part, name = f"inserted[{i}]", f"inserted[{i}]"
        yield Param(f"{name}.on", part, "on", 0.0, 1.0, "flag")
        yield Param(f"{name}.x", part, "x", x0 - cx, x1 - cx)     # from the region's centre
        yield Param(f"{name}.y", part, "y", y0 - cy, y1 - cy)
        yield Param(f"{name}.size", part, "size", 0.0, hi - lo)   # added to the smallest size
        yield Param(f"{name}.yaw", part, "yaw", -90.0, 90.0)


def _mission_params(space: SearchSpace):
    mission = space.seed.mission
    for part in ("start", "goal"):
        if part in space.frozen:
            continue
        for attr in ("dx", "dy", "yaw"):
            r = space.range_of(f"{part}_{attr}")
            if r:
                yield Param(f"mission.{part}.{attr}", part, attr, *r)
    if "waypoints" in space.frozen:
        return
    for i in range(len(mission.waypoints)):
        part = f"waypoints[{i}]"
        if part in space.frozen:
            continue
        for attr in ("dx", "dy"):
            r = space.range_of(f"waypoint_{attr}")
            if r:
                yield Param(f"mission.{part}.{attr}", part, attr, *r)


def _apply_obstacles(space: SearchSpace, scenario: Scenario, parts) -> Scenario:
    out, removed = [], 0
    for obs in scenario.obstacles:
        d = parts.get(f"obstacle:{obs.name}")
        if d and d.get("removed", 0.0) >= FLAG_ON and removed < space.limits.remove:
            removed += 1
            continue
        out.append(_followable(_mutate_obstacle(obs, d, space.min_size), scenario, d) if d else obs)
    return replace(scenario, obstacles=tuple(out))


def _followable(obs: Any, scenario: Scenario, d: Mapping[str, float]) -> Any:
    """A moving obstacle whose speed (or size) the candidate changed, no faster than the physics
    step can follow (the loader refuses faster ones: ``loader.max_resolved_speed``); unchanged when
    it already is, or when even MIN_SPEED is too fast (then the loader's check discards it)."""
    motion = getattr(obs, "motion", None)
    if motion is None or not ("speed" in d or "size" in d):
        return obs
    from ..scenario.loader import max_resolved_speed
    limit = math.floor(max_resolved_speed(scenario, obs) * 10**POSITION_DECIMALS) / 10**POSITION_DECIMALS
    if motion.velocity is not None:
        speed = math.hypot(*motion.velocity)
        if speed <= limit or limit < MIN_SPEED:
            return obs
        scale = limit / speed
        velocity = tuple(math.trunc(v * scale * 10**POSITION_DECIMALS) / 10**POSITION_DECIMALS for v in motion.velocity)
        return replace(obs, motion=replace(motion, velocity=velocity))
    if motion.speed <= limit or limit < MIN_SPEED:
        return obs
    return replace(obs, motion=replace(motion, speed=limit))


def _apply_inserted(space: SearchSpace, scenario: Scenario, parts) -> Scenario:
    x0, y0, x1, y1 = space.region
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    new = []
    for i in range(space.limits.insert):
        d = parts.get(f"inserted[{i}]")
        if not d or d.get("on", 0.0) < FLAG_ON:
            continue
        size = _r(space.limits.insert_size[0] + d.get("size", 0.0))
        new.append(BoxObstacle(name=f"{INSERT_PREFIX}{i + 1}", x=_r(cx + d.get("x", 0.0)),
                               y=_r(cy + d.get("y", 0.0)), length=size, width=size,
                               yaw=_r(d.get("yaw", 0.0))))
    return replace(scenario, obstacles=scenario.obstacles + tuple(new)) if new else scenario


def _apply_mission(space: SearchSpace, scenario: Scenario, parts) -> Scenario:
    m = scenario.mission
    if not any(k in parts for k in ("start", "goal")) and not any(k.startswith("waypoints[") for k in parts):
        return scenario
    start = _mutate_pose(m.start, parts.get("start"))
    goal = _mutate_pose(m.goal, parts.get("goal"))
    waypoints = tuple(_mutate_pose(w, parts.get(f"waypoints[{i}]")) for i, w in enumerate(m.waypoints))
    return replace(scenario, mission=replace(m, start=start, goal=goal, waypoints=waypoints))


def _robot_params(space: SearchSpace):
    if "robot" in space.frozen:
        return
    for key in ROBOT_PARAMS:
        r = space.range_of(key)
        if r:
            yield Param(f"robot.{key}", "robot", key, *r)


def _apply_robot(space: SearchSpace, scenario: Scenario, parts) -> Scenario:
    d = parts.get("robot")
    return replace(scenario, robot=_mutate_robot(scenario.robot, d)) if d else scenario


def _terrain_params(space: SearchSpace):
    for el in space.seed.terrain:
        if el.name in space.frozen:
            continue
        attrs = ["dx", "dy", "yaw", "size"]
        attrs += {"ramp": ["slope"], "steps": ["rise"], "platform": ["rise"], "pit": ["rise"],
                  "rough": ["roughness"]}.get(el.kind, [])
        for attr in attrs:
            r = space.range_of(f"terrain_{attr}")
            if r:
                yield Param(f"terrain.{el.name}.{attr}", f"terrain:{el.name}", attr, *r)


def _apply_terrain(space: SearchSpace, scenario: Scenario, parts) -> Scenario:
    if not any(k.startswith("terrain:") for k in parts):
        return scenario
    return replace(scenario, terrain=tuple(_mutate_terrain(el, parts[f"terrain:{el.name}"], space.min_size)
                                           if f"terrain:{el.name}" in parts else el for el in scenario.terrain))


def _mutate_terrain(el, d: Mapping[str, float], min_size: float):
    """A terrain element moved (dx, dy), turned (yaw), grown (size: length and width; a flight of
    steps only wider), a ramp made steeper or gentler with its high end where it was (slope), a
    step's rise, a platform's height or a pit's depth changed (rise), rough ground's amplitude."""
    changes: dict[str, Any] = {}
    x = el.x + d.get("dx", 0.0)
    y = el.y + d.get("dy", 0.0)
    if "yaw" in d:
        changes["yaw"] = _r(el.yaw + d["yaw"])
    ds = d.get("size", 0.0)
    if ds:
        changes["width"] = _r(max(min_size, el.width + ds))
        if el.kind != "steps":
            changes["length"] = _r(max(min_size, el.length + ds))
    if "slope" in d and el.kind == "ramp":
        length = changes.get("length", el.length)
        slope = min(SLOPE_RANGE[1], max(SLOPE_RANGE[0], math.degrees(math.atan2(el.rise, length)) + d["slope"]))
        new = el.rise / math.tan(math.radians(slope))
        yaw = math.radians(changes.get("yaw", el.yaw))
        x += (length - new) / 2 * math.cos(yaw)      # the high end (+x) stays where it was
        y += (length - new) / 2 * math.sin(yaw)
        changes["length"] = _r(max(min_size, new))
    if "rise" in d:
        key = {"steps": "rise", "platform": "height", "pit": "depth"}.get(el.kind)
        if key is not None:
            changes[key] = _r(max(MIN_TERRAIN, getattr(el, key) + d["rise"]))
    if "roughness" in d and el.kind == "rough":
        changes["amplitude"] = _r(max(MIN_TERRAIN, el.amplitude + d["roughness"]))
    if "dx" in d or "dy" in d or "slope" in d:
        changes["x"], changes["y"] = _r(x), _r(y)
    return replace(el, **changes)


BUILDERS = [_obstacle_params, _mission_params, _inserted_params, _robot_params, _terrain_params]
APPLIERS = [_apply_obstacles, _apply_inserted, _apply_mission, _apply_robot, _apply_terrain]


def _r(value: float) -> float:
    """A candidate value: rounded, and within the magnitude every number of a scenario keeps."""
    out = min(MAX_ABS, max(-MAX_ABS, round(value, POSITION_DECIMALS)))
    return 0.0 if out == 0 else out  # no -0.0 in YAML


_TARGETS = {key.name: key.target for key in RANGES}


def _within(value: float, range_key: str) -> float:
    """``value`` kept within the range of the key that search range ``range_key`` moves."""
    low, high = _TARGETS[range_key].span
    return _r(min(high, max(low, value)))


def _mutate_pose(pose: Pose, d: Mapping[str, float] | None) -> Pose:
    if not d:
        return pose
    yaw = pose.yaw + d.get("yaw", 0.0)
    yaw = (yaw + 180.0) % 360.0 - 180.0 if "yaw" in d else pose.yaw
    x = _r(pose.x + d["dx"]) if "dx" in d else pose.x
    y = _r(pose.y + d["dy"]) if "dy" in d else pose.y
    return Pose(x, y, _r(yaw) if "yaw" in d else pose.yaw)


def _mutate_robot(robot: Any, d: Mapping[str, float] | None) -> Any:
    """The robot with the opted-in sensor and localisation fault offsets added, each kept within
    the range the loader allows for it (never below 0, probabilities at most 1, drifts at most
    their declared maximum)."""
    if not d:
        return robot
    lidar, loc = robot.lidar, robot.localisation
    changes: dict[str, Any] = {}
    if "lidar_noise_per_metre" in d:
        changes["noise_per_metre"] = _within(lidar.noise_per_metre + d["lidar_noise_per_metre"],
                                             "lidar_noise_per_metre")
    if "lidar_dropout_at_max" in d:
        base = lidar.dropout if lidar.dropout_at_max is None else lidar.dropout_at_max
        changes["dropout_at_max"] = _within(base + d["lidar_dropout_at_max"], "lidar_dropout_at_max")
    if "lidar_spurious" in d:
        changes["spurious"] = _within(lidar.spurious + d["lidar_spurious"], "lidar_spurious")
    drift = {k: _within(getattr(loc, k) + d[k], k)
             for k in ("drift_per_metre", "drift_per_second", "yaw_drift_per_metre") if k in d}
    return replace(robot, lidar=replace(lidar, **changes), localisation=replace(loc, **drift))


def _mutate_motion(motion: Any, d: Mapping[str, float]) -> Any:
    """The motion with its path shifted by dx/dy, its start and speed moved (clamped)."""
    if motion is None:
        return None
    dx, dy = d.get("dx", 0.0), d.get("dy", 0.0)
    start = _within(motion.start + d["start"], "motion_start") if "start" in d else motion.start
    ds = d.get("speed", 0.0)
    if motion.velocity is not None:
        vx, vy = motion.velocity
        norm = math.hypot(vx, vy)
        scale = max(MIN_SPEED, norm + ds) / norm if ds and norm > 0 else 1.0
        return replace(motion, start=start, velocity=(_r(vx * scale), _r(vy * scale)) if scale != 1.0
                       else motion.velocity)
    path = (tuple((_r(px + dx), _r(py + dy)) for px, py in motion.path) if dx or dy else motion.path)
    speed = _within(max(MIN_SPEED, motion.speed + ds), "motion_speed") if ds else motion.speed
    return replace(motion, path=path, start=start, speed=speed)


def _mutate_obstacle(obs, d: Mapping[str, float], min_size: float):
    x = _r(obs.x + d["dx"]) if "dx" in d else obs.x
    y = _r(obs.y + d["dy"]) if "dy" in d else obs.y
    ds = d.get("size", 0.0)
    motion = _mutate_motion(getattr(obs, "motion", None), d)
    if motion is not None and motion.path:
        x, y = motion.path[0]       # a path's first point is where the obstacle stands
    yaw = _r(obs.yaw + d["yaw"]) if "yaw" in d and hasattr(obs, "yaw") else getattr(obs, "yaw", 0.0)
    if isinstance(obs, BoxObstacle):
        return replace(obs, x=x, y=y, motion=motion, yaw=yaw,
                       length=_r(max(min_size, obs.length + ds)) if ds else obs.length,
                       width=_r(max(min_size, obs.width + ds)) if ds else obs.width)
    if isinstance(obs, PolygonObstacle):
        points = tuple((_r(px + d.get(f"v{k}x", 0.0)), _r(py + d.get(f"v{k}y", 0.0)))
                       if f"v{k}x" in d or f"v{k}y" in d else (px, py) for k, (px, py) in enumerate(obs.points))
        return replace(obs, x=x, y=y, motion=motion, points=points, yaw=yaw)
    if isinstance(obs, MeshObstacle):
        return replace(obs, x=x, y=y, motion=motion, yaw=yaw)
    if isinstance(obs, CylinderObstacle):
        return replace(obs, x=x, y=y, motion=motion,
                       radius=_r(max(min_size / 2, obs.radius + ds / 2)) if ds else obs.radius)
    raise TypeError(f"unknown obstacle type {type(obs).__name__}")


# -- validity before simulation -------------------------------------------------------------
def invalid_reason(scenario: Scenario, way: Any = None) -> str | None:
    """Why a candidate is not a test (a broken scenario, not a planner failure), or None.

    A polygon whose corners were moved into a self-intersecting outline, obstacles covering the
    start or goal footprint (a moving obstacle: the start, where it stands at t = 0; it may cross
    the goal), anything else the loader's checks across keys refuse (a waypoint inside an
    obstacle: ``loader-refuses:<field>``), no collision-free path for the footprint at all
    (``paths.path_exists``), a shortest way that cannot be driven within the timeout at the robot's
    top speed (``too-slow``), or a moving obstacle whose motion crosses a static one
    (``mover-through:<name>``): the same checks as a hand-written scenario's at setup
    (verdict/feasibility.py). A candidate that passes loads again when frozen. ``way``: a function
    of the scenario giving the length of a way known to be free, or None (``verdict.open_way``),
    which answers the path checks without a path search.
    """
    from ..scenario.geometry import (bounding_radius, footprint_outline, footprint_radius, obstacle_outline,
                                     polygon_problem)

    for obs in scenario.obstacles:          # corners moved across an edge: not a polygon any more
        if isinstance(obs, PolygonObstacle) and polygon_problem(obs.points) is not None:
            return f"polygon-invalid:{obs.name}"
    m, fp = scenario.mission, scenario.robot.footprint
    start = footprint_outline(fp, m.start.x, m.start.y, m.start.yaw_rad)
    goal = footprint_outline(fp, m.goal.x, m.goal.y, m.goal.yaw_rad)
    reach = footprint_radius(fp) + 1e-6
    for obs in scenario.obstacles:
        far = reach + bounding_radius(obs)   # their bounding circles apart: no outline needed
        if math.hypot(obs.x - m.start.x, obs.y - m.start.y) > far and math.hypot(obs.x - m.goal.x,
                                                                                  obs.y - m.goal.y) > far:
            continue
        poly = obstacle_outline(obs)
        if poly.intersects(start):
            return f"start-blocked:{obs.name}"
        if poly.intersects(goal) and getattr(obs, "motion", None) is None:
            return f"goal-blocked:{obs.name}"
    from ..core.errors import ScenarioError
    from ..scenario.loader import check_scenario
    try:
        check_scenario(scenario)
    except ScenarioError as exc:
        return f"loader-refuses:{exc.field}"
    return path_reason(scenario, way(scenario) if way is not None else None)


def path_reason(scenario: Scenario, known_length: float | None = None) -> str | None:
    """The rest of ``invalid_reason``: no way for the footprint, too slow, a mover through a wall.
    ``known_length``: the length of a way known to be free (``verdict.open_way``), which
    answers the first and most often the second without a path search."""
    from ..verdict.paths import path_exists
    if known_length is None and not path_exists(scenario):
        return "no-path"
    from ..verdict.feasibility import too_slow
    if too_slow(scenario, known_length) is not None:   # no planner reaches the goal in time: not a failure to find
        return "too-slow"
    from ..verdict.movers import mover_through
    crossing = mover_through(scenario)
    if crossing is not None:               # a person through a wall: the simulation of the impossible
        return f"mover-through:{crossing.mover}"
    return None


# -- Hypothesis -----------------------------------------------------------------------------
def offsets_strategy(space: SearchSpace):
    """Hypothesis strategy of offset vectors (tuples); shrinks toward all zeros = the seed."""
    from hypothesis import strategies as st

    return st.tuples(*(st.floats(p.lo, p.hi, allow_nan=False, allow_infinity=False,
                                 allow_subnormal=False) for p in space.params))


def scenarios_around(seed: Scenario, space: SearchSpace | None = None):
    """Public Hypothesis strategy: Scenarios near ``seed`` (validity not checked; use
    ``invalid_reason`` with ``assume`` if your test needs valid ones)::

        @given(scenarios_around(load_scenario("scenarios/boxes1.yaml")))
        def test_never_collides(scenario): ...
    """
    space = space if space is not None else SearchSpace(seed)
    return offsets_strategy(space).map(space.apply)
