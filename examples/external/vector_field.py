#!/usr/bin/env python3
"""An external planner for pytest-navscenario, speaking the `navscenario-exec` protocol v1.

A reactive vector-field controller for omnidirectional robots with no dependencies beyond the standard library, to show that the
planner under test can be any program: it reads one JSON object per line on stdin and answers
one per line on stdout. Logs go to stderr.

    pytest scenarios/ --nav-subject="exec:python3 examples/external/vector_field.py"
"""
import json
import math
import sys

INFLUENCE = 1.5     # m: obstacles closer than this push the robot away...
SWIRL = 0.8         # ...and around (always to the same side, which breaks head-on symmetry)
BODY = 0.55         # m: about half the robot's length plus a margin
MAX_SPEED = 0.8     # m/s, capped again by the robot's limits


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def command(obs, limits):
    """Omnidirectional vector field in the robot frame: pulled to the target, pushed away from and
    around every lidar return closer than INFLUENCE, slowed down near obstacles, body turned
    toward the target."""
    x, y, yaw = obs["pose"]
    tx, ty = obs["waypoints"][0] if obs["waypoints"] else obs["goal"][:2]
    dist = math.hypot(tx - x, ty - y)
    heading = wrap(math.atan2(ty - y, tx - x) - yaw)
    fx, fy = math.cos(heading), math.sin(heading)
    nearest = float("inf")
    for r, a in zip(obs["ranges"], obs["angles"]):
        nearest = min(nearest, r)
        if r >= INFLUENCE:
            continue
        w = (1.0 / max(r - BODY, 0.05) - 1.0 / (INFLUENCE - BODY)) * 0.08
        ux, uy = math.cos(a), math.sin(a)
        fx -= w * ux + SWIRL * w * uy     # away from the return, and around it
        fy -= w * uy - SWIRL * w * ux
    norm = math.hypot(fx, fy) or 1.0
    speed = min(MAX_SPEED, limits["max_speed"], 0.6 * dist + 0.1, max(0.1, 0.7 * (nearest - BODY)))
    wz = max(-limits["yaw_rate"], min(limits["yaw_rate"], heading))
    return {"type": "command", "vx": speed * fx / norm, "vy": speed * fy / norm, "wz": wz}


def main():
    limits = {"max_speed": 1.0, "yaw_rate": 1.5}
    for line in sys.stdin:
        msg = json.loads(line)
        if msg["type"] == "reset":
            robot_limits = msg["scenario"].get("robot", {}).get("limits", {})
            limits = {"max_speed": robot_limits.get("max_speed", 1.0),
                      "yaw_rate": math.radians(robot_limits.get("max_yaw_rate", 90.0))}
            print(f"reset: {msg['scenario'].get('name', '?')}", file=sys.stderr)
            reply = {"type": "ready", "name": "vector-field (external)", "version": "1.0"}
        elif msg["type"] == "observation":
            reply = command(msg, limits)
        elif msg["type"] == "shutdown":
            return 0
        else:
            reply = {"type": "error", "message": f"unknown message type {msg['type']!r}"}
        sys.stdout.write(json.dumps(reply) + "\n")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
