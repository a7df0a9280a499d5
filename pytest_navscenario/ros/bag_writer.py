"""Write one episode as a ROS bag that opens in Foxglove or RViz with no extra work.

``write_episode_bag(result, path, fmt="mcap")`` writes a rosbag2 folder with MCAP storage
(``fmt="sqlite3"`` for rosbag2 sqlite3, ``fmt="ros1"`` for a ROS 1 ``.bag`` file), using only
standard message types:

===============================  ==================================  =====================
topic                            type                                rate
===============================  ==================================  =====================
/odom                            nav_msgs/Odometry                   physics rate, <= 50 Hz
/tf                              tf2_msgs/TFMessage (odom->base_link) with /odom
/tf_static                       tf2_msgs/TFMessage (base_link->laser once, latched
                                 and ->lidar3d)
/scan                            sensor_msgs/LaserScan (frame laser) control ticks
/points                          sensor_msgs/PointCloud2 (frame      control ticks, only with
                                 lidar3d: x, y, z, ring)             robot.lidar3d
/cmd_vel                         geometry_msgs/Twist (commanded)     control ticks
/goal_pose                       geometry_msgs/PoseStamped           once, latched
/navscenario/waypoints           nav_msgs/Path                       once, latched
/navscenario/obstacles           visualization_msgs/MarkerArray      once, latched (static ones)
/navscenario/moving_obstacles    visualization_msgs/MarkerArray      with /odom, only when
                                 (moving obstacles where they are)   obstacles move
/navscenario/terrain             visualization_msgs/MarkerArray      once, latched, only with
                                 (the ground's surface, one          terrain
                                 TRIANGLE_LIST per element)
/navscenario/result              std_msgs/String (JSON)              once, at the end
/navscenario/scenario            std_msgs/String (scenario YAML)     once, latched
===============================  ==================================  =====================

The bag clock is the simulation clock (t = 0 at the episode's start); the scenario's world
frame is the ``odom`` frame. On a body that rides the ground the base's pose is full 3D (its
height, roll and pitch on /odom and /tf); the 2D lidar's frame ``laser`` sits ``mount_height``
above the base and the 3D lidar's frame ``lidar3d`` at its mount, pitched as mounted. The bag is written to a temporary name and renamed into place,
so a crash never leaves a partial bag behind.
"""
from __future__ import annotations

import functools
import json
import math
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from ..core.errors import NavScenarioError
from ..verdict.result import EpisodeResult
from ..core.files import json_safe
from ..scenario.model import BoxObstacle, CylinderObstacle, MeshObstacle, PolygonObstacle

FORMATS = ("mcap", "sqlite3", "ros1")
ODOM_FRAME, BASE_FRAME, LASER_FRAME, CLOUD_FRAME = "odom", "base_link", "laser", "lidar3d"
ODOM_MAX_RATE = 50.0  # Hz: physics runs at 100 Hz+, a viewer needs no more than this

TOPICS: dict[str, str] = {
    "/odom": "nav_msgs/msg/Odometry",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/scan": "sensor_msgs/msg/LaserScan",
    "/cmd_vel": "geometry_msgs/msg/Twist",
    "/goal_pose": "geometry_msgs/msg/PoseStamped",
    "/navscenario/waypoints": "nav_msgs/msg/Path",
    "/navscenario/obstacles": "visualization_msgs/msg/MarkerArray",
    "/navscenario/result": "std_msgs/msg/String",
    "/navscenario/scenario": "std_msgs/msg/String",
}
MOVING_TOPIC = "/navscenario/moving_obstacles"     # only in bags of episodes with moving obstacles
CLOUD_TOPIC = "/points"                            # only in bags of episodes with a 3D lidar
TERRAIN_TOPIC = "/navscenario/terrain"             # only in bags of scenarios with terrain
TERRAIN_CELLS = 60                                 # ground samples along an element's longer side
LATCHED = ("/tf_static", "/goal_pose", "/navscenario/waypoints", "/navscenario/obstacles",
           "/navscenario/result", "/navscenario/scenario")
LATCHED_WHEN_THERE = (TERRAIN_TOPIC,)              # latched too, in the bags that have them


class BagWriteError(NavScenarioError):
    """A bag cannot be written (bad format name, unwritable folder)."""


# ---------------------------------------------------------------- message building

