"""What the wheeled body crosses, measured in MuJoCo: the highest step, the steepest ramp and the
widest gap a straight-driving planner gets across (bisection, 7 episodes each), for a few bodies.
The figures behind ``scenario/ground/crossing.py``'s WHEELED_* estimates (which stay under them).

    python benchmarks/measure_wheeled_limits.py

Measured under MuJoCo 4.0.1 (PyPI's today): default diff body step 0.041 m, slope 17.2 deg, gap 0.230 m;
30 kg: 0.045, 17.5, 0.227; 20 N m: 0.047, 17.5, 0.227; wheels 0.15 m: 0.055, 16.2, 0.477; skid: 0.081,
34.4, 0.191. A patch release moves these by up to a quarter (the steps and gaps below, under 4.0.0):
the estimates are bounds with room (crossing.py), checked against both releases' figures by
tests/verdict/test_traversable.py.

Measured (MuJoCo 4.0.0), with the mass at the axle and preloaded caster springs (terrain4): default
diff body (50 kg, 10 N m, wheels 0.1 m) step 0.036 m, slope 17.2 deg, gap 0.180 m; 30 kg: 0.038,
17.5, 0.168; 20 N m: 0.036, 17.5, 0.172; wheels 0.15 m: 0.047, 16.2, 0.453; skid: 0.064, 34.4, 0.172.
(Before, with the mass in the chassis box's middle and softer casters: step 0.044, slope 17.5, gap
0.129; skid 0.081, 32.5, 0.113.) A diff body's slope is not torque-limited: its casters carry load
and the driven wheels lose grip, so more torque does not help. (A gap's bisection assumes the
outcome is monotonic in the width; it is not quite, so the gap figures are rough.)
"""
from __future__ import annotations

import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests", "search"))

from straight_planner import Straight  # noqa: E402

from pytest_navscenario.scenario.ground.crossing import body_capability  # noqa: E402
from pytest_navscenario.scenario.model import Footprint, Mission, Pose, Robot, Safety, Scenario  # noqa: E402
from pytest_navscenario.scenario.terrain import Pit, Platform, Ramp, WheeledBody  # noqa: E402
from pytest_navscenario.sim.episode import simulate  # noqa: E402


def scene(terrain, body) -> Scenario:
    return Scenario(mission=Mission(start=Pose(0, 0, 0), goal=Pose(10, 0), timeout=20.0), terrain=tuple(terrain),
                    robot=Robot(footprint=Footprint(), drive="diff", body=body, safety=Safety(enabled=False)))


def crosses(terrain, body) -> bool:
    return simulate(scene(terrain, body), Straight(), 0).end == "goal"


def bisect(ok, lo: float, hi: float, n: int = 7) -> float:
    for _ in range(n):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def main() -> None:
    bodies = [WheeledBody(), WheeledBody(mass=30.0), WheeledBody(max_wheel_torque=20.0),
              WheeledBody(wheel_radius=0.15, clearance=0.15), WheeledBody(drive_wheels="skid")]
    print("mass torque radius wheels | step m  slope deg  gap m | estimate: step  slope  gap")
    for body in bodies:
        step = bisect(lambda h: crosses([Platform("k", 8, 0, length=4, width=3, height=h)], body), 0.0, 0.2)

        def ramp(deg):
            rise = 3 * math.tan(math.radians(deg))
            return [Ramp("r", 5, 0, length=3, width=3, rise=rise), Platform("t", 9.5, 0, length=6, width=3, height=rise)]

        slope = bisect(lambda d: crosses(ramp(d), body), 0.0, 40.0)
        gap = bisect(lambda w: crosses([Pit("g", 5, 0, length=w, width=3, depth=1.0)], body), 0.0, 0.5)
        cap = body_capability(scene([], body))
        print(f"{body.mass:4g} {body.max_wheel_torque:6g} {body.wheel_radius:6g} {body.drive_wheels:6} | "
              f"{step:6.3f} {slope:9.1f} {gap:6.3f} | {cap.max_step:14.3f} {cap.max_slope:6.1f} {cap.max_gap:5.3f}")


if __name__ == "__main__":
    main()
