"""Why a search discarded its candidates, and what to change in the seed's ``search:`` section.

A candidate that is no test (no way to the goal, an obstacle on the start, a person walking
through a wall: ``space.invalid_reason``) is discarded before simulation. When one reason takes
a large share of the draws, the search spends its time on layouts it cannot use: the summary and
the HTML report say so, why it happens, and which ``search:`` keys to narrow or which parts to
freeze, by the names of this seed (issue 32).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

SHARE = 0.25    # a reason is worth a word when it took at least this share of the draws ...
AT_LEAST = 10   # ... and at least this many candidates


@dataclass(frozen=True)
class DiscardAdvice:
    reason: str      # the discard code: no-path, mover-through, ...
    count: int
    drawn: int       # candidates drawn: simulated plus discarded
    why: str         # what the search did to make such candidates
    change: str      # what to write in the seed's search: section

    def line(self) -> str:
        return (f"{self.count} of {self.drawn} candidates discarded as {self.reason}: {self.why}; "
                f"to search valid layouts instead, {self.change}")


def _names(parts: list[str]) -> str:
    return ", ".join(parts) if parts else ""


def _moved(space: Any, prefix: str) -> list[str]:
    """Names of the seed's parts of one kind ("obstacle", "terrain") that the search moves."""
    seen: dict[str, None] = {}
    for p in getattr(space, "params", ()):
        kind, _, name = p.part.partition(":")
        if kind == prefix and p.attr in ("dx", "dy", "size", "yaw"):
            seen.setdefault(name)
    return list(seen)


# terrain keys that can break a joint (a ramp meeting its level) when they move one element alone
_JOINT_KEYS = ("terrain_dx", "terrain_rise", "terrain_slope", "terrain_size", "terrain_yaw")


def _active(space: Any, keys: tuple[str, ...]) -> list[str]:
    range_of = getattr(space, "range_of", None)
    return [k for k in keys if range_of is not None and k in getattr(space, "bounds", {}) and range_of(k)]


def _no_path(space: Any) -> tuple[str, str]:
    terrain, obstacles = _moved(space, "terrain"), _moved(space, "obstacle")
    joints = _active(space, _JOINT_KEYS)
    if terrain and joints:
        zeros = ", ".join(f"{k}: 0" for k in joints)
        return (f"the search moves and reshapes terrain elements ({_names(terrain)}) one by one, so that "
                f"pieces that must meet no longer do (a ramp moved along its length, or given another "
                f"slope or rise, leaves a step or a gap where it met its level) and no way the body can "
                f"drive joins start and goal",
                f"keep the joints: search: {{{zeros}}} (the ramp's side, terrain_dy, and the obstacles are "
                f"still searched), or narrow those ranges")
    return ("the search moves or grows the obstacles" + (f" ({_names(obstacles[:6])})" if obstacles else "")
            + " until they close every passage wide enough for the footprint",
            "narrow obstacle_dx/obstacle_dy/obstacle_size (e.g. search: {obstacle_dx: 0.5, obstacle_dy: "
            "0.5}) or freeze the walls that make the passage (search: {frozen: [...]})")


def _mover_through(space: Any) -> tuple[str, str]:
    seed = getattr(space, "seed", None)
    movers = [o.name for o in getattr(seed, "obstacles", ()) if getattr(o, "motion", None) is not None]
    who = _names([f"'{m}'" for m in movers]) or "a moving obstacle"
    return (f"the search moves {who} so that its path crosses a static obstacle (a person walking "
            f"through a wall)",
            "narrow obstacle_dx/obstacle_dy, which move its whole path (e.g. search: {obstacle_dx: 0.3, "
            "obstacle_dy: 0.3}; 0 searches its timing only: motion_start, motion_speed)")


_FIXED = {
    "start-blocked": ("the search moves obstacles (or inserts boxes) onto the start",
                      "narrow obstacle_dx/obstacle_dy or insert_margin, or freeze the obstacles beside the start"),
    "goal-blocked": ("the search moves obstacles (or inserts boxes) onto the goal",
                     "narrow obstacle_dx/obstacle_dy or insert_margin, or freeze the obstacles beside the goal"),
    "too-slow": ("the search lengthens the way beyond what the robot can drive in mission.timeout at its "
                 "top speed", "raise mission.timeout in the seed, or narrow the moves that lengthen the way"),
    "polygon-invalid": ("the search moves polygon corners across the polygon's edges",
                        "narrow polygon_vertex"),
    "loader-refuses": ("the search takes a value beyond what the format allows (a waypoint inside an "
                       "obstacle, a size or height out of range)",
                       "narrow the search: range of the key that moves it"),
}


def discard_advice(discarded: Mapping[str, int], simulated: int, space: Any = None) -> list[DiscardAdvice]:
    """One piece of advice per discard reason that took a large share of the draws (SHARE, AT_LEAST),
    most frequent first; ``space``: the search's SearchSpace (its seed names the parts)."""
    drawn = int(simulated) + sum(discarded.values())
    out = []
    for reason, count in sorted(discarded.items(), key=lambda kv: (-kv[1], kv[0])):
        if count < AT_LEAST or count < SHARE * drawn:
            continue
        if reason == "no-path":
            why, change = _no_path(space)
        elif reason == "mover-through":
            why, change = _mover_through(space)
        else:
            why, change = _FIXED.get(reason, ("the candidates are no test", "narrow the search's ranges"))
        out.append(DiscardAdvice(reason, count, drawn, why, change))
    return out
