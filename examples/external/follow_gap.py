#!/usr/bin/env python3
"""An external planner for pytest-navscenario, speaking the `navscenario-exec` protocol v1.

A follow-the-gap controller with no dependencies beyond the standard library, to show that the
planner under test can be any program: it reads one JSON object per line on stdin and answers
one per line on stdout. Logs go to stderr.

    pytest scenarios/ --nav-subject="exec:python3 examples/external/follow_gap.py"
"""
import json
import math
import sys

SAFE = 1.0          # m: beams shorter than this are blocked
MAX_SPEED = 0.8     # m/s, capped again by the robot's limits


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def command(obs, limits):
    x, y, yaw = obs["pose"]
    tx, ty = obs["waypoints"][0] if obs["waypoints"] else obs["goal"][:2]
    dist = math.hypot(tx - x, ty - y)
    heading = wrap(math.atan2(ty - y, tx - x) - yaw)
    ranges, angles = obs["ranges"], obs["angles"]
    # the free beam closest to the goal direction (beams near obstacles are blocked)
    best, best_cost = heading, float("inf")
    for r, a in zip(ranges, angles):
        if r < min(SAFE, dist):
            continue
        cost = abs(wrap(a - heading))
        if cost < best_cost:
            best, best_cost = a, cost
    front = min((r for r, a in zip(ranges, angles) if abs(a) < 0.5), default=float("inf"))
    speed = min(MAX_SPEED, limits["max_speed"], 0.6 * dist, max(0.0, front - 0.6))
    speed *= max(0.0, math.cos(best))
    wz = max(-limits["yaw_rate"], min(limits["yaw_rate"], 1.5 * best))
    return {"type": "command", "vx": speed, "vy": 0.0, "wz": wz}


def main():
    limits = {"max_speed": 1.0, "yaw_rate": 1.5}
    for line in sys.stdin:
        msg = json.loads(line)
        if msg["type"] == "reset":
            robot_limits = msg["scenario"].get("robot", {}).get("limits", {})
            limits = {"max_speed": robot_limits.get("max_speed", 1.0),
                      "yaw_rate": math.radians(robot_limits.get("max_yaw_rate", 90.0))}
            print(f"reset: {msg['scenario'].get('name', '?')}", file=sys.stderr)
            reply = {"type": "ready", "name": "follow-gap (external)", "version": "1.0"}
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
