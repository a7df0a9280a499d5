"""What a body can cross, as one rule over a ground profile: the legged body's capability model
(sim/bodies/legged.py) walks it every tick, and the traversable grid (verdict/traversable.py)
applies it between neighbouring cells, so the simulation and the feasibility check agree.

A *profile* is the ground's height at evenly spaced points along a line (``spacing`` metres
apart), walked from a *level* (the height the body's foot, or centre, stands at now):

* ground that changes by at most ``spacing * tan(max_slope)`` per sample is walked on (a slope
  within the body's limit);
* a steeper stretch (a step's face, a kerb, a slope steeper than ``max_slope``) is taken in one
  go: rising by at most ``max_step`` it is climbed; rising more it is a *barrier* ("step", or
  "slope" when the stretch is wider than FOOT);
* a steeper stretch down by at most ``max_step`` is stepped down; deeper, it is a drop edge: when
  ground within ``max_step`` of the level comes back within ``max_gap`` (a trench, a gap between
  two platforms) the body strides over it (its support is the straight line across); else it is a
  "drop" barrier: a body that goes on falls.

Distances are exact to the spacing (SPACING, 2 cm, in the simulation). No MuJoCo, no I/O.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

SPACING = 0.02    # m between the samples of a profile (a threshold of 5 cm is seen)
FOOT = 0.1        # m: a steep stretch narrower than this is a step's face, wider a slope (words only)
EPS = 1e-9


@dataclass(frozen=True)
class Capability:
    """What a body can cross: steps up and down of ``max_step`` metres, slopes of ``max_slope``
    degrees, gaps of ``max_gap`` metres (0: none)."""
    max_step: float
    max_slope: float
    max_gap: float


@dataclass(frozen=True)
class Barrier:
    """Where a profile stops the body: ``index`` is the last sample it stands on before it;
    ``kind`` "step" or "slope" (a rise it cannot climb: it is stopped) or "drop" (a drop deeper
    than max_step with no ground back within max_gap: it falls if it goes on); ``height`` the rise
    or the depth (m), ``width`` the steep stretch's or the gap's width (inf: no far side seen)."""
    kind: str
    index: int
    height: float
    width: float


def walk(h: Sequence[float], spacing: float, level: float, cap: Capability) -> tuple[list[float], Barrier | None]:
    """Walk the profile ``h`` (heights at 0, spacing, 2 spacing ...) from ``level`` at its first
    sample: (the support height at each sample up to the first barrier, NaN beyond; the barrier or
    None). The support is the ground, or the straight line across a gap it strides over."""
    n = len(h)
    tol = spacing * math.tan(math.radians(min(cap.max_slope, 89.9))) + EPS
    step = cap.max_step + EPS
    reach = int(math.floor(cap.max_gap / spacing + EPS)) + 1   # samples from a drop edge to the far side
    support = [math.nan] * n
    support[0] = cur = float(level)
    k = 0
    while k < n - 1:
        nxt = h[k + 1]
        if abs(nxt - cur) <= tol:               # walkable ground
            k += 1
            support[k] = cur = nxt
            continue
        j = k + 1
        if nxt > cur:                          # a steep rise: climbed in one go if low enough
            while j + 1 < n and h[j + 1] - h[j] > tol:
                j += 1
            rise = h[j] - cur
            if rise > step:
                width = (j - k - 1) * spacing
                return support, Barrier("slope" if width > FOOT else "step", k, rise, width)
        else:                                  # a steep drop: stepped down if shallow enough
            while j + 1 < n and h[j + 1] - h[j] < -tol:
                j += 1
            if cur - h[j] > step:
                far = next((i for i in range(j, min(n, k + reach + 1)) if h[i] >= cur - step), None)
                if far is None:
                    seen = h[k + 1:min(n, k + reach + 1)]
                    return support, Barrier("drop", k, cur - min(seen), math.inf)
                if h[far] - cur > step:        # the far side is a wall: it cannot get up there
                    return support, Barrier("step", k, h[far] - cur, (far - k - 1) * spacing)
                for i in range(k + 1, far):    # strides over: supported on the line across
                    support[i] = cur + (h[far] - cur) * (i - k) / (far - k)
                support[far] = cur = h[far]
                k = far
                continue
        for i in range(k + 1, j + 1):
            support[i] = h[i]
        cur = h[j]
        k = j
    return support, None


def look_ahead(cap: Capability, move: float, spacing: float = SPACING) -> int:
    """Samples a profile needs to decide a move of ``move`` metres: the move, the widest gap and
    two samples more (so a far side within max_gap is seen)."""
    return int(math.ceil((move + cap.max_gap) / spacing)) + 3


# ---------------------------------------------------------------- what each body can cross

# The wheeled body's limits are estimates from its wheels, measured in MuJoCo with a straight
# drive (benchmarks/measure_wheeled_limits.py; default body: 50 kg, 10 N m, wheels of 0.1 m): it
# climbed steps of 0.044 m (diff: its ball casters, 0.05 m, meet a step first) and 0.081 m (skid),
# slopes of 17.5 deg (diff: the casters carry load, the driven wheels lose grip) and 32.5 deg
# (skid), and crossed gaps of 0.09-0.13 m. The estimates below stay under those figures.
WHEELED_CASTER_STEP = 0.8     # of the caster's radius (diff)
WHEELED_WHEEL_STEP = 0.7      # of the wheel's radius (skid)
WHEELED_SLOPE = {"diff": 15.0, "skid": 30.0}   # degrees, at most the torque's limit
WHEELED_GAP = 0.5             # of the wheel's radius


def body_capability(scenario) -> Capability | None:
    """What the scenario's body can cross: a legged body's declared limits, a wheeled body's
    estimated ones (see WHEELED_*), None for a body that declares none (planar: no terrain;
    mjcf: its limits are the user's model's, unknown here)."""
    body = scenario.robot.body
    if body.kind == "legged":
        return Capability(float(body.max_step), float(body.max_slope), float(body.max_gap))
    if body.kind != "wheeled":
        return None
    r = float(body.wheel_radius)
    g = 9.81
    driven = 4 if body.drive_wheels == "skid" else 2
    torque = math.degrees(math.atan(driven * body.max_wheel_torque / (r * body.mass * g)))
    if body.drive_wheels == "skid":
        step = WHEELED_WHEEL_STEP * r
    else:
        caster = max(0.02, min(body.clearance, r / 2))      # sim/bodies/wheeled.py's casters
        step = WHEELED_CASTER_STEP * caster
    return Capability(min(step, float(body.clearance)), min(torque, WHEELED_SLOPE[body.drive_wheels]),
                      WHEELED_GAP * r)
