"""The ``navscenario from-bag`` command line: its arguments and what it writes."""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from ..robot_options import RobotOptionError, add_robot_arguments, parse_footprint, read_robot
from .clouds import CloudSettings
from .frames import FRAMES
from .reading import PATH_AS, BagImportError
from .scans import STAMPS
from .robot import RobotChoice
from .seed import scenario_from_bag


def _triple(text: str) -> tuple[float, float, float]:
    try:
        parts = [float(v) for v in text.split(",")]
    except ValueError:
        parts = []
    if len(parts) != 3 or not all(math.isfinite(v) for v in parts):
        raise argparse.ArgumentTypeError(f"expected x,y,yaw (metres, metres, degrees), got {text!r}")
    return parts[0], parts[1], parts[2]


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("bag", metavar="PATH", help="ROS 1 .bag file, rosbag2 folder, or .mcap/.db3 file")
    p.add_argument("-o", "--output", default=None, metavar="OUT.yaml",
                   help="seed scenario YAML to write (an existing file is kept unless --force); required unless "
                        "--list-events")
    p.add_argument("--start", type=float, default=None, metavar="SECONDS", help="window start, seconds after the first odometry message")
    p.add_argument("--end", type=float, default=None, metavar="SECONDS", help="window end, seconds after the first odometry message")
    p.add_argument("--at", type=float, default=None, metavar="SECONDS",
                   help="cut the seed from the --window seconds before this moment (seconds after the first "
                        "odometry message; --list-events shows candidates); instead of --start/--end")
    p.add_argument("--window", type=float, default=30.0, metavar="SECONDS",
                   help="with --at: how many seconds before that moment the seed covers (default 30)")
    p.add_argument("--list-events", action="store_true",
                   help="list candidate moments with their times (stopped far from the goal, reversed, turned in "
                        "place long, command dropped to zero during a goal, nearest return inside the footprint "
                        "margin) and write nothing")
    p.add_argument("--margin", type=float, default=0.05, metavar="METRES",
                   help="with --list-events: a return closer than the footprint plus this is an event (default 0.05 m)")
    p.add_argument("--odom-topic", default=None, metavar="TOPIC", help="nav_msgs/Odometry topic (default: found by type)")
    p.add_argument("--scan-topic", default=None, metavar="TOPIC", help="sensor_msgs/LaserScan topic (default: found by type)")
    p.add_argument("--cloud-topic", default=None, metavar="TOPIC",
                   help="sensor_msgs/PointCloud2 topic of a 3D lidar (default: found by type when the bag has no "
                        "laser scan; giving it reads the cloud instead of the scan)")
    p.add_argument("--robot-height", type=float, default=1.0, metavar="METRES",
                   help="point clouds: points higher than this above the ground cannot be hit (default 1.0 m)")
    p.add_argument("--ground-clearance", type=float, default=0.05, metavar="METRES",
                   help="point clouds: points lower than this above the ground are the ground (default 0.05 m)")
    p.add_argument("--laser-pose", type=_triple, default=None, metavar="X,Y,YAW",
                   help="laser (or 3D lidar) pose in the odometry child frame (m, m, degrees; e.g. --laser-pose "
                        "-0.064,0,0); default /tf_static, else the first /tf transforms, else guessed "
                        "from the scans among the common mountings (turned 0, 90, 180, -90 degrees)")
    p.add_argument("--scan-stamp", choices=STAMPS, default="auto",
                   help="what a scan's header stamp is: the scan's start (the ROS convention: its first beam), its "
                        "end (drivers that stamp a scan when it is complete), or auto (default: told from how long "
                        "after its stamp the bag received each scan; the output says which was used)")
    p.add_argument("--scan-time-offset", type=float, default=0.0, metavar="SECONDS",
                   help="add this to every scan's stamp, for a driver that stamps its scans late or early against "
                        "the odometry (default 0)")
    p.add_argument("--frame", choices=FRAMES, default="auto",
                   help="the seed's world frame: auto (default: the map frame when the bag has map -> odom on /tf "
                        "or a pose topic in the map frame, else the odometry frame), map (an error without one), odom")
    p.add_argument("--map-frame", default="map", metavar="FRAME", help="name of the map frame (default map)")
    p.add_argument("--pose-topic", default=None, metavar="TOPIC",
                   help="localisation pose topic (PoseWithCovarianceStamped or PoseStamped in the map frame) to use "
                        "instead of map -> odom on /tf (default: /tf, else /amcl_pose, /pose, /tracked_pose)")
    p.add_argument("--goal-topic", default=None, metavar="TOPIC",
                   help="the navigation goal's topic (default: found by type: /goal_pose, NavigateToPose and move_base "
                        "goals); without a goal the seed's goal is the window's last pose")
    p.add_argument("--path-as", choices=PATH_AS, default="waypoints",
                   help="driven path as decimated waypoints (default), a reference trajectory (CSV t,x,y beside "
                        "the seed, for the reference deviation metrics) or both")
    p.add_argument("--robot-radius", type=float, default=None, metavar="METRES",
                   help="the seed robot's circular footprint radius, m (default: the base link's collision geometry "
                        "in the URDF on /robot_description, else a Nav2 footprint in the bag, else 0.15)")
    add_robot_arguments(p, timeout=False, default_robot=(
        "the robot of the scenario a bag of ours ran (/navscenario/scenario, --nav-bag), else a guess from the "
        "bag: its URDF's or Nav2 footprint (or --robot-radius), a differential drive, limits 20 %% above the "
        "recorded peaks"))
    p.add_argument("--name", default="", metavar="TEXT", help="scenario name (default: the output file's stem)")
    p.add_argument("--force", action="store_true", help="overwrite an existing output file")


