"""The laser's mounting on the robot: from the bag's transforms, else guessed from the scans."""
from __future__ import annotations

import math

import numpy as np

from .projection import beam_rays, cell_count
from .reading import BagData


def laser_mount(data: BagData, source: str = "/tf_static") -> tuple[float, float, float] | None:
    """The laser's pose (x, y, yaw rad) in the odometry child frame from ``source`` ("/tf_static",
    or "/tf": the first transform of each frame there, with /tf_static filling gaps), or None."""
    tree = data.static_tf if source == "/tf_static" else {**data.static_tf, **data.first_tf}
    frame, x, y, yaw = data.scan_frame, 0.0, 0.0, 0.0
    for _ in range(32):
        if frame == data.base_frame:
            return (x, y, yaw)
        if frame not in tree:
            break
        parent, px, py, pyaw = tree[frame]
        c, s = math.cos(pyaw), math.sin(pyaw)
        x, y, yaw = px + c * x - s * y, py + s * x + c * y, pyaw + yaw
        frame = parent
    if frame == data.base_frame:
        return (x, y, yaw)
    return None



GUESS_YAWS = (0.0, 90.0, 180.0, -90.0)       # degrees: the laser turned as lasers commonly are
GUESS_OFFSETS = np.round(np.arange(-0.16, 0.1601, 0.016), 3)   # m, ahead of the base frame
GUESS_TRIED = (f"the laser turned {', '.join(f'{y:g}' for y in GUESS_YAWS)} degrees at forward offsets "
               f"{GUESS_OFFSETS[0]:g}..{GUESS_OFFSETS[-1]:g} m, kept the sharpest map")


def estimate_mount(data: BagData, res: float = 0.02, sample=None) -> tuple[float, float, float]:
    """The common mounting (turned 0, 90, 180 or -90 degrees, forward offset) that makes the
    accumulated map sharpest (fewest occupied cells), on ``sample`` (scans.ScanBatch; default
    150 scans spread over the window).

    Used when the bag has no /tf_static and no --laser-pose is given: a laser mounted behind the
    base frame (TurtleBot3 Waffle: -0.064 m) smears round obstacles into rings, a laser turned
    backwards mirrors the world around the robot.
    """
    from .streaming import sample_scans

    part = sample if sample is not None else sample_scans(data, 150)   # 150 scans suffice to compare
    base = beam_rays(data, part, (0.0, 0.0, 0.0))     # the base's pose at each beam; the mount varies below
    px, py = base.ox[base.valid], base.oy[base.valid]
    pyaw = np.broadcast_to(base.angle - data.scan_layout.angles[None, :], base.range.shape)[base.valid]
    rng = base.range[base.valid].astype(float)
    pc, ps = np.cos(pyaw), np.sin(pyaw)
    bx, by = rng * np.cos(base.angle[base.valid]), rng * np.sin(base.angle[base.valid])

    def score(dx: float, yaw: float) -> int:
        c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
        x = px + dx * pc + c * bx - s * by
        y = py + dx * ps + s * bx + c * by
        return cell_count(np.stack([x, y], 1), res)

    # a wrong turn smears far more than a wrong offset: pick the turn on every 5th offset, then the offset
    yaw = min(GUESS_YAWS, key=lambda y: min(score(dx, y) for dx in GUESS_OFFSETS[::5]))
    dx = min(GUESS_OFFSETS, key=lambda d: score(d, yaw))
    return (float(dx), 0.0, math.radians(yaw))


def choose_mount(data: BagData, laser_pose: tuple[float, float, float] | None) -> tuple[tuple[float, float, float], str]:
    """The laser's mounting (x, y, yaw rad) and where it came from: ``--laser-pose``, /tf_static,
    the first /tf transforms, else guessed from the scans."""
    if laser_pose is not None:
        return (laser_pose[0], laser_pose[1], math.radians(laser_pose[2])), "from --laser-pose"
    mount = laser_mount(data)
    if mount is not None:
        return mount, "from /tf_static"
    if data.first_tf:
        mount = laser_mount(data, "/tf")
        if mount is not None:
            return mount, "from the first /tf transforms (no /tf_static)"
    return estimate_mount(data), (f"guessed: estimated from the scans (no transform {data.base_frame} -> {data.scan_frame} "
                                  f"on /tf_static or /tf; tried {GUESS_TRIED}); pass --laser-pose=X,Y,YAW "
                                  f"(m, m, degrees) to give it")
