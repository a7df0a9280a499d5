"""How the robot moved, from its odometry resampled on a regular clock: forward speed, yaw rate,
and the spans where it turned in place or drove backwards. Used by the event list and by ``--at``
(a seed cut at a turn in place holds the turn)."""
from __future__ import annotations

import numpy as np

STEP = 0.1            # s, resampling step of the odometry
STILL = 0.02          # m/s, slower is standing still
REVERSE = -0.05       # m/s, forward speed below this is driving backwards
REVERSE_MIN = 0.5     # s
TURN_RATE = 0.3       # rad/s, turning in place above this ...
TURN_MIN = 3.0        # s, ... for this long


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(first, last + 1) index pairs of the runs of True in ``mask``."""
    d = np.diff(np.r_[0, mask.astype(np.int8), 0])
    return list(zip(np.nonzero(d == 1)[0], np.nonzero(d == -1)[0]))


def resample(od: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Resampled times, poses (k, 3), forward speed and yaw rate (central differences over 0.4 s)."""
    t = np.arange(od[0, 0], od[-1, 0] + 1e-9, STEP)
    pose = np.stack([np.interp(t, od[:, 0], od[:, 1]), np.interp(t, od[:, 0], od[:, 2]),
                     np.interp(t, od[:, 0], np.unwrap(od[:, 3]))], 1)
    k = 2
    d = np.zeros_like(pose)
    if len(t) > 2 * k:
        d[k:-k] = (pose[2 * k:] - pose[:-2 * k]) / (2 * k * STEP)
    fwd = d[:, 0] * np.cos(pose[:, 2]) + d[:, 1] * np.sin(pose[:, 2])
    return t, pose, fwd, d[:, 2]


def turn_spans(t: np.ndarray, fwd: np.ndarray, rate: np.ndarray) -> list[tuple[int, int]]:
    """Index runs where the robot turned in place for TURN_MIN seconds or more."""
    speed = np.abs(fwd)
    return [(a, b) for a, b in runs((np.abs(rate) > TURN_RATE) & (speed < 2 * STILL + 0.03))
            if t[b - 1] - t[a] >= TURN_MIN]


def reverse_spans(t: np.ndarray, fwd: np.ndarray) -> list[tuple[int, int]]:
    """Index runs where the robot drove backwards for REVERSE_MIN seconds or more."""
    return [(a, b) for a, b in runs(fwd < REVERSE) if t[b - 1] - t[a] >= REVERSE_MIN]


def manoeuvre_at(od: np.ndarray, at: float, slack: float = 0.5) -> tuple[str, float, float] | None:
    """The turn in place or reversing that is under way at ``at`` (or starts within ``slack``
    seconds after it): (kind, start, end) in the odometry's times, else None."""
    if len(od) < 2:
        return None
    t, _, fwd, rate = resample(od)
    spans = [("turn in place", a, b) for a, b in turn_spans(t, fwd, rate)] + \
            [("reversing", a, b) for a, b in reverse_spans(t, fwd)]
    under_way = []
    for kind, a, b in spans:
        # the differences blur each end by two steps: the manoeuvre ends that much later
        end = float(t[min(b + 1, len(t) - 1)])
        if t[a] - slack <= at < end:
            under_way.append((end, kind, float(t[a])))
    if not under_way:
        return None
    end, kind, start = max(under_way)      # the one that goes on longest: the seed holds all of them
    return kind, start, end