_PRIMITIVE_DTYPES = {
    "bool": np.bool_, "byte": np.uint8, "char": np.uint8, "int8": np.int8, "uint8": np.uint8,
    "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32,
    "int64": np.int64, "uint64": np.uint64, "float32": np.float32, "float64": np.float64,
}


_PLANS: dict[tuple[int, str], tuple[frozenset, list]] = {}
_DEFAULTS: dict[tuple[int, str], Any] = {}


def _plan(ts: Any, msgtype: str) -> tuple[frozenset, list]:
    """Per message type, once: (field names, [(name, nodetype, spec), ...])."""
    key = (id(ts), msgtype)
    plan = _PLANS.get(key)
    if plan is None:
        _, fields = ts.fielddefs[msgtype]
        plan = (frozenset(n for n, _ in fields), [(n, int(nt), spec) for n, (nt, spec) in fields])
        _PLANS[key] = plan
    return plan


def build(typestore: Any, msgtype: str, values: dict[str, Any] | None = None) -> Any:
    """A message of ``msgtype`` from a (nested) dict; fields not given get their zero value.

    Works for both the ROS 1 and the ROS 2 typestore, whose definitions differ (Header.seq,
    Marker texture fields), so callers describe messages once. Zero-valued sub-messages are
    shared between messages (they are only serialised, never changed).
    """
    if not values:
        key = (id(typestore), msgtype)
        msg = _DEFAULTS.get(key)
        if msg is None:
            msg = _DEFAULTS[key] = _build(typestore, msgtype, {})
        return msg
    return _build(typestore, msgtype, values)


def _build(ts: Any, msgtype: str, values: dict[str, Any]) -> Any:
    names, fields = _plan(ts, msgtype)
    if not names.issuperset(values):
        raise KeyError(f"{msgtype} has no field(s) {sorted(set(values) - names)}")
    kwargs = {}
    for name, nodetype, spec in fields:
        kwargs[name] = _field_value(ts, nodetype, spec, values.get(name))
    return ts.types[msgtype](**kwargs)


def _field_value(ts: Any, nodetype: int, spec: Any, given: Any) -> Any:
    if nodetype == 1:  # BASE
        if given is not None:
            return given
        base = spec[0]
        return "" if base == "string" else (False if base == "bool" else
                                           (0.0 if base.startswith("float") else 0))
    if nodetype == 2:  # NAME (nested message)
        return given if given is not None and not isinstance(given, dict) else build(ts, spec, given)
    # ARRAY (3) or SEQUENCE (4)
    (inner_type, inner_spec), length = spec
    if int(inner_type) == 1 and inner_spec[0] in _PRIMITIVE_DTYPES:
        dtype = _PRIMITIVE_DTYPES[inner_spec[0]]
        if given is None:
            return np.zeros(length if nodetype == 3 else 0, dtype=dtype)
        return np.asarray(given, dtype=dtype)
    if given is None:
        if nodetype == 3:
            return [_field_value(ts, int(inner_type), inner_spec, None) for _ in range(length)]
        return []
    return [_field_value(ts, int(inner_type), inner_spec, g) for g in given]


def _stamp(t: float) -> dict[str, int]:
    ns = int(round(t * 1e9))
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def _quat(yaw: float) -> dict[str, float]:
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2.0), "w": math.cos(yaw / 2.0)}


def _quat_rpy(roll: float, pitch: float, yaw: float) -> dict[str, float]:
    """The quaternion of Z-Y-X angles (yaw, then pitch, then roll), ROS's order of fields."""
    cr, sr = math.cos(roll / 2.0), math.sin(roll / 2.0)
    cp, sp = math.cos(pitch / 2.0), math.sin(pitch / 2.0)
    cy, sy = math.cos(yaw / 2.0), math.sin(yaw / 2.0)
    return {"x": sr * cp * cy - cr * sp * sy, "y": cr * sp * cy + sr * cp * sy,
            "z": cr * cp * sy - sr * sp * cy, "w": cr * cp * cy + sr * sp * sy}


def _pose(x: float, y: float, yaw: float, z: float = 0.0) -> dict[str, Any]:
    return {"position": {"x": float(x), "y": float(y), "z": float(z)}, "orientation": _quat(yaw)}


def result_summary(result: EpisodeResult) -> dict[str, Any]:
    """The JSON written on /navscenario/result: outcome, message, metrics and the scenario."""
    s = result.scenario
    out: dict[str, Any] = {
        "scenario": s.name, "family": s.family, "subject": result.subject,
        "subject_version": result.subject_version, "seed": result.seed,
        "outcome": result.outcome.value, "passed": result.passed, "message": result.message,
        "metrics": result.metrics.as_dict(),
    }
    for key in ("collision", "safety_stop", "subject_failure"):
        event = getattr(result, key)
        if event is not None:
            out[key] = dict(vars(event))
    return json_safe(out)


