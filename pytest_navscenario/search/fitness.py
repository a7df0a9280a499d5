"""What the search reads from an episode: how close it came to failing, and how it failed.

*Robustness* (lower = closer to failure; below 0 = failed) follows the robustness semantics of
falsification tools (VerifAI, S-TaLiRo): each requirement of a navigation test gets a margin
normalised to [0, 1] and the episode's robustness is the smallest margin, plus a small share
of their mean so that a candidate near two failure modes ranks above one near a single mode:

* time: the share of the *spare time* (timeout less the route's length at full speed) left when
  the goal was reached (a success that needed 28 of 30 s is near a timeout);
* stall: 1 - the longest time the robot gained no STALL_STEP along the route, over the spare
  time (a robot that hesitated 15 s in front of a gap before finding its way was near a stuck
  timeout, however fast it was afterwards: the way a competent planner fails);
* clearance: min clearance / CLEARANCE_SCALE (near a collision);
* safety: the smallest clearance of the poses the safety layer predicts (near a safety stop);
* efficiency: path efficiency (a long detour is near a timeout too).

With requirements (issue 34; ``requirements:`` or ``--nav-requirements``) the margins are theirs
alone: each requirement's robustness over its scale (declared, else the range of its signals in
the episode), so that one in m/s does not mask one in m; a violation is a failure whose culprit is
``requirement:<name>`` (the requirement violated first), placed where the robot was at that time.

A failure's robustness is -1 + progress / 2: failures rank before every success, and among
failures the one that got less far ranks first.

The *cause signature* tells failures apart by behaviour, not by parameters: outcome, culprit
obstacle (inserted obstacles are one culprit "inserted", whichever slot holds them; a terrain
element, ``terrain:<name>``, for a fall, a tip-over, being stuck on it or driving into its face), where the
culprit is along the seed's route (a seed obstacle: where the seed has it, part of its identity; an
inserted box: where it stands) and how far along the route the robot was when it failed (both in
PLACE_BINS bins). Two failures with the same signature fail the same way.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

from .space import INSERT_PREFIX

CLEARANCE_SCALE = 0.5   # m: clearance above this counts as fully safe
SAFETY_SCALE = 0.3      # m: predicted clearance above the safety margin by this counts as safe
MEAN_SHARE = 0.25       # weight of the mean margin beside the smallest one
PLACE_BINS = 4          # route quarters
PATH_POINTS = 40        # path samples kept per candidate for the placement operators
STALL_STEP = 0.25       # m along the route: gaining less than this is no progress (the stuck cell)
PROGRESS_RATE = 10.0    # Hz: trajectory samples read for the stall
FRACTIONS_KEPT = 100_000   # Route.fraction's remembered answers (then it starts afresh)


@dataclass(frozen=True)
class Reading:
    """The search's view of one episode."""
    robustness: float
    signature: tuple[str, str, int, int]
    progress: float                         # 0..1 along the seed's route where the robot ended/failed
    path: tuple[tuple[float, float], ...]   # robot centre, PATH_POINTS samples
    closest: tuple[float, float, float]     # (t, x, y) of the closest approach
    margins: dict[str, float]

    @property
    def closest_margin(self) -> str:
        """The name of the smallest margin ("" for a failure, which has none): what came closest."""
        return min(self.margins, key=self.margins.get) if self.margins else ""


