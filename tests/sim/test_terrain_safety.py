"""The collision safety layer halts for a terrain face the body cannot cross, as for an obstacle
(issue 36.3): a stair riser or a platform's side rising ahead of a wheeled robot stops it before its
chassis meets the face. A face is a wall only from its low side: a robot on top of a dock is not
stopped by the dock's own edge (a 2D layer cannot see a drop; the 3D lidar's ground layer does), nor
one on the floor by a pit's rim; and a sill the body climbs is no face at all. Real MuJoCo episodes
of the built-in wheeled body driven straight, blind."""
import sys
from pathlib import Path

import pytest

from pytest_navscenario.scenario.bodies import WheeledBody
from pytest_navscenario.scenario.model import Footprint, Mission, Pose, Robot, Scenario
from pytest_navscenario.scenario.terrain import Pit, Platform, Steps
from pytest_navscenario.sim.episode import simulate

sys.path.insert(0, str(Path(__file__).parents[1] / "search"))
from straight_planner import Straight  # noqa: E402

FP = Footprint(shape="box", length=0.9, width=0.5)


def scene(terrain, start=(0.0, 0.0), goal=(9.0, 0.0)):
    return Scenario(mission=Mission(start=Pose(*start, 0.0), goal=Pose(*goal, 0.0), timeout=20),
                    terrain=tuple(terrain), robot=Robot(footprint=FP, drive="diff", body=WheeledBody()))


def test_it_halts_before_a_stair_riser_its_scan_plane_meets_and_not_one_under_it():
    """Risers of 0.25 m rise above the 2D lidar's plane (0.2 m): the layer halts before the first.
    A 0.17 m face does not: it is under the plane, unseen by a real layer as glass is."""
    tall = Steps("stairs", 5.0, 0.0, count=4, rise=0.25, run=0.3, width=2.0)    # first riser at x = 4.4
    res = simulate(scene([tall]), Straight(), 0)
    assert res.end == "safety-stop", (res.end, res.collision, res.terrain_event)
    assert res.safety_stop.obstacle == "steps 'stairs' (0.25 m step)"
    front = float(res.trajectory.pose[-1, 0]) + FP.length / 2
    safety = Robot().safety                  # horizon 0.5 s, margin 0.05 m
    reach = 1.0 * safety.horizon + safety.margin + 0.1               # at 1 m/s, plus a tick's travel
    assert 0.0 < 4.4 - front < reach         # stopped short of the riser, within its horizon's reach
    # a 0.17 m kerb is under the plane: unseen, the chassis (0.1 m up) drives into it
    kerb = simulate(scene([Platform("kerb", 6.0, 0.0, length=4.0, width=4.0, height=0.17)]), Straight(), 0)
    assert kerb.end == "collision" and kerb.collision.terrain, (kerb.end, kerb.safety_stop)
    # stairs of 0.17 m: the plane meets the second riser (0.34 m up), within the sweep before the
    # chassis reaches the first at 1 m/s
    low = simulate(scene([Steps("stairs", 5.0, 0.0, count=5, rise=0.17, run=0.3, width=2.0)]), Straight(), 0)
    assert low.end == "safety-stop" and low.safety_stop.obstacle == "steps 'stairs' (0.17 m step)"
    assert float(low.trajectory.pose[-1, 0]) + FP.length / 2 < 4.25


def test_it_halts_before_a_platforms_side_but_not_at_the_edge_of_the_one_it_stands_on():
    wall = simulate(scene([Platform("dock", 6.0, 0.0, length=4.0, width=4.0, height=0.6)]), Straight(), 0)
    assert wall.end == "safety-stop" and wall.safety_stop.obstacle.startswith("platform 'dock'")
    # on top of it, driving off its far edge: the edge is a drop for it, not a wall
    off = simulate(scene([Platform("dock", 0.0, 0.0, length=4.0, width=4.0, height=0.6)], goal=(5.0, 0.0)),
                   Straight(), 0)
    assert off.end == "fell", (off.end, off.safety_stop)


def test_a_pits_rim_and_a_sill_it_climbs_do_not_halt_it():
    pit = simulate(scene([Pit("pit", 4.0, 0.0, length=1.0, width=3.0, depth=0.5)]), Straight(), 0)
    assert pit.end == "fell", (pit.end, pit.safety_stop)
    sill = simulate(scene([Platform("sill", 4.0, 0.0, length=0.3, width=3.0, height=0.01)]), Straight(), 0)
    assert sill.end == "goal", (sill.end, sill.safety_stop)


def test_the_verdict_names_the_face_it_was_predicted_to_hit():
    from pytest_navscenario.harness.runner import run_scenario

    tall = Steps("stairs", 5.0, 0.0, count=4, rise=0.25, run=0.3, width=2.0)
    res = run_scenario(scene([tall]), Straight, seed=0)
    assert res.outcome.value == "safety-stop"
    assert "predicted to hit the face of steps 'stairs' (0.25 m step) at 1.00 m/s" in res.message, res.message
