"""Make the docs' pictures of terrain episodes (docs/how-to/plots-html.md, docs/reference/sensors.md).

    python benchmarks/make_terrain_pictures.py [--out docs/pictures]

A wheeled robot driving straight at a pit: with the 2D lidar alone its plane passes over the pit
and the robot falls in (``terrain-fall.png``); the same robot with a 3D lidar is halted by the
safety layer before the edge; both side by side (``terrain-pit-side-by-side.png``). A ramp up to a
dock: the 2D lidar reads the ramp as a wall, then the plane tilts with the body
(``terrain-ramp.png``, with the side profile).
"""
from __future__ import annotations

import argparse
from pathlib import Path

PIT = """
version: 1
name: pit-ahead
robot:
  body: {type: wheeled}
  drive: diff
  LIDAR3D
mission: {start: {x: 0, y: 0}, goal: {x: 8, y: 0}, timeout: 20}
terrain:
  - {type: pit, name: hole, x: 4.5, y: 0, length: 1.5, width: 6, depth: 1.0}
"""

RAMP = """
version: 1
name: ramp-to-dock
robot:
  body: {type: wheeled}
  drive: diff
mission: {start: {x: 0, y: 0}, goal: {x: 9, y: 0}, timeout: 25}
obstacles:
  - {type: box, name: crate, x: 8.8, y: 1.0, length: 0.6, width: 0.6, height: 0.8}
terrain:
  - {type: ramp, name: up, x: 4, y: 0, length: 4, width: 3, rise: 0.70530}
  - {type: platform, name: dock, x: 8, y: 0, length: 4, width: 3, height: 0.70530}
"""


class Straight:
    """Drives straight ahead at ``speed``."""
    name, version = "straight", "1"

    def __init__(self, speed: float = 0.6):
        self.speed = speed

    def reset(self, scenario):
        pass

    def act(self, obs):
        return (self.speed, 0.0, 0.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "docs" / "pictures"))
    args = ap.parse_args()
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.report.plots import save_comparison, save_trajectory
    from pytest_navscenario.scenario.loader import loads_scenario

    out = Path(args.out)
    fall = run_scenario(loads_scenario(PIT.replace("LIDAR3D", "")), Straight())
    stop = run_scenario(loads_scenario(PIT.replace("LIDAR3D", "lidar3d: {}")), Straight())
    print(fall.outcome.value, fall.message)
    print(stop.outcome.value, stop.message)
    save_trajectory(fall, out / "terrain-fall.png")
    save_comparison(fall, stop, out / "terrain-pit-side-by-side.png", labels=("2D lidar", "3D lidar"))
    ramp = run_scenario(loads_scenario(RAMP), Straight(0.5))
    print(ramp.outcome.value, ramp.message)
    save_trajectory(ramp, out / "terrain-ramp.png")


if __name__ == "__main__":
    main()