def _cloud_settings(args: argparse.Namespace) -> CloudSettings:
    for name, value in (("--robot-height", args.robot_height), ("--ground-clearance", args.ground_clearance)):
        if not (math.isfinite(value) and 0 <= value <= 10):
            raise BagImportError(f"{name} must be a height in [0, 10] m, got {value}")
    if args.ground_clearance >= args.robot_height:
        raise BagImportError(f"--ground-clearance ({args.ground_clearance} m) must be below --robot-height "
                             f"({args.robot_height} m)")
    return CloudSettings(robot_height=args.robot_height, clearance=args.ground_clearance)


def run(args: argparse.Namespace) -> int:
    if args.list_events:
        return _list_events(args)
    import_bag(args)
    return 0


def import_bag(args: argparse.Namespace):
    """Build the seed, write it (and its reference CSV) and print the notes; return the BagSeed
    and the seed file's path (the command line's own layer draws the picture)."""
    from ..world_import import write_seed
    if not args.output:
        raise BagImportError("-o/--output is required: the seed scenario YAML to write (or --list-events)")
    out = Path(args.output)
    csv_name = f"{out.stem}.reference.csv"
    seed = scenario_from_bag(args.bag, odom_topic=args.odom_topic, scan_topic=args.scan_topic,
                             start=args.start, end=args.end, laser_pose=args.laser_pose,
                             path_as=args.path_as, reference_file=csv_name, name=args.name,
                             robot_radius=args.robot_radius, frame=args.frame, map_frame=args.map_frame,
                             pose_topic=args.pose_topic, cloud_topic=args.cloud_topic,
                             cloud=_cloud_settings(args), goal_topic=args.goal_topic, at=args.at,
                             window=args.window, scan_stamp=args.scan_stamp, scan_offset=args.scan_time_offset,
                             robot=_robot_choice(args))
    extra = {}
    if args.path_as != "waypoints":
        extra[csv_name] = reference_csv(seed.path)
    if seed.fit is not None:
        extra[f"{out.stem}.fit.json"] = seed.fit.to_json()
    extra.update(seed.files)          # the ground a 3D lidar saw, as a heightfield (ground.py)
    write_seed(seed.scenario, out, extra_files=extra, force=args.force)
    for note in seed.notes:
        print(f"navscenario from-bag: {note}")
    print(f"navscenario from-bag: wrote {out}" + "".join(f" and {out.parent / name}" for name in extra))
    for line in seed.fit.lines() if seed.fit is not None else ["no fit figure: the bag has no 2D laser scans to "
                                                               "compare the seed with"]:
        print(f"navscenario from-bag: {line}")
    return seed, out


def _robot_choice(args: argparse.Namespace) -> RobotChoice:
    """--robot (read and checked), --footprint, --drive; --robot-radius is --footprint circle:R."""
    footprint = getattr(args, "footprint", None)
    if footprint and args.robot_radius is not None:
        raise BagImportError(f"--footprint {footprint} and --robot-radius {args.robot_radius}: give one (--robot-radius R "
                             f"is --footprint circle:R)")
    try:
        return RobotChoice(robot=read_robot(Path(args.robot)) if getattr(args, "robot", None) else None,
                           robot_file=getattr(args, "robot", None) or "",
                           footprint=parse_footprint(footprint) if footprint else None,
                           footprint_text=footprint or "", drive=getattr(args, "drive", None))
    except RobotOptionError as exc:
        raise BagImportError(str(exc)) from None


def _list_events(args: argparse.Namespace) -> int:
    from .events import bag_events, format_events
    events, notes = bag_events(args.bag, odom_topic=args.odom_topic, scan_topic=args.scan_topic,
                               cloud_topic=args.cloud_topic, frame=args.frame, map_frame=args.map_frame,
                               pose_topic=args.pose_topic, laser_pose=args.laser_pose,
                               robot_radius=args.robot_radius, margin=args.margin)
    for note in notes:
        print(f"navscenario from-bag: {note}")
    print(f"navscenario from-bag: {len(events)} candidate moment(s) in {args.bag}:")
    for line in format_events(events):
        print(f"  {line}")
    if events:
        print(f"navscenario from-bag: cut a seed before one with --at T (and --window S, default {args.window:g} s)")
    return 0


def reference_csv(rows: np.ndarray) -> str:
    """The reference trajectory file: a ``t,x,y`` header and one row per odometry message."""
    lines = ["t,x,y"] + [f"{t:.3f},{x:.4f},{y:.4f}" for t, x, y in rows]
    return "\n".join(lines) + "\n"
