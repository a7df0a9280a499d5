"""The checks across fields of a loaded scenario (``check_scenario``): whole physics steps per
control tick, the episode's length, a 3D lidar's rays and record within ``SCENARIO_LIMITS``,
latencies in whole ticks, start, goal and waypoints clear of obstacles, moving obstacles no faster
than the physics step can follow (``max_resolved_speed``), and the ground's and the body's own
checks. Run by the loader after reading; call ``check_scenario`` on scenarios built in code.
"""
from __future__ import annotations

import math
from typing import Any

from .keys import SCENARIO_LIMITS
from .model import BoxObstacle, CylinderObstacle, Scenario, Simulation
from .reading import _Ctx


def _steps_per_tick(sim: Simulation) -> float:
    return 1.0 / (sim.timestep * sim.control_rate)


def _check_lidar3d(ctx: _Ctx, scenario: Scenario) -> None:
    """A 3D lidar's rays a scan (each costs ~0.3 us of CPU: 256 x 10000 rays took 0.9 s a scan) and
    the ranges an episode records (a float32 a ray a tick, kept for bags: 3 GB for 30 s of those)
    within SCENARIO_LIMITS."""
    lidar, lines = scenario.robot.lidar3d, ctx.lines
    rays = int(lidar.rings) * int(lidar.beams)
    limit = int(SCENARIO_LIMITS["max_lidar3d_rays"])
    if rays > limit:
        raise ctx.fail(f"{lidar.rings} rings x {lidar.beams} beams = {rays} rays a scan, more than the limit "
                       f"of {limit} (128 x 2048, the densest spinning lidars)", "robot.lidar3d.beams",
                       lines.get("robot.lidar3d.beams", lines.get("robot.lidar3d")),
                       f"fewer rings or beams: rings x beams at most {limit}")
    sim = scenario.simulation
    scans = math.ceil(scenario.mission.timeout * sim.control_rate - 1e-9) + 1
    size, budget = scans * rays * 4, int(SCENARIO_LIMITS["max_lidar3d_record_bytes"])
    if size > budget:
        raise ctx.fail(f"{scans} scans of {lidar.rings} x {lidar.beams} ranges (float32) would record "
                       f"{size / 2**30:.1f} GiB, more than the limit of {budget / 2**30:g} GiB",
                       "robot.lidar3d", lines.get("robot.lidar3d", lines.get("robot")),
                       "fewer rings or beams, a shorter mission.timeout or a lower simulation.control_rate "
                       f"(scans x rings x beams at most {budget // 4})")


