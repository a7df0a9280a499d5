"""Make docs/pictures/moving-person.png (docs/pictures is examples/pictures): the person-crossing seed with the person starting 1.4 s
later than written (a failure the search finds), run against the built-in ``dwa``.

    python benchmarks/make_moving_picture.py [--out docs/pictures/moving-person.png]
"""
from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "docs" / "pictures" / "moving-person.png"))
    args = ap.parse_args()
    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.report.plots import save_trajectory
    from pytest_navscenario.scenario.loader import load_scenario

    seed = load_scenario(ROOT / "scenarios" / "person-crossing.yaml")
    walker = seed.obstacle("walker")
    later = dataclasses.replace(walker, motion=dataclasses.replace(walker.motion, start=walker.motion.start + 1.4))
    scenario = dataclasses.replace(seed, obstacles=tuple(later if o is walker else o for o in seed.obstacles))
    result = run_scenario(scenario, "dwa")
    print(result.outcome.value, result.message)
    save_trajectory(result, args.out)


if __name__ == "__main__":
    main()