def _messages(result: EpisodeResult, ros1: bool):
    """Yield (topic, time_s, message-dict) in time order per topic."""
    scenario, traj = result.scenario, result.trajectory
    t, pose, vel = np.asarray(traj.t), np.asarray(traj.pose), np.asarray(traj.velocity)

    def header(time_s: float, frame: str) -> dict[str, Any]:
        return {"stamp": _stamp(time_s), "frame_id": frame}

    mounts = [{"header": header(0.0, BASE_FRAME), "child_frame_id": LASER_FRAME,
               "transform": {"translation": {"x": 0.0, "y": 0.0, "z": float(scenario.robot.lidar.mount_height)},
                             "rotation": _quat(0.0)}}]
    spec3d = scenario.robot.lidar3d
    if spec3d is not None:
        mounts.append({"header": header(0.0, BASE_FRAME), "child_frame_id": CLOUD_FRAME,
                       "transform": {"translation": {"x": float(spec3d.mount_x), "y": float(spec3d.mount_y),
                                                     "z": float(spec3d.mount_z)},
                                     "rotation": _quat_rpy(0.0, math.radians(spec3d.mount_pitch), 0.0)}})
    yield "/tf_static", 0.0, {"transforms": mounts}
    goal = scenario.mission.goal
    yield "/goal_pose", 0.0, {"header": header(0.0, ODOM_FRAME),
                              "pose": _pose(goal.x, goal.y, goal.yaw_rad)}
    points = [scenario.mission.start, *scenario.mission.waypoints, goal]
    yield "/navscenario/waypoints", 0.0, {"header": header(0.0, ODOM_FRAME), "poses": [
        {"header": header(0.0, ODOM_FRAME), "pose": _pose(p.x, p.y, p.yaw_rad)} for p in points]}
    yield "/navscenario/obstacles", 0.0, {"markers": _markers(result)}
    if scenario.terrain:
        yield TERRAIN_TOPIC, 0.0, {"markers": terrain_markers(scenario)}
    from ..scenario.dump import dump_scenario
    yield "/navscenario/scenario", 0.0, {"data": dump_scenario(scenario)}  # the bag reproduces the run

    if len(t) > 1:
        dt = float(np.median(np.diff(t)))
        stride = max(1, int(round(1.0 / (ODOM_MAX_RATE * dt)))) if dt > 0 else 1
    else:
        stride = 1
    idx = list(range(0, len(t), stride))
    if idx and idx[-1] != len(t) - 1:
        idx.append(len(t) - 1)  # the final pose always makes it into the bag
    yield from _moving_markers(result, t[idx])
    # the full 3D pose of a body that rides the ground (None: the planar body, on the floor, level)
    zs, rolls, pitches = (getattr(traj, name, None) for name in ("z", "roll", "pitch"))
    for i in idx:
        x, y, yaw = (float(v) for v in pose[i])
        ti = float(t[i])
        z = float(zs[i]) if zs is not None else 0.0
        rot = (_quat_rpy(float(rolls[i]), float(pitches[i]), yaw) if rolls is not None and pitches is not None
               else _quat(yaw))
        yield "/odom", ti, {
            "header": header(ti, ODOM_FRAME), "child_frame_id": BASE_FRAME,
            "pose": {"pose": {"position": {"x": x, "y": y, "z": z}, "orientation": rot}},
            "twist": {"twist": {"linear": {"x": float(vel[i, 0]), "y": float(vel[i, 1])},
                                "angular": {"z": float(vel[i, 2])}}}}
        yield "/tf", ti, {"transforms": [{
            "header": header(ti, ODOM_FRAME), "child_frame_id": BASE_FRAME,
            "transform": {"translation": {"x": x, "y": y, "z": z}, "rotation": rot}}]}
    yield from _clouds(result, header)

    lidar = scenario.robot.lidar
    angles = np.asarray(traj.angles, dtype=float)
    ranges = np.asarray(traj.ranges, dtype=np.float32)
    if len(angles):
        increment = float(angles[1] - angles[0]) if len(angles) > 1 else 0.0
        for k, tk in enumerate(np.asarray(traj.tick_t, dtype=float)):
            if k >= len(ranges):
                break
            yield "/scan", float(tk), {
                "header": header(float(tk), LASER_FRAME),
                "angle_min": float(angles[0]), "angle_max": float(angles[-1]),
                "angle_increment": increment,
                "scan_time": 1.0 / scenario.simulation.control_rate,
                "range_min": float(lidar.range_min), "range_max": float(lidar.range_max),
                "ranges": ranges[k]}
    for k, tk in enumerate(np.asarray(traj.tick_t, dtype=float)):
        if k >= len(traj.command):
            break
        vx, vy, wz = (float(v) for v in traj.command[k])
        yield "/cmd_vel", float(tk), {"linear": {"x": vx, "y": vy}, "angular": {"z": wz}}

    yield "/navscenario/result", traj.duration, {
        "data": json.dumps(result_summary(result), sort_keys=True, allow_nan=False)}


