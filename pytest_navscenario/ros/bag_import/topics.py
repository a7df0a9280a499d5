"""Which topic plays which part (by message type, and topic name where types are shared), and the
small values taken from each message: planar transforms, poses, goals, velocity commands,
footprints."""
from __future__ import annotations

import math
import re
from typing import Any

ODOM_TYPES = ("nav_msgs/msg/Odometry",)
SCAN_TYPES = ("sensor_msgs/msg/LaserScan",)
CLOUD_TYPES = ("sensor_msgs/msg/PointCloud2",)
TF_TYPES = ("tf2_msgs/msg/TFMessage",)
POSE_TYPES = ("geometry_msgs/msg/PoseWithCovarianceStamped", "geometry_msgs/msg/PoseStamped")
CMD_TYPES = ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped")
# goals: a PoseStamped on a goal topic (Nav2 / RViz: /goal_pose; ROS 1 RViz: /move_base_simple/goal),
# a ROS 1 move_base action goal, a Nav2 NavigateToPose goal (recorded service request or goal message)
GOAL_TYPE_SUFFIXES = ("MoveBaseActionGoal", "NavigateToPose_SendGoal_Event", "NavigateToPose_SendGoal_Request",
                      "NavigateToPose_Goal", "NavigateToPose_Request")
FOOTPRINT_TYPES = ("geometry_msgs/msg/PolygonStamped",)
PARAM_EVENT_TYPES = ("rcl_interfaces/msg/ParameterEvent",)
STRING_TYPES = ("std_msgs/msg/String",)
RECORDED_SCENARIO = "/navscenario/scenario"   # the scenario a bag of ours ran (ros/bag_writer.py, --nav-bag)
MAP_TYPES = ("nav_msgs/msg/OccupancyGrid",)


def role(topic: str, msgtype: str) -> str | None:
    """The part a topic plays beyond odometry and laser (picked apart): tf, pose, goal, cmd,
    description, footprint, params, map, recorded (the scenario a --nav-bag bag ran); None for a
    topic the importer does not read."""
    name = topic.rstrip("/").lower()
    if msgtype in TF_TYPES and name in ("/tf", "/tf_static"):
        return name[1:]
    if msgtype.endswith(GOAL_TYPE_SUFFIXES):
        return "goal"
    if msgtype == "geometry_msgs/msg/PoseStamped" and ("goal" in name.rsplit("/", 1)[-1] or name.endswith("/goal")):
        return "goal"
    if msgtype in POSE_TYPES:
        return "pose"
    if msgtype in CMD_TYPES and "cmd_vel" in name:
        return "cmd"
    if msgtype in STRING_TYPES and name.endswith("robot_description"):
        return "description"
    if msgtype in STRING_TYPES and name == RECORDED_SCENARIO:
        return "recorded"
    if msgtype in FOOTPRINT_TYPES and "footprint" in name:
        return "footprint"
    if msgtype in PARAM_EVENT_TYPES:
        return "params"
    if msgtype in MAP_TYPES and (name == "/map" or name.endswith("/map")):
        return "map"
    return None


def yaw_of(q: Any) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def planar(tf: Any) -> tuple[str, float, float, float]:
    """(parent frame, x, y, yaw) of a geometry_msgs/TransformStamped."""
    tr, rot = tf.transform.translation, tf.transform.rotation
    return (tf.header.frame_id.lstrip("/"), tr.x, tr.y, yaw_of(rot))


def spatial(tf: Any) -> tuple[str, tuple[float, ...]]:
    """(parent frame, (x, y, z, qx, qy, qz, qw)) of a geometry_msgs/TransformStamped."""
    tr, q = tf.transform.translation, tf.transform.rotation
    return tf.header.frame_id.lstrip("/"), (tr.x, tr.y, tr.z, q.x, q.y, q.z, q.w)


def goal_pose(msg: Any) -> tuple[Any, Any] | None:
    """(header, geometry_msgs/Pose) of a goal message of any supported type, else None. A recorded
    service event (ROS 2 Jazzy records an action's send_goal as one) holds its request in a list."""
    for path in (("goal", "target_pose"), ("goal", "pose"), ("request", "goal", "pose"), ("pose",), ()):
        cur = msg
        for part in path:
            cur = getattr(cur, part, None)
            if isinstance(cur, (list, tuple)):
                cur = cur[0] if len(cur) else None
        if cur is not None and hasattr(cur, "header") and hasattr(getattr(cur, "pose", None), "position"):
            return cur.header, cur.pose
    return None


def pose_of(msg: Any) -> Any:
    """The geometry_msgs/Pose of a PoseStamped or PoseWithCovarianceStamped."""
    pose = msg.pose
    return pose.pose if hasattr(pose, "pose") else pose


def command(msg: Any) -> tuple[float, float]:
    """(forward speed, yaw rate) of a Twist or TwistStamped."""
    tw = getattr(msg, "twist", msg)
    return float(tw.linear.x), float(tw.angular.z)


def footprint_from_params(msg: Any) -> tuple[str, Any] | None:
    """A Nav2 costmap's ``footprint`` (string "[[x, y], ...]") or ``robot_radius`` from a parameter
    event: ("polygon", [(x, y), ...]) or ("radius", r), else None."""
    for p in list(getattr(msg, "new_parameters", [])) + list(getattr(msg, "changed_parameters", [])):
        name = p.name.rsplit(".", 1)[-1]
        if name == "footprint" and p.value.string_value.strip() not in ("", "[]"):
            nums = [float(v) for v in re.findall(r"-?\d+(?:\.\d*)?(?:[eE]-?\d+)?", p.value.string_value)]
            if len(nums) >= 6 and len(nums) % 2 == 0:
                return "polygon", list(zip(nums[0::2], nums[1::2]))
        if name == "robot_radius" and p.value.double_value > 0:
            return "radius", float(p.value.double_value)
    return None