class Route:
    """The seed's reference route (its shortest collision-free path) for places and progress."""

    def __init__(self, seed: Any):
        import numpy as np
        from ..verdict.paths import shortest_path

        sp = shortest_path(seed)
        m = seed.mission
        pts = (np.asarray(sp.points, dtype=float) if sp is not None else
               np.array([[m.start.x, m.start.y], *([w.x, w.y] for w in m.waypoints), [m.goal.x, m.goal.y]]))
        self.points = pts.reshape(-1, 2)
        seg = np.hypot(*np.diff(self.points, axis=0).T) if len(self.points) > 1 else np.zeros(0)
        self.cum = np.concatenate([[0.0], np.cumsum(seg)])
        self.length = float(self.cum[-1]) or 1.0
        self._fractions: dict[tuple[float, float], float] = {}   # fraction's answers: the aimed
        # operators ask about the same path points again and again (a parent's 40 samples)
        # a seed obstacle's place is where the seed has it: part of its identity, so a nudge across
        # a quarter boundary (the paper seeds' obstacles sit on one) is not a new way of failing
        self.places = {o.name: _bin(self.fraction(o.x, o.y)) for o in seed.obstacles}
        self.places.update({f"terrain:{el.name}": _bin(self.fraction(el.x, el.y)) for el in seed.terrain})

    def fraction(self, x: float, y: float) -> float:
        """Arc-length fraction (0..1) of the route point nearest to (x, y) (remembered)."""
        key = (x, y)
        known = self._fractions.get(key)
        if known is None:
            import numpy as np

            if len(self._fractions) >= FRACTIONS_KEPT:
                self._fractions.clear()
            known = self._fractions[key] = float(self.fractions(np.array([[x, y]], dtype=float))[0])
        return known

    def fractions(self, xy: Any) -> Any:
        """``fraction`` of each row of an (n, 2) array."""
        import numpy as np

        p = self.points
        if len(p) < 2:
            return np.zeros(len(xy))
        x, y = xy[:, 0:1], xy[:, 1:2]
        a, d = p[:-1], np.diff(p, axis=0)
        dd = np.maximum((d * d).sum(axis=1), 1e-12)
        u = np.clip(((x - a[:, 0]) * d[:, 0] + (y - a[:, 1]) * d[:, 1]) / dd, 0.0, 1.0)
        qx, qy = a[:, 0] + u * d[:, 0], a[:, 1] + u * d[:, 1]
        i = np.argmin((qx - x) ** 2 + (qy - y) ** 2, axis=1)
        rows = np.arange(len(xy))
        return (self.cum[i] + u[rows, i] * np.sqrt(dd[i])) / self.length


def _bin(fraction: float) -> int:
    return min(PLACE_BINS - 1, max(0, int(fraction * PLACE_BINS)))


def culprit_of(res: Any) -> str:
    """The obstacle hit, the one the safety layer stopped for, the terrain element the robot
    fell from, tipped on, was stuck at or drove into (``terrain:<name>``), or (timeout) the
    obstacle nearest to where the robot ended, else nearest over the run."""
    violated = first_violated(res)
    if violated is not None:
        return f"requirement:{violated.name}"
    if res.collision is not None:
        if getattr(res.collision, "terrain", False):
            return terrain_culprit(res.scenario, res.collision.obstacle, res.collision.x, res.collision.y)
        return res.collision.obstacle
    event = getattr(res, "terrain_event", None)
    if event is not None:
        return terrain_culprit(res.scenario, event.element, event.x, event.y)
    if res.safety_stop is not None:
        return res.safety_stop.obstacle
    if res.outcome.value == "timeout" and len(res.trajectory.pose):
        from ..verdict.gaps import is_terrain_face
        from ..verdict.metrics import min_clearance
        pose = res.trajectory.pose
        name = min_clearance(res.scenario, res.trajectory.t[-1:], pose[-1:])[1]
        if name and is_terrain_face(res.scenario, name):   # a face it cannot cross: its element
            return terrain_culprit(res.scenario, name, float(pose[-1, 0]), float(pose[-1, 1]))
        if name:
            return name
        if res.scenario.terrain:       # no obstacle near: the terrain element it ended beside
            return terrain_culprit(res.scenario, "", float(pose[-1, 0]), float(pose[-1, 1]), margin=1.0)
    name = res.metrics.min_clearance_obstacle
    if name and res.scenario.terrain:
        from ..verdict.gaps import is_terrain_face
        if is_terrain_face(res.scenario, name):
            return terrain_culprit(res.scenario, name, res.metrics.min_clearance_x, res.metrics.min_clearance_y)
    return name


def terrain_culprit(scenario: Any, label: str, x: float, y: float, margin: float = 0.3) -> str:
    """``terrain:<name>`` of the element a message names ("off platform 'dock'", "ramp 'r'"), or
    of the element under (x, y) (its outline grown by ``margin``); "" over the plain floor."""
    import re

    names = {el.name for el in scenario.terrain}
    quoted = re.findall(r"'([^']*)'", label or "")
    if quoted and quoted[-1] in names:
        return f"terrain:{quoted[-1]}"
    from ..scenario.ground.surface import element_at
    i = element_at(scenario, x, y, margin=margin)
    return f"terrain:{scenario.terrain[i].name}" if i is not None else ""