def check_scenario(scenario: Scenario, *, _ctx: _Ctx | None = None) -> None:
    """Checks across fields: whole physics steps per tick, episode length, start/goal/waypoints clear
    of obstacles. Run by the loader; call it on scenarios built in code (e.g. generated layouts)."""
    ctx = _ctx or _Ctx(scenario.source)
    lines = ctx.lines
    sim = scenario.simulation
    steps = _steps_per_tick(sim)
    if steps > 1e6:
        raise ctx.fail(f"timestep {sim.timestep!r} s and control_rate {sim.control_rate!r} Hz give "
                       f"{steps:.3g} physics steps per control tick", "simulation.control_rate",
                       lines.get("simulation.control_rate", lines.get("simulation")),
                       "raise the control rate (planner ticks per second)")
    if steps < 1 - 1e-9 or abs(steps - round(steps)) > 1e-6 * max(1.0, steps):
        whole = max(1, round(steps))
        raise ctx.fail(f"timestep {sim.timestep!r} s and control_rate {sim.control_rate!r} Hz give "
                       f"{steps:.4g} physics steps per control tick; it must be a whole number",
                       "simulation.control_rate", lines.get("simulation.control_rate", lines.get("simulation")),
                       f"e.g. control_rate: {1.0 / (sim.timestep * whole):g} ({whole} steps of {sim.timestep:g} s)")
    episode_steps = scenario.mission.timeout / sim.timestep
    if episode_steps > SCENARIO_LIMITS["max_episode_steps"]:
        raise ctx.fail(f"timeout {scenario.mission.timeout!r} s at timestep {sim.timestep!r} s is "
                       f"{episode_steps:.3g} physics steps, more than {SCENARIO_LIMITS['max_episode_steps']:g}",
                       "mission.timeout", lines.get("mission.timeout", lines.get("mission")),
                       "shorten the timeout or lengthen the timestep")
    if scenario.robot.lidar3d is not None:
        _check_lidar3d(ctx, scenario)
    for key in ("observation", "command"):
        delay = getattr(scenario.robot.latency, key)
        ticks = delay * sim.control_rate
        if abs(ticks - round(ticks)) > 1e-6:
            field = f"robot.latency.{key}"
            raise ctx.fail(f"a delay of {delay!r} s is not a whole number of control periods "
                           f"({1.0 / sim.control_rate:g} s at {sim.control_rate:g} Hz)", field,
                           lines.get(field, lines.get("robot.latency")),
                           f"e.g. {key}: {round(ticks) / sim.control_rate:g}")
        timeout = scenario.mission.timeout
        if delay >= timeout:
            field = f"robot.latency.{key}"
            what = ("the planner would see nothing after the first observation" if key == "observation"
                    else "no command would act before the episode ends: the robot never moves")
            raise ctx.fail(f"a delay of {delay!r} s is not shorter than the timeout ({timeout!r} s): {what}",
                           field, lines.get(field, lines.get("robot.latency")),
                           f"shorten the delay below {timeout:g} s, or lengthen mission.timeout")
    if scenario.obstacles:
        _check_clear(scenario, ctx)
        _check_speeds(scenario, ctx)
    if scenario.terrain or scenario.robot.body.kind != "planar" or any(o.z is not None for o in scenario.obstacles):
        from .bodies import body_problem
        from .ground.surface import mission_problem, obstacle_problem, terrain_problem
        problem = (body_problem(scenario) or terrain_problem(scenario) or mission_problem(scenario)
                   or obstacle_problem(scenario))
        if problem is not None:
            field, message, fix = problem
            parts = field.split(".")
            line = next((lines[key] for key in (".".join(parts[:n]) for n in range(len(parts), 0, -1))
                         if key in lines), None)
            raise ctx.fail(message, field, line, fix)


STEP_SHARE = 0.2   # of the obstacle's and the robot's smallest widths: the farthest a mover may go in a step


def max_resolved_speed(scenario: Scenario, obs: Any, timestep: float | None = None) -> float:
    """The fastest a moving obstacle may go (m/s) for contacts, checked after every physics step,
    to see it cross the robot: the two may close in on each other by at most ``STEP_SHARE`` of the
    sum of their smallest widths per step (the robot's own top speed counts), so that a crossing
    overlaps at some step; at the limit only a graze shallower than ~1 % of the two widths together
    can fall between two steps (round shapes). Above it a box at 100 m/s passed through the robot
    unseen (issue 26)."""
    reach, robot_speed = _closing(scenario, obs)
    return reach / (timestep or scenario.simulation.timestep) - robot_speed


def _closing(scenario: Scenario, obs: Any) -> tuple[float, float]:
    """(how far the obstacle and the robot may close in per physics step, the robot's top speed)."""
    from .geometry import convex_parts_local, outline_points

    if isinstance(obs, BoxObstacle):
        width = min(obs.length, obs.width)
    elif isinstance(obs, CylinderObstacle):
        width = 2.0 * obs.radius
    else:                                    # polygon, mesh: the thinnest of its convex parts
        width = min(_min_width(part) for part in convex_parts_local(tuple(outline_points(obs))))
    fp = scenario.robot.footprint
    robot_width = 2.0 * fp.radius if fp.shape == "circle" else min(fp.length, fp.width)
    limits = scenario.robot.limits
    robot_speed = math.hypot(limits.max_speed, limits.max_lateral_speed if scenario.robot.drive == "omni" else 0.0)
    return STEP_SHARE * (width + robot_width), robot_speed


