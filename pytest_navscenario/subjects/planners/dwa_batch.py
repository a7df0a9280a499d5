"""``dwa``'s tick for a batch of episodes (``DynamicWindowPlanner.act_batch``): each episode gets
the command ``act`` gives it alone, bit for bit, and the batch pays a few dozen numpy calls a tick
instead of a few dozen per episode.

What may be done for the whole batch and what may not:

* elementwise operations (abs, subtract, maximum, square, add, sqrt, arctan2, comparisons) and
  exact reductions (minimum) give every element the same bits whatever array it sits in, so they
  run once over buffers that hold every episode's candidates side by side;
* matrix products do not: BLAS adds in an order that can change with the shapes (measured on this
  project's machine: a float32 product with 3 inner terms changes in the last bit for some columns
  when the number of columns changes, and a one-column product goes through gemv, which rounds
  differently). So each episode's products (its rollout poses times its nearby lidar points, the
  lane map times the points, the score rows times the target, the weights times the terms) are
  computed exactly as ``act`` computes them: one call per episode with the same shapes and
  contiguous inputs, written into the batch buffers through ``out=`` (the row stride of the output
  is an address, not a term of any sum). Nothing is padded inside a product; the buffers' unused
  columns hold ``BIG``, which no minimum picks.

The per-episode logic (the dynamic window, stall detection and the route, the detour, the goal
phase, the choice) is the single planner's own code, called on one ``DynamicWindowPlanner`` per
episode; ``tests/subjects/test_dwa_batch.py`` and ``benchmarks/check_bit_identical.py --batch``
compare the commands bit for bit on every shipped seed and on search candidates.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from ..protocol import Command, Observation
from ._common import require_reset, wrap_angle

BIG = np.float32(1e15)   # unused buffer columns: squared (1e30) above any real squared distance


def act_batch(planners: Sequence[Any], observations: Sequence[Observation]) -> list[Command]:
    """One tick of every episode: ``planners[k]`` (a reset ``DynamicWindowPlanner``) sees
    ``observations[k]``; returns their commands, each the one its ``act`` would return."""
    k = len(planners)
    wins = []
    for ep, obs in zip(planners, observations):
        require_reset(ep._p, "DynamicWindowPlanner")
        wins.append(ep._dynamic_window(obs))
    points = _near_points(planners, observations, wins)
    near = [j for j in range(k) if points[j] is not None]
    order = near + [j for j in range(k) if points[j] is None]
    start = [0] * k                  # each episode's first candidate in the flat buffers
    total = 0
    for j in order:
        start[j] = total
        total += wins[j].n
    terms = np.empty((3, total))     # rows: distance to target, heading error, clearance
    _clearance(planners, wins, points, near, order, start, terms)
    aims = _aim(planners, observations, points)
    score = _score(planners, observations, wins, aims, order, start, terms)
    out = []
    for j in range(k):
        ep, win = planners[j], wins[j]
        a, b = start[j], start[j] + win.n
        best = ep._choose(win, score[a:b], terms[2, a:b], aims[j][0])
        ep._idx = win.cand[best]
        out.append(win.commands[best])
    return out


def _near_points(planners, observations, wins) -> list[np.ndarray | None]:
    """Each episode's lidar points within its window's reach as [px, py, 1] float32 columns (the
    ``P`` of ``_clearance``), or None. Episodes with the same beam layout (the same shared unit
    vectors, _beam_geometry) are thresholded and projected together."""
    groups: dict[tuple, list[int]] = {}
    for j, (ep, obs) in enumerate(zip(planners, observations)):
        groups.setdefault((id(ep._unit), obs.ranges.dtype), []).append(j)
    points: list[np.ndarray | None] = [None] * len(planners)
    for members in groups.values():
        unit = planners[members[0]]._unit
        ranges = np.stack([observations[j].ranges for j in members])
        # act compares with a Python float, which numpy casts to the ranges' dtype
        limit = np.array([min(wins[j].reach, planners[j]._p.range_max * 0.999) for j in members],
                         dtype=ranges.dtype)
        mask = ranges < limit[:, None]
        counts = np.count_nonzero(mask, axis=1).tolist()
        if not any(counts):
            continue
        cols = mask.nonzero()[1]
        pts = np.empty((3, len(members), unit.shape[1]), dtype=np.float32)
        pts[2] = 1.0
        np.multiply(unit[:, None, :], ranges, out=pts[:2])
        a = 0
        for g, j in enumerate(members):
            c = counts[g]
            if c:
                points[j] = pts[:, g][:, cols[a:a + c]]    # contiguous (3, m), as act's gather
                a += c
    return points


def _clearance(planners, wins, points, near, order, start, terms) -> None:
    """``DynamicWindowPlanner._clearance`` for every episode into ``terms[2]``: the products per
    episode into one buffer, then the distances, minimum, root and cap once for all."""
    clear = terms[2]
    if near:
        rows = [wins[j].rot3.shape[0] for j in near]
        width = max(points[j].shape[1] for j in near)
        e = np.full((sum(rows), width), BIG, dtype=np.float32)
        r0 = 0
        for j, r in zip(near, rows):
            p = points[j]
            np.matmul(wins[j].rot3, p, out=e[r0:r0 + r, :p.shape[1]])
            r0 += r
        half = wins[near[0]].half if len(near) == 1 else np.concatenate([wins[j].half for j in near])
        np.abs(e, out=e)
        e -= half
        np.maximum(e, 0.0, out=e)
        np.square(e, out=e)
        e3 = e.reshape(-1, 2, width)
        d2 = e3[:, 0] + e3[:, 1]                                  # (poses, width)
        n_near = sum(wins[j].n for j in near)
        mine = clear[:n_near]
        np.minimum.reduce(d2.reshape(n_near, -1), axis=1, out=mine)
        np.sqrt(mine, out=mine)
        mine -= _per_candidate([planners[j]._t.radius + planners[j]._inflation for j in near],
                               [wins[j].n for j in near])
        np.minimum(mine, _per_candidate([planners[j]._t.cap for j in near], [wins[j].n for j in near]),
                   out=mine)
    for j in order[len(near):]:
        clear[start[j]:start[j] + wins[j].n].fill(planners[j]._t.cap)


def _per_candidate(values: list[float], counts: list[int]) -> Any:
    """A per-episode value for every candidate: the Python float itself when all are equal."""
    first = values[0]
    if all(v == first for v in values):
        return first
    return np.repeat(np.array(values), counts)


def _aim(planners, observations, points) -> list[tuple[bool, float, float]]:
    """``DynamicWindowPlanner._aim`` for every episode: the route per episode, then the blocked-lane
    test of every episode that needs one in one pass (the lane products per episode)."""
    aims = []
    lanes = []            # (episode, lane length) of the episodes whose lane is tested
    for j, (ep, obs) in enumerate(zip(planners, observations)):
        routed, tx, ty = ep._aim_route(obs)
        aims.append((routed, tx, ty))
        if not routed and points[j] is not None and ep.lookahead > 0:
            lanes.append((j, ep._set_lane(tx, ty)))
    if lanes:
        width = max(points[j].shape[1] for j, _ in lanes)
        lane = np.full((2 * len(lanes), width), BIG, dtype=np.float32)
        for g, (j, _) in enumerate(lanes):
            p = points[j]
            np.matmul(planners[j]._lane_map, p, out=lane[2 * g:2 * g + 2, :p.shape[1]])
        np.abs(lane, out=lane)
        free = (np.minimum.reduce(np.maximum(lane[0::2], lane[1::2]), axis=1) >= 1.0).tolist()
        for (j, length), ok in zip(lanes, free):
            ep = planners[j]
            routed, tx, ty = aims[j]
            if ok:
                ep._side = 0.0
            else:
                aims[j] = (routed,) + ep._detour(tx, ty, points[j], length)
    return aims


def _score(planners, observations, wins, aims, order, start, terms) -> np.ndarray:
    """``DynamicWindowPlanner._score`` for every episode: the flat score of all candidates."""
    dist, heading = terms[0], terms[1]
    goal_phase = []                  # (episode, q, want) of the episodes turning to the goal yaw
    tol = []
    for j in order:
        ep, obs, win = planners[j], observations[j], wins[j]
        p = ep._p
        _, tx, ty = aims[j]
        d0sq = tx * tx + ty * ty
        d0 = math.sqrt(d0sq)
        v = ep._target_vec
        v[0], v[1], v[3] = tx, ty, d0sq
        q = win.score_rows @ v
        n, steps = win.n, ep.steps
        nk = n * steps
        a = start[j]
        wp = ep._weights[0]
        if ep._in_goal_phase(obs, d0):
            goal_phase.append((j, q, float(wrap_angle(p.goal_yaw - float(obs.pose[2])))))
            dist[a:a + n] = 0.0          # written over below; defined values for the batch pass
            heading[a:a + n] = 0.0
            k_dist = -wp / max(p.goal_tolerance, 1e-6)
            tol.append(-math.inf)
        else:
            np.minimum.reduce(q[:nk].reshape(n, steps), axis=1, out=dist[a:a + n])
            np.arctan2(q[nk + n:], q[nk:nk + n], out=heading[a:a + n])
            tol.append(0.5 * (p.waypoint_tolerance if len(obs.waypoints) else p.goal_tolerance))
            k_dist = -wp / (p.max_speed * ep.horizon)
        w = ep._term_weights
        w[0] = k_dist
        if p.omni and d0 < ep.near:
            w[1] = -ep.weights[1] / math.pi * (d0 / ep.near)
        else:
            w[1] = -ep.weights[1] / math.pi
    # the closest approach along each rollout and the bearing at its end (goal-phase episodes
    # are written over below); a rollout that reaches the target has no heading error
    np.sqrt(np.maximum(dist, 0.0, out=dist), out=dist)
    np.abs(heading, out=heading)
    heading[dist < _per_candidate(tol, [wins[j].n for j in order])] = 0.0
    for j, q, want in goal_phase:
        win = wins[j]
        n, a, nk = win.n, start[j], win.n * planners[j].steps
        np.abs(wrap_angle(want - win.stop_yaw), out=heading[a:a + n])
        np.hypot(q[nk:nk + n], q[nk + n:], out=dist[a:a + n])
    score = np.empty(dist.shape[0])
    for j in order:
        a, b = start[j], start[j] + wins[j].n
        np.matmul(planners[j]._term_weights, terms[:, a:b], out=score[a:b])
    score += wins[order[0]].static if len(order) == 1 else np.concatenate([wins[j].static for j in order])
    score[terms[2] < _per_candidate([planners[j]._min_clear for j in order], [wins[j].n for j in order])] = -np.inf
    return score
