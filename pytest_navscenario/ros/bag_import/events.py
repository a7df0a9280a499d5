"""Candidate moments in a long bag where navigation may have gone wrong, with their times, so that
a user picks one and cuts a seed before it (``--at T``).

Found on the whole bag, in the seed's world frame: the robot stopped far from its goal, drove
backwards, turned in place for long, its velocity command dropped to zero while a goal was
active, or the nearest laser return came closer than its footprint plus a margin.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .frames import compose, held
from .motion import STILL, resample, reverse_spans, runs, turn_spans
from .reading import BagData

STOP_MIN = 2.0        # s, a stop shorter than this is not an event
NEAR_GOAL = 0.5       # m, closer than this the goal counts as reached


@dataclass(frozen=True)
class Event:
    t: float          # s after the first odometry message (the clock of --start/--end/--at)
    duration: float   # s
    kind: str         # stopped, reversed, turned, cmd-zero, close
    text: str


def _goal_distance(data: BagData, corr: np.ndarray | None, t: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Distance to the goal in force at each time (NaN when none: before the first goal, after arrival)."""
    out = np.full(len(t), np.nan)
    for i, (tg, frame, x, y, yaw, _) in enumerate(data.goals):
        if frame == data.odom_frame and corr is not None:
            x, y, _ = compose(held(corr, np.array([tg]))[0], np.array([x, y, yaw]))
        until = data.goals[i + 1][0] if i + 1 < len(data.goals) else math.inf
        span = (t >= tg) & (t < until)
        dist = np.hypot(pose[:, 0] - x, pose[:, 1] - y)
        reached = np.nonzero(span & (dist < NEAR_GOAL))[0]
        if len(reached):
            span &= t < t[reached[0]]
        out[span] = dist[span]
    return out


def find_events(data: BagData, corr: np.ndarray | None, robot_radius: float, margin: float,
                nearest: np.ndarray | None = None) -> list[Event]:
    """The candidate moments of the whole bag, in time order; ``nearest``: (k, 2) time and
    distance to the nearest return of each scan or cloud (see ``scan_nearest``)."""
    od = data.full_odom
    if corr is not None:
        od = np.c_[od[:, 0], compose(held(corr, od[:, 0]), od[:, 1:4])]
    t, pose, fwd, rate = resample(od)
    goal = _goal_distance(data, corr, t, pose)
    speed = np.abs(fwd)
    events: list[Event] = []
    for a, b in runs((speed < STILL) & (np.abs(rate) < 0.05)):
        dur = t[b - 1] - t[a]
        if dur < STOP_MIN or a == 0:
            continue
        g = goal[a]
        if np.isfinite(g):
            events.append(Event(t[a], dur, "stopped", f"stopped {g:.1f} m from the goal for {dur:.1f} s"))
        elif b < len(t):
            events.append(Event(t[a], dur, "stopped", f"stopped for {dur:.1f} s, then drove on (no goal recorded)"))
    for a, b in reverse_spans(t, fwd):
        dist = float(np.hypot(*(pose[b - 1, :2] - pose[a, :2])))
        events.append(Event(t[a], t[b - 1] - t[a], "reversed", f"drove backwards {dist:.1f} m"))
    for a, b in turn_spans(t, fwd, rate):
        # the differences blur each end by 2 steps: measure the turn over the run widened by them
        turn = math.degrees(abs(pose[min(b + 1, len(t) - 1), 2] - pose[max(a - 2, 0), 2]))
        events.append(Event(t[a], t[b - 1] - t[a], "turned", f"turned in place {turn:.0f} deg in "
                                                                f"{t[b - 1] - t[a]:.1f} s"))
    events += _command_drops(data, t, goal)
    events += _close_returns(np.zeros((0, 2)) if nearest is None else nearest, robot_radius, margin)
    return sorted(events, key=lambda e: (e.t, e.kind))


def _command_drops(data: BagData, t: np.ndarray, goal: np.ndarray) -> list[Event]:
    """The velocity command falling to zero while a goal was active and not reached."""
    cmd = data.cmd
    if len(cmd) < 2:
        return []
    moving = (np.abs(cmd[:, 1]) > 1e-3) | (np.abs(cmd[:, 2]) > 1e-3)
    out = []
    for i in np.nonzero(moving[:-1] & ~moving[1:])[0] + 1:
        g = float(np.interp(cmd[i, 0], t, np.nan_to_num(goal, nan=-1.0)))
        if g > NEAR_GOAL:
            out.append(Event(float(cmd[i, 0]), 0.0, "cmd-zero",
                             f"velocity command dropped to zero {g:.1f} m from the active goal"))
    return out