def read_episode(res: Any, route: Route) -> tuple[Reading, str]:
    """(reading, culprit) of one EpisodeResult."""
    import numpy as np

    traj, sc = res.trajectory, res.scenario
    pose = np.asarray(traj.pose, dtype=float).reshape(-1, 3)
    culprit = culprit_of(res)
    end_xy = _failure_point(res, pose)
    progress = route.fraction(*end_xy) if end_xy is not None else 0.0
    failed = res.outcome.value != "success"
    margins = (requirement_margins(res) or _margins(res, pose, route)) if not failed else {}
    if failed:
        robustness = -1.0 + progress / 2.0
    else:
        vals = list(margins.values())
        robustness = min(vals) + MEAN_SHARE * sum(vals) / len(vals)
    signature = (res.outcome.value, *_culprit_place(culprit, sc, route), _bin(progress))
    if not failed and margins and next(iter(margins)).startswith("requirement:"):
        # a success with requirements: its behaviour is which requirement came closest to failing
        # (evolve keeps the closest candidate of each signature: one per requirement)
        signature = (res.outcome.value, min(margins, key=margins.get), 0, _bin(progress))
    idx = np.linspace(0, len(pose) - 1, min(PATH_POINTS, len(pose))).astype(int) if len(pose) else []
    path = tuple((round(float(pose[i, 0]), 4), round(float(pose[i, 1]), 4)) for i in idx)
    m = res.metrics
    closest = (float(m.min_clearance_time), float(m.min_clearance_x), float(m.min_clearance_y))
    return Reading(robustness, signature, progress, path, closest, margins), culprit


def _culprit_place(culprit: str, scenario: Any, route: Route) -> tuple[str, int]:
    """(who, place) of a cause signature: a seed obstacle by its name and the quarter of the route
    where the seed has it; an inserted box (any slot) as "inserted" and the quarter where it
    stands, since where it stands is all that tells two inserted boxes apart."""
    if not culprit:
        return "", 0
    if not culprit.startswith(INSERT_PREFIX):
        return culprit, route.places.get(culprit, 0)
    try:
        obs = scenario.obstacle(culprit)
    except KeyError:
        return "inserted", 0
    return "inserted", _bin(route.fraction(obs.x, obs.y))


def _failure_point(res: Any, pose: Any) -> tuple[float, float] | None:
    violated = first_violated(res)
    if violated is not None and violated.first_violation is not None and len(pose):
        import numpy as np
        i = int(np.searchsorted(res.trajectory.t, violated.first_violation - 1e-9))
        return float(pose[min(i, len(pose) - 1), 0]), float(pose[min(i, len(pose) - 1), 1])
    if res.collision is not None:
        return float(res.collision.x), float(res.collision.y)
    if len(pose):
        return float(pose[-1, 0]), float(pose[-1, 1])
    return None


def first_violated(res: Any) -> Any:
    """The requirement whose violation is the outcome (the first violated; None otherwise)."""
    if res.outcome.value != "requirement":
        return None
    violated = [r for r in getattr(res, "requirements", ()) if r.violated]
    return min(violated, key=lambda r: (r.first_violation if r.first_violation is not None else 0.0,
                                        r.robustness)) if violated else None


def requirement_margins(res: Any) -> dict[str, float]:
    """With requirements (issue 34) the graded fitness is theirs alone: each robustness over its
    scale (the declared ``scale``, else the range of its signals in this episode), so that
    requirements in different units do not mask each other; {} without requirements."""
    out = {}
    for r in getattr(res, "requirements", ()):
        scale = r.scale if r.scale else (r.span if math.isfinite(r.span) and r.span > 0 else 1.0)
        out[f"requirement:{r.name}"] = _unit(r.robustness / scale) if math.isfinite(r.robustness) else 1.0
    return out


def _margins(res: Any, pose: Any, route: Route) -> dict[str, float]:
    """Every source's margins (MARGIN_SOURCES), in order, as one dict."""
    out: dict[str, float] = {}
    for source in MARGIN_SOURCES:
        out.update(source(res, pose, route))
    return out


