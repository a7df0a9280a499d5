"""Building the seed: start, goal, driven path, limits, lidar and robot from what was read and fitted."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...scenario.model import (
    CylinderObstacle,
    Footprint,
    GoalTolerance,
    Lidar,
    Limits,
    Mission,
    Obstacle,
    PolygonObstacle,
    Pose,
    Reference,
    Robot,
    Scenario,
)
from .clouds import CloudSettings, grid_clouds
from .ground import drop_ground_obstacles, terrain_from_ground
from .fit import FitFigure, fit_figure
from .footprint import footprint_from_bag, inner_radius
from .frames import to_world_frame
from .goal import choose_goal
from .known_map import map_background, not_on_map
from .mount import choose_mount
from .obstacles import FitSettings, _r, fit_obstacles, occupied_clusters
from .projection import map_scans, settle_timing
from .reading import PATH_AS, BagData, BagImportError, close_bag, open_bag, read_bag
from .robot import RobotChoice, base_robot, describe, seed_robot
from .streaming import stream_notes
from .simplify import SeedSize, merge_neighbours, split_near_path


def _peak_rates(od: np.ndarray, window: float = 0.5) -> tuple[float, float]:
    """98th-percentile speed (m/s) and yaw rate (rad/s) over ``window``-second steps (odometry
    jitter makes per-message differences useless for limits)."""
    if len(od) < 2 or od[-1, 0] - od[0, 0] <= 0:
        return 0.0, 0.0
    t = np.arange(od[0, 0], od[-1, 0], window / 5)
    if len(t) < 6:
        return 0.0, 0.0
    x, y = np.interp(t, od[:, 0], od[:, 1]), np.interp(t, od[:, 0], od[:, 2])
    yaw = np.interp(t, od[:, 0], np.unwrap(od[:, 3]))
    speed = np.hypot(x[5:] - x[:-5], y[5:] - y[:-5]) / window
    rate = np.abs(yaw[5:] - yaw[:-5]) / window
    return float(np.percentile(speed, 98)), float(np.percentile(rate, 98))


@dataclass
class BagSeed:
    """The importer's result: the scenario, the driven path (t, x, y), what to tell the user and
    how well the seed agrees with its own scans (None without scans)."""
    scenario: Scenario
    path: np.ndarray
    notes: list[str]
    mount: tuple[float, float, float] | None = None
    fit: FitFigure | None = None
    files: dict[str, bytes] = dataclasses.field(default_factory=dict)   # beside the seed (a heightfield)


def decimate_path(xy: np.ndarray, tolerance: float = 0.15, min_spacing: float = 0.5) -> np.ndarray:
    """Waypoints that follow the driven path within ``tolerance`` (Douglas-Peucker), no two
    closer than ``min_spacing``; excludes the first and last point (start and goal)."""
    from shapely.geometry import LineString
    if len(xy) < 3:
        return np.zeros((0, 2))
    simple = np.asarray(LineString(xy).simplify(tolerance, preserve_topology=False).coords)
    pts = [simple[0]]
    for p in simple[1:-1]:
        if np.hypot(*(p - pts[-1])) >= min_spacing:
            pts.append(p)
    inner = np.asarray(pts[1:])
    if len(inner) and np.hypot(*(inner[-1] - simple[-1])) < min_spacing:
        inner = inner[:-1]
    return inner.reshape(-1, 2)


def scenario_from_bag(path: str | Path, *, odom_topic: str | None = None, scan_topic: str | None = None,
                      start: float | None = None, end: float | None = None,
                      laser_pose: tuple[float, float, float] | None = None,
                      path_as: str = "waypoints", reference_file: str | None = None,
                      name: str = "", robot_radius: float | None = None,
                      settings: FitSettings = FitSettings(), frame: str = "auto", map_frame: str = "map",
                      pose_topic: str | None = None, cloud_topic: str | None = None,
                      cloud: CloudSettings = CloudSettings(), goal_topic: str | None = None,
                      at: float | None = None, window: float = 30.0, size: SeedSize = SeedSize(),
                      scan_stamp: str = "auto", scan_offset: float = 0.0,
                      robot: RobotChoice = RobotChoice()) -> BagSeed:
    """Build a seed scenario from a bag (see the package docstring). ``laser_pose`` is x, y (m),
    yaw (degrees) of the laser in the robot's base frame; ``robot_radius`` the seed's circular
    footprint (m; default: from the bag's URDF or Nav2 footprint, else 0.15 m); ``reference_file`` is the CSV name
    written into ``scenario.reference`` when ``path_as`` is ``"reference"`` or ``"both"``
    (waypoints to drive the loop and the reference to measure how closely the run replays it).
    ``at``: cut the ``window`` seconds before this moment instead of ``start``..``end``.
    ``frame``: "auto" (the map frame when the bag has ``map -> odom`` or a pose topic in it, else
    the odometry frame), "map" or "odom". ``scan_stamp`` ("auto", "start", "end") and
    ``scan_offset`` (s): when each scan was taken (scans.choose_timing). ``robot``: --robot,
    --footprint, --drive (robot.py; a bag of ours gives the robot of the scenario it ran)."""
    if robot_radius is not None and not (math.isfinite(robot_radius) and 0 < robot_radius <= 5):
        raise BagImportError(f"--robot-radius must be a length in (0, 5] m, got {robot_radius}")
    if path_as not in PATH_AS:
        raise BagImportError(f"--path-as must be one of {', '.join(PATH_AS)}, got {path_as!r}")
    if at is not None and (start is not None or end is not None):
        raise BagImportError("--at cuts the window before a moment: give it without --start/--end")
    if scan_topic and cloud_topic:
        raise BagImportError("--scan-topic and --cloud-topic: give one (obstacles come from a laser or a 3D lidar)")
    reader = open_bag(Path(path))    # one open bag for every pass: its index and types are read once
    try:
        data = read_bag(path, odom_topic=odom_topic, scan_topic=scan_topic, start=start, end=end,
                        cloud_topic=cloud_topic, at=at, window=window, scan_stamp=scan_stamp,
                        scan_offset=scan_offset, reader=reader)
        return _seed(data, laser_pose, path_as, reference_file, name, robot_radius, settings, frame, map_frame,
                     pose_topic, cloud, goal_topic, size, robot)
    finally:
        close_bag(reader)


def _seed(data: BagData, laser_pose, path_as, reference_file, name, robot_radius, settings, frame, map_frame,
          pose_topic, cloud, goal_topic, size, choice: RobotChoice) -> BagSeed:
    corr = to_world_frame(data, frame, map_frame, pose_topic, data.full_odom)
    goal, goal_note = choose_goal(data, corr, goal_topic)
    base, base_how, fp_warnings = base_robot(data, choice)
    if choice.footprint is not None:
        fp, fp_how = choice.footprint, f"{describe(choice.footprint)} from --footprint {choice.footprint_text}"
    elif base is not None and robot_radius is None:
        fp, fp_how = base.footprint, base_how
    else:
        fp, fp_how, more = footprint_from_bag(data, robot_radius)
        fp_warnings += more
    radius = inner_radius(fp)
    notes = list(data.notes) + [goal_note] + [f"warning: {w}" for w in fp_warnings] + [f"footprint: {fp_how}"]
    obstacles: list[Obstacle] = []
    mount = smap = terrain = None
    if data.scan_topic is not None:
        mount, how = choose_mount(data, laser_pose)
        notes.append(f"laser {data.scan_frame} at x={mount[0]:.3f} y={mount[1]:.3f} "
                     f"yaw={math.degrees(mount[2]):.1f} deg in {data.base_frame}, {how}")
        settle_timing(data, mount)
        smap = map_scans(data, mount, settings.res)
        notes.extend(stream_notes(data))
        if smap.scans:
            notes.append(_timing_note(data, smap))
            obstacles = _fit_scans(data, smap, settings, notes)
            notes += check_path_free(data, obstacles, radius, how)
        else:
            notes.append(f"no scans on {data.scan_topic} within the window: the seed has the trajectory only, "
                         f"no obstacles")
    elif data.cloud_topic is not None:
        clouds = grid_clouds(data, laser_pose, dataclasses.replace(cloud, near=max(cloud.near, radius)), settings.res)
        notes.extend(clouds.notes)
        grid, how = clouds.grid, clouds.how
        obstacles = _fit(data, grid, settings, notes, f"{data.cloud_count} clouds")
        terrain = _ground(data, clouds, notes)
        obstacles = drop_ground_obstacles(obstacles, terrain.raised, notes)
        notes += check_path_free(data, obstacles, radius, how, data.cloud_topic)
    obstacles, background = _keep_small(data, obstacles, radius, size, notes)
    scenario, summary = _scenario(data, obstacles, path_as, reference_file, name, fp, goal)
    scenario = dataclasses.replace(scenario, robot=seed_robot(scenario.robot, base, choice, fp))
    if base is not None or choice.drive:
        notes.append(f"robot: {scenario.robot.drive} drive, top speed {scenario.robot.limits.max_speed:g} m/s, from "
                     + (base_how if base is not None else "the bag") + (f", --drive {choice.drive}" if choice.drive else ""))
    if terrain is not None and terrain.elements:
        scenario = _on_terrain(scenario, terrain, clouds, notes, keep=base is not None)
    if background:
        scenario = dataclasses.replace(scenario, search={"frozen": background})
    notes.append(summary)
    _check_moves(data, scenario)
    fit = None
    if smap is not None and smap.scans:
        fit = fit_figure(scenario, data, mount, smap.sample, smap.first)
    od = data.odom
    path_rows = np.stack([od[:, 0] - od[0, 0], od[:, 1], od[:, 2]], axis=1)
    return BagSeed(scenario=scenario, path=path_rows, notes=notes, mount=mount, fit=fit,
                   files=dict(terrain.files) if terrain is not None else {})


def _ground(data: BagData, clouds: Any, notes: list[str]) -> Any:
    """The terrain the clouds saw (ground.py), its ground heights made relative to the floor."""
    od = data.odom
    up = data.odom_up
    if len(up) and not np.any(up[:, 1:]):
        notes.append("ground: the odometry is planar (no height, roll or pitch): the robot counts as level at z = 0, "
                     "so ground it drove up or down is placed too low or too high; record 3D odometry for terrain")
    guess = terrain_from_ground(clouds.ground, (float(od[0, 1]), float(od[0, 2])), od[:, 1:3])
    notes.extend(guess.notes)
    return guess


def _on_terrain(scenario: Scenario, terrain: Any, clouds: Any, notes: list[str], keep: bool = False) -> Scenario:
    """The seed with the terrain, a body that rides it and the 3D lidar the bag had (guessed;
    ``keep``: the robot is known, --robot's or the recorded scenario's, and a body and a 3D lidar
    it has are kept)."""
    from ...scenario.terrain import Lidar3D, WheeledBody

    robot = scenario.robot
    if keep and robot.body.kind != "planar" and robot.lidar3d is not None:
        return dataclasses.replace(scenario, terrain=tuple(terrain.elements))
    keep_body = keep and robot.body.kind != "planar"

    m = clouds.mount if clouds.mount is not None else np.eye(4)
    pitch = math.degrees(math.atan2(-m[2, 0], m[0, 0]))
    rows, cols = clouds.layout or (1, 0)
    organised = rows > 1 and cols > 1
    lidar3d = Lidar3D(rings=rows if organised else 16, beams=min(cols, 4096) if organised else 360,
                      mount_x=_r(m[0, 3]), mount_y=_r(m[1, 3]), mount_z=_r(m[2, 3]), mount_pitch=_r(pitch, 2))
    notes.append(f"robot.lidar3d: mounted as the cloud's frame (x={m[0, 3]:.2f}, z={m[2, 3]:.2f} m, pitch "
                 f"{pitch:.1f} deg); " + (f"{rows} rings x {cols} beams from the organised cloud" if organised else
                                          "16 rings x 360 beams, -15..15 deg (a guess: the clouds are not organised)"))
    if not keep_body:
        notes.append("robot.body: wheeled (a guess: a bag does not say how the robot meets the ground; set robot.body)")
    robot = dataclasses.replace(robot, body=robot.body if keep_body else WheeledBody(),
                                lidar3d=robot.lidar3d if keep and robot.lidar3d is not None else lidar3d)
    return dataclasses.replace(scenario, terrain=tuple(terrain.elements), robot=robot)


def _timing_note(data: BagData, smap) -> str:
    """When the scans' beams were taken, and how much the robot moved within one scan."""
    timing = data.scan_timing
    text = f"scan timing: {timing.how}"
    if timing.skewed:
        m, deg = smap.skew
        text += (f"; each beam placed with the robot's pose at its own time (within one scan the robot moved up "
                 f"to {m:.2f} m and turned up to {deg:.1f} deg)")
    return text


def _fit_scans(data: BagData, smap, settings: FitSettings, notes: list[str]) -> list[Obstacle]:
    """Obstacles from the cells with returns that the occupancy grid still holds occupied after
    every beam carved its free way (log-odds > 0)."""
    grid = smap.grid
    cells = grid.cells
    occupied = smap.occupancy.at_cells(cells[:, 0], cells[:, 1]) > 0.0
    hit = grid.counts >= 2
    carved = int(np.count_nonzero(hit & ~occupied))
    if carved:
        notes.append(f"{carved} of {int(hit.sum())} cells with returns were crossed by later beams more often "
                     f"than hit (a smear, or something that moved away): carved free")
    occ = smap.occupancy
    return _fit(data, grid, settings, notes, f"{smap.scans} scans", occupied=occupied,
                seen_free=lambda cols, rows: occ.at_cells(cols, rows) < 0.0)


def _check_moves(data: BagData, scenario: Scenario) -> None:
    """A seed whose start already satisfies its goal tests nothing: the robot did not move, or drove
    a loop back to where it started (with no waypoints to follow it)."""
    from ...verdict.feasibility import trivially_passed

    if trivially_passed(scenario) is None:
        return
    od = data.odom
    extent = float(np.hypot(*(od[:, 1:3].max(axis=0) - od[:, 1:3].min(axis=0))))
    window = f"t={od[0, 0]:.1f}..{od[-1, 0]:.1f} s"
    if extent <= 2 * scenario.mission.goal_tolerance.position:
        raise BagImportError(f"{data.path}: the robot hardly moved in the window ({window}, {len(od)} poses within "
                             f"{extent:.2f} m) and no recorded goal lies farther: the seed's start would already be "
                             f"at its goal; choose a window where the robot drives (--start/--end, --at), or check "
                             f"{data.odom_topic}")
    raise BagImportError(f"{data.path}: the robot drove a loop in the window ({window}, {extent:.1f} m across) and "
                         f"ended where it started, with no recorded goal elsewhere: the seed's start would already "
                         f"be at its goal; end the window before it comes back (--end), or keep the loop as "
                         f"waypoints (--path-as waypoints or both)")


def _fit(data: BagData, grid, settings: FitSettings, notes: list[str], what: str,
         occupied: np.ndarray | None = None, seen_free=None) -> list[Obstacle]:
    clusters, dropped = occupied_clusters(grid, link=settings.link, occupied=occupied)
    obstacles = fit_obstacles(clusters, settings, free_xy=data.odom[:, 1:3], seen_free=seen_free)
    n_cyl = sum(isinstance(o, CylinderObstacle) for o in obstacles)
    n_poly = sum(isinstance(o, PolygonObstacle) for o in obstacles)
    notes.append(f"{what}, {grid.returns} returns -> {len(clusters)} clusters -> "
                 f"{n_cyl} cylinders, {len(obstacles) - n_cyl - n_poly} boxes, {n_poly} wall outlines"
                 + (f" ({dropped} specks of < 3 cells ignored as noise)" if dropped else ""))
    return obstacles


def _keep_small(data: BagData, obstacles: list[Obstacle], radius: float, size: SeedSize,
                notes: list[str]) -> tuple[list[Obstacle], list[str]]:
    """Neighbours merged into polygons; with the bag's /map in the seed's frame, the map near the
    path as the background and only what it lacks from the sensors; the obstacles near the driven
    path searchable, the rest (and the map) the fixed background. Returns obstacles, background names."""
    free = data.odom[:, 1:3]
    merged, n = merge_neighbours(obstacles, free, size, clearance=radius)
    if n:
        notes.append(f"{len(obstacles)} obstacles -> {len(merged)}: {n} merged with a neighbour closer than "
                     f"{size.merge_gap:g} m into simplified polygons (outline1, ...)")
    fixed_map: list[Obstacle] = []
    if data.known_map is not None and merged:
        new, note = not_on_map(data.known_map, merged, data.frame)
        notes.append(note)
        if data.known_map.frame == data.frame:
            cells = map_background(data.known_map, free, size.map_reach)
            fixed_map, _ = merge_neighbours(cells, free, dataclasses.replace(size, merge_gap=data.known_map.resolution))
            fixed_map = [dataclasses.replace(o, name=f"map{i}") for i, o in enumerate(fixed_map, 1)]
            notes.append(f"{data.known_map.topic} is the fixed background: {len(fixed_map)} obstacles within "
                         f"{size.map_reach:g} m of the driven path; of the sensors' obstacles the "
                         f"{len(new)} not on the map are kept")
            merged = new
            size = dataclasses.replace(size, near=math.inf)   # what the map lacks is the likeliest cause
    searchable, far = split_near_path(merged, free, radius, size)
    background = [o.name for o in fixed_map] + far
    if background:
        within = "not on the map" if fixed_map else f"within {size.near:g} m of the driven path"
        notes.append(f"{len(searchable)} obstacle(s) {within} are searchable; "
                     f"{len(background)} are a fixed background (search: frozen) that the search does not move")
    return fixed_map + merged, background


SYSTEMATIC = 0.2   # share of the driven path under obstacles above which the sensor's mounting is wrong


def check_path_free(data: BagData, obstacles: list[Obstacle], radius: float, how: str,
                    topic: str | None = None) -> list[str]:
    """Fitted obstacles must not overlap the footprint where the robot drove. Over the start, the
    window's end or more than SYSTEMATIC of the path, the sensor's mounting (or the localisation)
    is wrong: an error saying where the mounting came from and how to give it. A few local
    overlaps are something that moved (a person, a door): warnings naming them."""
    import shapely

    from ...scenario.geometry import obstacle_polygon

    if not obstacles:
        return []
    od = data.odom
    step = np.hypot(*np.diff(od[:, 1:3], axis=0).T).cumsum()
    keep = np.r_[0, np.nonzero(np.diff(np.floor(step / 0.05)) > 0)[0] + 1, len(od) - 1]
    pts = shapely.points(od[keep, 1:3])
    hits = {o.name: shapely.distance(obstacle_polygon(o), pts) < radius - 1e-3 for o in obstacles}
    under = np.any(list(hits.values()), axis=0)
    if not under.any():
        return []
    if under[0] or under[-1] or under.mean() > SYSTEMATIC:
        i = 0 if under[0] else len(keep) - 1 if under[-1] else int(np.argmax(under))
        name = next(n for n, h in hits.items() if h[i])
        k = keep[i]
        where = "the start" if i == 0 else "the end of the window" if i == len(keep) - 1 else "the driven path"
        raise BagImportError(
            f"{data.path}: the obstacles fitted from {topic or data.scan_topic} overlap the robot's footprint "
            f"(radius {radius} m) on {where} (t={od[k, 0]:.1f} s, x={od[k, 1]:.2f}, y={od[k, 2]:.2f}: {name}) "
            f"and on {under.mean():.0%} of the driven path, where the robot drove: the laser mounting is likely "
            f"wrong. It was {how}. Give it with --laser-pose=X,Y,YAW (the laser in {data.base_frame}, from the "
            f"robot's URDF), or a smaller --robot-radius if the footprint is too large"
            + (f"; the poses are in the {data.frame} frame from the bag's localisation: if it was off, "
               f"--frame odom uses the odometry alone" if data.frame != data.odom_frame else ""))
    return [f"warning: {o.name} at ({o.x:.2f}, {o.y:.2f}) lies where the robot drove "
            f"(t={od[keep[int(np.argmax(hits[o.name]))], 0]:.1f} s): something that moved (a person, a door)? "
            f"Remove it from the seed if so" for o in obstacles if hits[o.name].any()]


def _scenario(data: BagData, obstacles: list[Obstacle], path_as: str, reference_file: str | None,
              name: str, footprint: Footprint, goal: tuple[float, float, float] | None = None
              ) -> tuple[Scenario, str]:
    """The seed scenario from the odometry window and the obstacles (the goal: ``goal``, else
    the window's last pose), and a one-line summary."""
    od = data.odom
    start_pose = Pose(_r(od[0, 1]), _r(od[0, 2]), _r(math.degrees(od[0, 3]), 2))
    gx, gy, gyaw = goal if goal is not None else od[-1, 1:4]
    goal_pose = Pose(_r(gx), _r(gy), _r(math.degrees(gyaw), 2))
    length = float(np.hypot(*np.diff(od[:, 1:3], axis=0).T).sum())
    duration = float(od[-1, 0] - od[0, 0])
    waypoints: tuple[Pose, ...] = ()
    reference = None
    if path_as in ("waypoints", "both"):
        waypoints = tuple(Pose(_r(x), _r(y)) for x, y in decimate_path(od[:, 1:3]))
    if path_as in ("reference", "both"):
        reference = Reference(file=reference_file or "reference.csv", compare="path")  # a real robot's pace differs
    robot = _robot(data, footprint)
    limits = robot.limits
    timeout = _r(max(30.0, math.ceil(max(duration, length / max(limits.max_speed, 0.1)) * 2.0 + 10.0)), 1)
    scenario = Scenario(
        mission=Mission(start=start_pose, goal=goal_pose, waypoints=waypoints,
                        goal_tolerance=GoalTolerance(position=0.3), timeout=timeout),
        obstacles=tuple(obstacles), robot=robot, reference=reference, name=name,
        description=(f"Seed from {Path(data.path).name}: {data.odom_topic} ({length:.1f} m in {duration:.1f} s)"
                     + (f", obstacles from {data.scan_topic or data.cloud_topic}" if data.scan_topic or data.cloud_topic
                        else ", no obstacles (no scans)")
                     + f"; frame {data.frame or data.odom_frame}."),
    )
    summary = (f"path {length:.1f} m in {duration:.1f} s: "
               + ", ".join(([f"{len(waypoints)} waypoints"] if path_as != "reference" else [])
                           + ([f"reference trajectory of {len(od)} poses"] if path_as != "waypoints" else [])))
    return scenario, summary


def _robot(data: BagData, footprint: Footprint) -> Robot:
    """The robot with its footprint, limits 20 % above the recorded peaks and the bag's laser."""
    speed, yaw_rate = _peak_rates(data.odom)
    # 20 % above the real peak speed, rounded up to 0.05 m/s: headroom for the planner
    limits = Limits(max_speed=_r(max(0.2, math.ceil(speed * 1.2 * 20) / 20), 2),
                    max_yaw_rate=_r(max(30.0, math.ceil(math.degrees(yaw_rate) * 1.2 / 5) * 5), 1))
    lidar = Lidar(beams=min(len(data.scan_angles), 360) if data.scan_topic else 72,
                  range_max=_r(data.range_max if data.scan_topic and math.isfinite(data.range_max) else 8.0, 2),
                  range_min=_r(data.range_min if data.scan_topic else 0.05, 3))
    return Robot(footprint=footprint, drive="diff", limits=limits, lidar=lidar)