def _clouds(result: EpisodeResult, header: Any):
    """The 3D lidar's scans as PointCloud2 in its own frame: the returns' x, y, z (float32) and ring
    (uint16), one message a control tick."""
    spec, cloud = result.scenario.robot.lidar3d, result.trajectory.cloud
    if spec is None or cloud is None:
        return
    from ..sim.lidar3d import sensor_directions   # plain numpy: the beam table

    dirs = sensor_directions(spec).reshape(int(spec.rings), int(spec.beams), 3)
    ring = np.broadcast_to(np.arange(int(spec.rings), dtype=np.uint16)[:, None], dirs.shape[:2])
    record = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("ring", "<u2"), ("pad", "<u2")])
    fields = [{"name": n, "offset": o, "datatype": d, "count": 1}
              for n, o, d in (("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("ring", 12, 4))]
    for k, tk in enumerate(np.asarray(result.trajectory.tick_t, dtype=float)):
        if k >= len(cloud):
            break
        ranges = cloud[k]
        seen = ranges < np.float32(spec.range_max)
        pts = np.zeros(int(seen.sum()), dtype=record)
        xyz = dirs[seen] * ranges[seen, None]
        pts["x"], pts["y"], pts["z"], pts["ring"] = xyz[:, 0], xyz[:, 1], xyz[:, 2], ring[seen]
        yield CLOUD_TOPIC, float(tk), {
            "header": header(float(tk), CLOUD_FRAME), "height": 1, "width": len(pts), "fields": fields,
            "is_bigendian": False, "point_step": record.itemsize, "row_step": record.itemsize * len(pts),
            "data": np.frombuffer(pts.tobytes(), dtype=np.uint8), "is_dense": True}


def terrain_markers(scenario: Any) -> list[dict[str, Any]]:
    """The ground's surface over each terrain element (and a margin of floor around it) as a
    TRIANGLE_LIST marker: its height sampled on a grid of at most TERRAIN_CELLS a side (two
    triangles a cell, so a step's riser is a steep band one cell wide), coloured by height per
    vertex: blue below the floor, green to brown above."""
    from ..scenario.ground import surface as ground

    out = []
    for i, el in enumerate(scenario.terrain):
        corners = ground.outline(el)
        (x0, y0), (x1, y1) = corners.min(axis=0) - 0.2, corners.max(axis=0) + 0.2
        step = max(x1 - x0, y1 - y0) / TERRAIN_CELLS
        xs = np.linspace(x0, x1, max(2, int(round((x1 - x0) / step)) + 1))
        ys = np.linspace(y0, y1, max(2, int(round((y1 - y0) / step)) + 1))
        gx, gy = np.meshgrid(xs, ys)
        gz = ground.ground_height(scenario, gx, gy)
        verts = np.stack([gx, gy, gz], axis=-1)
        a, b, c, d = verts[:-1, :-1], verts[:-1, 1:], verts[1:, 1:], verts[1:, :-1]
        tris = np.stack([a, b, c, a, c, d], axis=2).reshape(-1, 3)
        z = tris[:, 2]
        span = max(float(np.abs(gz).max()), 0.05)
        up, down = np.clip(z / span, 0.0, 1.0), np.clip(-z / span, 0.0, 1.0)
        colours = [{"r": float(0.75 - 0.35 * u - 0.55 * w), "g": float(0.8 - 0.45 * u - 0.35 * w),
                    "b": float(0.7 - 0.45 * u + 0.25 * w), "a": 1.0} for u, w in zip(up.tolist(), down.tolist())]
        out.append({"header": {"frame_id": ODOM_FRAME}, "ns": "terrain", "id": i, "type": 11, "action": 0,
                    "pose": _pose(0.0, 0.0, 0.0), "scale": {"x": 1.0, "y": 1.0, "z": 1.0},
                    "color": {"r": 0.6, "g": 0.55, "b": 0.45, "a": 1.0}, "text": ground.describe_element(el),
                    "points": [{"x": float(p[0]), "y": float(p[1]), "z": float(p[2])} for p in tris.tolist()],
                    "colors": colours})
    return out


_COLOURS = {"box": (0.55, 0.55, 0.6), "cylinder": (0.45, 0.5, 0.65), "polygon": (0.5, 0.55, 0.55),
            "mesh": (0.6, 0.5, 0.45), "moving_obstacles": (0.95, 0.55, 0.15)}


def _markers(result: EpisodeResult) -> list[dict[str, Any]]:
    hit = {result.collision.obstacle} if result.collision else set()
    if result.safety_stop:
        hit.add(result.safety_stop.obstacle)
    return [_marker(obs, i, obs.name in hit, "obstacles", obs.x, obs.y)
            for i, obs in enumerate(result.scenario.obstacles) if getattr(obs, "motion", None) is None]


def _marker(obs: Any, i: int, hit: bool, ns: str, x: float, y: float, stamp: float | None = None
            ) -> dict[str, Any]:
    """A CUBE or CYLINDER marker of the obstacle with its centre at (x, y); red if it was hit."""
    r, g, b = (0.9, 0.2, 0.15) if hit else _COLOURS[ns if ns in _COLOURS else obs.kind]
    header: dict[str, Any] = {"frame_id": ODOM_FRAME}
    if stamp is not None:
        header["stamp"] = _stamp(stamp)
    common = {"header": header, "ns": ns, "id": i,
              "action": 0, "color": {"r": r, "g": g, "b": b, "a": 0.8}, "text": obs.name}
    if isinstance(obs, BoxObstacle):
        return {**common, "type": 1, "pose": _pose(x, y, obs.yaw_rad, obs.height / 2),
                "scale": {"x": obs.length, "y": obs.width, "z": obs.height}}
    if isinstance(obs, (PolygonObstacle, MeshObstacle)):     # TRIANGLE_LIST: the prism's faces
        return {**common, "type": 11, "pose": _pose(x, y, obs.yaw_rad, 0.0),
                "scale": {"x": 1.0, "y": 1.0, "z": 1.0}, "points": _prism_triangles(obs)}
    return {**common, "type": 3, "pose": _pose(x, y, 0.0, obs.height / 2),
            "scale": {"x": 2 * obs.radius, "y": 2 * obs.radius, "z": obs.height}}


def _prism_triangles(obs: Any) -> list[dict[str, float]]:
    """The triangles (as a flat list of points, three each) of a polygon or mesh obstacle's prism in
    its own frame: its convex parts' top and bottom fans and the outline's walls."""
    from ..scenario.geometry import convex_parts_local, outline_points

    h = float(obs.height)
    pts: list[dict[str, float]] = []

    def p(x: float, y: float, z: float) -> dict[str, float]:
        return {"x": float(x), "y": float(y), "z": z}

    for part in convex_parts_local(tuple(outline_points(obs))):
        for k in range(1, len(part) - 1):
            for z in (0.0, h):
                pts += [p(*part[0], z), p(*part[k], z), p(*part[k + 1], z)]
    ring = list(outline_points(obs))
    for (ax, ay), (bx, by) in zip(ring, ring[1:] + ring[:1]):
        pts += [p(ax, ay, 0.0), p(bx, by, 0.0), p(bx, by, h), p(ax, ay, 0.0), p(bx, by, h), p(ax, ay, h)]
    return pts


def _moving_markers(result: EpisodeResult, times: np.ndarray):
    """The moving obstacles where they are, at the /odom instants (one MarkerArray each; the
    same id per obstacle, so a viewer moves it instead of adding one)."""
    from ..scenario.motion import tracks

    moving = tracks(result.scenario.obstacles)
    if not moving:
        return
    hit_at = result.collision.time if result.collision else math.inf
    hit_name = result.collision.obstacle if result.collision else ""
    where = {j: track.positions(times) for j, track in moving.items()}
    for k, tk in enumerate(times.tolist()):
        yield MOVING_TOPIC, tk, {"markers": [
            _marker(result.scenario.obstacles[j], j, hit_name == result.scenario.obstacles[j].name
                    and tk >= hit_at - 1e-9, "moving_obstacles", float(xy[k, 0]), float(xy[k, 1]), tk)
            for j, xy in where.items()]}


# ---------------------------------------------------------------- writing

@functools.lru_cache(maxsize=2)
def _typestore(ros1: bool):
    """The message definitions (cached: rosbags compiles its serialisers per typestore)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    if not ros1:
        return get_typestore(Stores.ROS2_HUMBLE)
    ts = get_typestore(Stores.ROS1_NOETIC)
    if "tf2_msgs/msg/TFMessage" not in ts.types:  # not in rosbags' noetic store
        ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms",
                                       "tf2_msgs/msg/TFMessage"))
    return ts


def _latched_qos():
    from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime
    never = QosTime(sec=0, nsec=0)
    return [Qos(history=QosHistory.KEEP_LAST, depth=1, reliability=QosReliability.RELIABLE,
                durability=QosDurability.TRANSIENT_LOCAL, deadline=never, lifespan=never,
                liveliness=QosLiveliness.AUTOMATIC, liveliness_lease_duration=never,
                avoid_ros_namespace_conventions=False)]


def _write(result: EpisodeResult, path: Path, fmt: str) -> None:
    ros1 = fmt == "ros1"
    ts = _typestore(ros1)
    msgs = sorted(_messages(result, ros1), key=lambda m: m[1])  # stable: per-topic order kept
    if ros1:
        from rosbags.rosbag1 import Writer as Ros1Writer
        writer = Ros1Writer(path)
        serialize = ts.serialize_ros1
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer
        plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
        writer = Writer(path, version=9, storage_plugin=plugin)
        serialize = ts.serialize_cdr
    with writer:
        conns = {}
        topics = dict(TOPICS)
        if any(getattr(o, "motion", None) is not None for o in result.scenario.obstacles):
            topics[MOVING_TOPIC] = TOPICS["/navscenario/obstacles"]
        if result.scenario.robot.lidar3d is not None and result.trajectory.cloud is not None:
            topics[CLOUD_TOPIC] = "sensor_msgs/msg/PointCloud2"
        if result.scenario.terrain:
            topics[TERRAIN_TOPIC] = TOPICS["/navscenario/obstacles"]
        for topic, msgtype in topics.items():
            if ros1:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=ts,
                                                     latching=1 if topic in LATCHED + LATCHED_WHEN_THERE else None)
            else:
                qos = _latched_qos() if topic in LATCHED + LATCHED_WHEN_THERE else ()
                conns[topic] = writer.add_connection(topic, msgtype, typestore=ts,
                                                     offered_qos_profiles=qos)
        for topic, time_s, values in msgs:
            msgtype = topics[topic]
            data = serialize(build(ts, msgtype, values), msgtype)
            writer.write(conns[topic], int(round(time_s * 1e9)), data)


def default_bag_path(folder: str | os.PathLike, stem: str, fmt: str = "mcap") -> Path:
    """Where a bag named ``stem`` goes in ``folder``: a rosbag2 folder, or ``stem.bag`` for ROS 1."""
    return Path(folder) / (f"{stem}.bag" if fmt == "ros1" else stem)


def write_episode_bag(result: EpisodeResult, path: str | os.PathLike, *, fmt: str = "mcap") -> Path:
    """Write ``result`` as a bag at ``path`` and return the path written.

    ``fmt``: ``"mcap"`` (rosbag2 folder with one .mcap file, the default), ``"sqlite3"``
    (rosbag2 folder with a .db3 file) or ``"ros1"`` (one ROS 1 .bag file; ``.bag`` is appended
    to a path without it, as readers recognise ROS 1 bags by it). An existing bag at the path is
    replaced; the new one appears whole or not at all.
    """
    if fmt not in FORMATS:
        raise BagWriteError(f"unknown bag format {fmt!r} (choose one of {', '.join(FORMATS)})")
    path = Path(path)
    if fmt == "ros1" and path.suffix != ".bag":
        path = path.with_name(path.name + ".bag")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent))
    except OSError as exc:
        raise BagWriteError(f"{path}: cannot create the bag's folder: {exc}") from None
    try:
        tmp = staging / path.name
        _write(result, tmp, fmt)
        if path.exists() or path.is_symlink():
            trash = staging / ".old"
            os.replace(path, trash)
        os.replace(tmp, path)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return path