def mission_margins(res: Any, pose: Any, route: Route) -> dict[str, float]:
    """The margins of the mission itself: time, stall, clearance, efficiency, safety."""
    m, sc = res.metrics, res.scenario
    spare = spare_time(sc, route)
    out = {"time": _unit((sc.mission.timeout - m.duration) / spare),
           "stall": _unit(1.0 - longest_stall(res.trajectory.t, pose, route) / spare),
           "clearance": _unit(m.min_clearance / CLEARANCE_SCALE),
           "efficiency": _unit(m.path_efficiency)}
    safety = _safety_margin(res, pose)
    if safety is not None:
        out["safety"] = safety
    return out


def spare_time(scenario: Any, route: Route) -> float:
    """Seconds a robot can lose and still reach the goal in time: the timeout less the seed's
    route at the robot's top speed (at least a tenth of the timeout)."""
    timeout = scenario.mission.timeout
    fastest = route.length / max(scenario.robot.limits.max_speed, 1e-6)
    return max(timeout - fastest, 0.1 * timeout, 1e-6)


def longest_stall(t: Any, pose: Any, route: Route) -> float:
    """The longest time (s) in which the robot got no STALL_STEP further along the seed's route
    than it had been (at the end of the episode: up to its end)."""
    import numpy as np

    t = np.asarray(t, dtype=float)
    if len(pose) < 2 or len(t) != len(pose):
        return 0.0
    step = max(1, int(round(len(pose) / max(1.0, (t[-1] - t[0]) * PROGRESS_RATE))))
    ts, xy = t[::step], pose[::step, :2]
    s = route.fractions(xy) * route.length
    best, mark, since = 0.0, s[0] + STALL_STEP, ts[0]
    for ti, si in zip(ts, s):
        if si >= mark:
            best, mark, since = max(best, ti - since), si + STALL_STEP, ti
    return float(max(best, t[-1] - since))


def _unit(v: float) -> float:
    return 1.0 if not math.isfinite(v) else min(1.0, max(0.0, float(v)))


def _safety_margin(res: Any, pose: Any) -> float | None:
    """How close the safety layer came to triggering, in [0, 1]: as the layer does, predict
    each control tick's pose half a horizon and a full horizon ahead at the measured velocity;
    the smallest clearance of those predicted poses, less the layer's margin, over
    SAFETY_SCALE (0 = it would have stopped the robot)."""
    import numpy as np
    from ..verdict.metrics import closest_approach

    sc = res.scenario
    safety = getattr(sc.robot, "safety", None)
    if safety is None or not getattr(safety, "enabled", False) or not sc.obstacles or len(pose) < 3:
        return None
    t = np.asarray(res.trajectory.t, dtype=float)
    vel = np.asarray(res.trajectory.velocity, dtype=float).reshape(-1, 3)
    step = max(1, int(round(len(pose) / max(1.0, t[-1] * 10.0))))   # about 10 Hz
    p, v = pose[::step], vel[::step]
    c, sn = np.cos(p[:, 2]), np.sin(p[:, 2])
    wx, wy = c * v[:, 0] - sn * v[:, 1], sn * v[:, 0] + c * v[:, 1]
    ahead = np.concatenate([np.stack([p[:, 0] + wx * h, p[:, 1] + wy * h, p[:, 2] + v[:, 2] * h], axis=1)
                            for h in (0.5 * safety.horizon, safety.horizon)])   # both horizons, one call
    best = closest_approach(sc.obstacles, sc.robot.footprint, ahead)[0]
    return _unit((best - safety.margin) / SAFETY_SCALE)


#: Where a successful episode's margins come from, in order: each source maps (EpisodeResult, poses,
#: route) to named margins in [0, 1] (0: at the edge of failing). A scenario with STL requirements
#: (``requirements:``) is steered by them instead (``requirement_margins``: each ``requirement:<name>``
#: its robustness over its scale, never raw units in one min: a speed in m/s would mask a distance in
#: m), and ``Reading.closest_margin`` names the margin that was smallest.
MARGIN_SOURCES: list[Callable[[Any, Any, Route], dict[str, float]]] = [mission_margins]