def scan_nearest(data: BagData, mount: tuple[float, float, float]) -> np.ndarray:
    """(k, 2) time and distance from the base to the nearest valid return of each scan, streamed
    (scans.stream_scans: one batch in memory, however long the bag)."""
    from .projection import beam_rays, poses_at
    from .streaming import stream_scans

    rows = []
    for batch in stream_scans(data):
        r = beam_rays(data, batch, mount)
        rng = np.where(r.valid, r.range, 0.0).astype(float)
        px, py = r.ox + rng * np.cos(r.angle), r.oy + rng * np.sin(r.angle)
        base = poses_at(data, np.broadcast_to(r.t, r.range.shape))
        dist = np.where(r.valid, np.hypot(px - base[..., 0], py - base[..., 1]), np.inf)
        rows.append(np.stack([batch.t, dist.min(axis=1)], 1))
    return np.concatenate(rows) if rows else np.zeros((0, 2))


def _close_returns(nearest: np.ndarray, radius: float, margin: float) -> list[Event]:
    """Runs of scans or clouds whose nearest return is closer than the footprint plus ``margin``."""
    if not len(nearest):
        return []
    gap = nearest[:, 1] - radius
    out = []
    for a, b in runs(gap < margin):
        g = float(gap[a:b].min())
        out.append(Event(float(nearest[a, 0]), float(nearest[b - 1, 0] - nearest[a, 0]), "close",
                         f"nearest return {g * 100:.0f} cm from the footprint (margin {margin * 100:.0f} cm)"))
    return out


def format_events(events: list[Event]) -> list[str]:
    """One line per event: time, duration, what happened."""
    if not events:
        return ["no candidate moments found (no stop far from a goal, no reversing, no long turn in place, "
                "no command dropped to zero, no return inside the footprint margin)"]
    return [f"t={e.t:8.1f} s  {e.kind:9s} {e.text}" for e in events]


def bag_events(path, *, odom_topic: str | None = None, scan_topic: str | None = None,
               cloud_topic: str | None = None, frame: str = "auto", map_frame: str = "map",
               pose_topic: str | None = None, laser_pose: tuple[float, float, float] | None = None,
               robot_radius: float | None = None, margin: float = 0.05) -> tuple[list[Event], list[str]]:
    """The candidate moments of a whole bag, and notes on the frame and sensors used."""
    from .reading import close_bag, open_bag, read_bag

    reader = open_bag(Path(path))    # one open bag for both passes
    try:
        data = read_bag(path, odom_topic=odom_topic, scan_topic=scan_topic, cloud_topic=cloud_topic, reader=reader)
        return _events(data, frame, map_frame, pose_topic, laser_pose, robot_radius, margin)
    finally:
        close_bag(reader)


def _events(data: BagData, frame, map_frame, pose_topic, laser_pose, robot_radius, margin):
    from .footprint import footprint_from_bag, inner_radius
    from .frames import to_world_frame
    from .mount import choose_mount

    corr = to_world_frame(data, frame, map_frame, pose_topic, data.full_odom)
    notes = list(data.notes)
    fp, how, _ = footprint_from_bag(data, robot_radius)
    notes.append(f"footprint: {how}")
    radius = inner_radius(fp)
    nearest = None
    if data.scan_topic is not None:
        mount, how = choose_mount(data, laser_pose)
        notes.append(f"laser {data.scan_frame} at x={mount[0]:.3f} y={mount[1]:.3f} "
                     f"yaw={math.degrees(mount[2]):.1f} deg in {data.base_frame}, {how}")
        from .projection import settle_timing
        settle_timing(data, mount)
        nearest = scan_nearest(data, mount)
        from .streaming import stream_notes
        notes.extend(stream_notes(data))
    elif data.cloud_topic is not None:
        from .clouds import CloudSettings, grid_clouds
        clouds = grid_clouds(data, laser_pose, CloudSettings(near=radius), 0.05)
        notes.extend(clouds.notes)
        nearest = clouds.nearest
    else:
        notes.append("no laser scan or point cloud: the gap to the nearest return is not checked")
    if not data.goals:
        notes.append("no navigation goal in the bag: stops are listed only where the robot drove on after them")
    return find_events(data, corr, radius, margin, nearest), notes
