"""The episode's ground probe (sim/ground/riding.GroundProbe, asked every tick whether the body stands,
fell or is stuck) answers exactly what scenario/ground.ground_height answers, bit for bit, over
ramps, steps, pits, rough ground and height grids, and on their edges."""
import numpy as np

from pytest_navscenario.scenario.ground import surface as ground
from pytest_navscenario.scenario.model import Mission, Pose, Robot, Scenario
from pytest_navscenario.scenario.terrain import Pit, Platform, Ramp, Rough, Steps, WheeledBody
from pytest_navscenario.sim.ground.riding import GroundProbe


def scene(terrain):
    return Scenario(mission=Mission(start=Pose(-9.0, -9.0, 0.0), goal=Pose(9.0, 9.0)), terrain=tuple(terrain),
                    robot=Robot(drive="diff", body=WheeledBody()))


MIXED = [Rough("yard", 0.0, 0.0, length=6.0, width=4.0, amplitude=0.2, wavelength=0.6, seed=7, yaw=30.0),
         Rough("dip", 4.0, 3.0, length=3.0, width=3.0, amplitude=0.3, wavelength=0.8, seed=2, z=-0.1),
         Ramp("ramp", 1.0, 2.5, length=3.0, width=2.0, rise=0.4, yaw=-20.0),
         Platform("dock", -3.0, -2.0, length=2.0, width=2.0, height=0.5),
         Pit("pit", 2.0, -2.5, length=1.0, width=1.0, depth=0.6),
         Steps("steps", -3.5, 2.5, count=3, rise=0.1, run=0.3, width=1.5, yaw=45.0)]


def test_the_probe_matches_ground_height_bit_for_bit_on_grids_pieces_and_their_edges():
    sc = scene(MIXED)
    probe = GroundProbe(sc)
    rng = np.random.default_rng(0)
    pts = rng.uniform(-6.0, 6.0, size=(3000, 2))
    # on and a hair either side of each element's outline
    for el in sc.terrain:
        ring = ground.outline(el)
        for eps in (0.0, 1e-10, -1e-10, 2e-9, 1e-3):
            centre = np.array([el.x, el.y])
            pts = np.vstack([pts, centre + (ring - centre) * (1.0 + eps)])
    want = ground.ground_height(sc, pts[:, 0], pts[:, 1])
    got = np.array([probe.height(float(x), float(y)) for x, y in pts])
    same = (got == want) | (np.isnan(got) & np.isnan(want))
    assert same.all(), pts[~same][:5]