def _min_width(points: Any) -> float:
    """The width of a convex polygon across its thinnest direction (the least, over its edges, of
    the farthest corner from the edge's line)."""
    best = math.inf
    n = len(points)
    for i in range(n):
        (ax, ay), (bx, by) = points[i], points[(i + 1) % n]
        ex, ey = bx - ax, by - ay
        length = math.hypot(ex, ey)
        if length > 0.0:
            best = min(best, max(abs(ex * (py - ay) - ey * (px - ax)) for px, py in points) / length)
    return best


def _check_speeds(scenario: Scenario, ctx: _Ctx) -> None:
    """Moving obstacles no faster than the physics step can follow (``max_resolved_speed``)."""
    for i, obs in enumerate(scenario.obstacles):
        motion = getattr(obs, "motion", None)
        if motion is None:
            continue
        speed = math.hypot(*motion.velocity) if motion.velocity is not None else motion.speed
        limit = max_resolved_speed(scenario, obs)
        if speed <= limit:
            continue
        key = "velocity" if motion.velocity is not None else "speed"
        field = f"obstacles[{i}].motion.{key}"
        dt, period = scenario.simulation.timestep, 1.0 / scenario.simulation.control_rate
        reach, robot_speed = _closing(scenario, obs)
        steps = math.ceil(period / (reach / (speed + robot_speed)) - 1e-9)   # per tick, to follow it
        while not _decimal(steps):
            steps += 1          # a step count whose timestep is a short decimal: 0.00125, not 0.00175439
        raise ctx.fail(
            f"{speed:g} m/s is faster than the simulation can follow at a timestep of {dt:g} s: "
            f"{obs.name!r} would move {speed * dt:.3g} m per physics step and could pass through the "
            f"robot between two steps unseen; at most {max(limit, 0.0):.3g} m/s at this timestep (it and "
            f"the robot may close in by {STEP_SHARE:g} of their smallest widths per step)",
            field, ctx.lines.get(field, ctx.lines.get(f"obstacles[{i}].motion", ctx.lines.get("obstacles"))),
            f"slow it down, or give simulation.timestep: {period / steps:.10g} ({steps} steps per control tick)")


def _decimal(n: int) -> bool:
    """True if 1/n has a finite decimal expansion (n = 2^a 5^b)."""
    for p in (2, 5):
        while n % p == 0:
            n //= p
    return n == 1


def _check_clear(scenario: Scenario, ctx: _Ctx) -> None:
    """Start and goal footprints and waypoints must not touch an obstacle (names the first one)."""
    from shapely.geometry import Point

    from .geometry import bounding_radius, footprint_polygon, footprint_radius, obstacle_polygon

    mission = scenario.mission
    fp = scenario.robot.footprint
    checks = [("start", mission.start, footprint_radius(fp), "the robot's footprint at the start"),
              ("goal", mission.goal, footprint_radius(fp), "the robot's footprint at the goal")]
    checks += [(f"waypoints[{i}]", wp, 0.0, f"waypoint {i}") for i, wp in enumerate(mission.waypoints)]
    # Cheap bounding-circle test first, so thousands of obstacles cost microseconds, not polygons.
    bounds = [(o.x, o.y, bounding_radius(o)) for o in scenario.obstacles]
    moving = {i for i, o in enumerate(scenario.obstacles) if getattr(o, "motion", None) is not None}
    for key, pose, reach, what in checks:
        # a moving obstacle must leave the start clear (where it stands at t = 0); it may cross the
        # goal and the waypoints
        near = [i for i, (x, y, r) in enumerate(bounds) if math.hypot(x - pose.x, y - pose.y) <= r + reach + 1e-9
                and (key == "start" or i not in moving)]
        if not near:
            continue
        shape = (footprint_polygon(fp, pose.x, pose.y, pose.yaw_rad) if reach else Point(pose.x, pose.y))
        for i in near:
            obs = scenario.obstacles[i]
            if shape.intersects(obstacle_polygon(obs)):
                field = f"mission.{key}"
                what_moves = "start" if key == "start" else "goal" if key == "goal" else "waypoint"
                raise ctx.fail(f"{what} ({pose.x:g}, {pose.y:g}) overlaps obstacle {obs.name!r}", field,
                               ctx.lines.get(field, ctx.lines.get("mission")),
                               f"move the {what_moves} or obstacle {obs.name!r} so they are clear")

