"""What the wheeled body crosses, measured in MuJoCo: the highest step, the steepest ramp and the
widest gap a straight-driving planner gets across at a given speed (bisection, 7 episodes each), for
a few bodies. The figures behind ``scenario/bodies/wheeled.py``'s WHEELED_* estimates (which stay
at or above them at every speed).

    python benchmarks/measure_wheeled_limits.py [--speeds 1.0,0.5,0.25,0.1] [--bodies default]

Measured under MuJoCo 4.0.1 with the PI wheel-speed loop and the casters that give way at a ramp's
foot (issue 36.1): default diff body at 1 / 0.5 / 0.25 / 0.1 m/s: steps 0.041 / 0.033 / 0.017 /
0.014 m, slopes 24.4 / 23.1 / 20.3 / 20.6 deg, gaps 0.203 / 0.129 / 0.105 / 0.109 m; skid 0.080 ->
0.053 m, 35.0 -> 33.8 deg, 0.191 -> 0.172 m (docs/benchmarks.md). The figures below are of the
earlier bodies.

Measured under MuJoCo 4.0.1 (PyPI's today): default diff body step 0.041 m, slope 17.2 deg, gap 0.230 m;
30 kg: 0.045, 17.5, 0.227; 20 N m: 0.047, 17.5, 0.227; wheels 0.15 m: 0.055, 16.2, 0.477; skid: 0.081,
34.4, 0.191. A patch release moves these by up to a quarter (the steps and gaps below, under 4.0.0):
the estimates are bounds with room (scenario/bodies/wheeled.py), checked against both releases' figures by
tests/verdict/test_traversable.py.

Measured (MuJoCo 4.0.0), with the mass at the axle and preloaded caster springs (terrain4): default
diff body (50 kg, 10 N m, wheels 0.1 m) step 0.036 m, slope 17.2 deg, gap 0.180 m; 30 kg: 0.038,
17.5, 0.168; 20 N m: 0.036, 17.5, 0.172; wheels 0.15 m: 0.047, 16.2, 0.453; skid: 0.064, 34.4, 0.172.
(Before, with the mass in the chassis box's middle and softer casters: step 0.044, slope 17.5, gap
0.129; skid 0.081, 32.5, 0.113.) A diff body's slope is not torque-limited: its casters carry load
and the driven wheels lose grip, so more torque does not help. (A gap's bisection assumes the
outcome is monotonic in the width; it is not quite, so the gap figures are rough.) All at 1 m/s;
figures at several speeds: docs/benchmarks.md (#36).
"""
from __future__ import annotations

import argparse
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from pytest_navscenario.scenario.bodies import WheeledBody, body_capability  # noqa: E402
from pytest_navscenario.scenario.model import Footprint, Mission, Pose, Robot, Safety, Scenario  # noqa: E402
from pytest_navscenario.scenario.terrain import Pit, Platform, Ramp  # noqa: E402
from pytest_navscenario.sim.episode import simulate  # noqa: E402

BODIES = {
    "default": WheeledBody(),
    "30kg": WheeledBody(mass=30.0),
    "20Nm": WheeledBody(max_wheel_torque=20.0),
    "r0.15": WheeledBody(wheel_radius=0.15, clearance=0.15),
    "skid": WheeledBody(drive_wheels="skid"),
}
EDGE = 2.0      # m from the start to the step's edge, the ramp's foot, the gap's near side
BEYOND = 1.5    # m past the obstacle to the goal


class Straight:
    """Drives straight along +x at ``speed`` m/s, blind to everything."""

    def __init__(self, speed: float):
        self.speed = speed

    def reset(self, scenario):
        pass

    def act(self, obs):
        return (self.speed, 0.0, 0.0)


def scene(terrain, body, goal_x: float, speed: float) -> Scenario:
    timeout = 2.0 * goal_x / speed + 10.0
    return Scenario(mission=Mission(start=Pose(0, 0, 0), goal=Pose(goal_x, 0), timeout=timeout),
                    terrain=tuple(terrain),
                    robot=Robot(footprint=Footprint(), drive="diff", body=body, safety=Safety(enabled=False)))


def crosses(terrain, body, goal_x: float, speed: float) -> bool:
    return simulate(scene(terrain, body, goal_x, speed), Straight(speed), 0).end == "goal"


def bisect(ok, lo: float, hi: float, n: int = 7) -> float:
    for _ in range(n):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def step_limit(body, speed: float) -> float:
    kerb = lambda h: [Platform("k", EDGE + 2.0, 0, length=4, width=3, height=h)]  # noqa: E731
    return bisect(lambda h: crosses(kerb(h), body, EDGE + BEYOND, speed), 0.0, 0.2)


def ramp(deg: float) -> list:
    rise = 3 * math.tan(math.radians(deg))
    return [Ramp("r", EDGE + 1.5, 0, length=3, width=3, rise=rise),
            Platform("t", EDGE + 6.0, 0, length=6, width=3, height=rise)]


def slope_limit(body, speed: float) -> float:
    return bisect(lambda d: crosses(ramp(d), body, EDGE + 3.0 + BEYOND, speed), 0.0, 40.0)


def gap_limit(body, speed: float) -> float:
    pit = lambda w: [Pit("g", EDGE + w / 2, 0, length=w, width=3, depth=1.0)]  # noqa: E731
    return bisect(lambda w: crosses(pit(w), body, EDGE + 0.5 + BEYOND, speed), 0.0, 0.5)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speeds", default="1.0", help="comma-separated straight-driving speeds, m/s (default 1.0)")
    ap.add_argument("--bodies", default=",".join(BODIES), help=f"comma-separated, of: {', '.join(BODIES)}")
    ap.add_argument("--what", default="step,slope,gap", help="comma-separated, of: step, slope, gap")
    args = ap.parse_args(argv)
    what = args.what.split(",")
    print(f"command: python benchmarks/measure_wheeled_limits.py {' '.join(argv if argv is not None else sys.argv[1:])}")
    print("body    speed | step m  slope deg  gap m | estimate: step  slope  gap")
    for name in args.bodies.split(","):
        body = BODIES[name]
        cap = body_capability(scene([], body, 1.0, 1.0))
        for speed in (float(s) for s in args.speeds.split(",")):
            step = step_limit(body, speed) if "step" in what else math.nan
            slope = slope_limit(body, speed) if "slope" in what else math.nan
            gap = gap_limit(body, speed) if "gap" in what else math.nan
            print(f"{name:7} {speed:5.2f} | {step:6.3f} {slope:9.1f} {gap:6.3f} | "
                  f"{cap.max_step:14.3f} {cap.max_slope:6.1f} {cap.max_gap:5.3f}", flush=True)


if __name__ == "__main__":
    main()
