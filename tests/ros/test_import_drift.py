"""Issue 37, odometry drift corrected by scan matching: a generated bag of a robot driving a loop in a
furnished room whose odometry drifts to 6 degrees and 0.35 m (no map -> odom in the bag). Without
correction the seed blocked 29 % of its own beams; each key scan aligned to the map of those before
it puts the poses within centimetres of the truth, and the importer says how far it moved them."""
from __future__ import annotations

import math
import re
import sys

import numpy as np
import pytest
from ros_synthetic import drift_bag

from pytest_navscenario.ros.bag_import import scenario_from_bag
from pytest_navscenario.ros.bag_import.mount import choose_mount
from pytest_navscenario.ros.bag_import.reading import BagImportError, read_bag
from pytest_navscenario.ros.bag_import.scan_match import correct_drift


@pytest.fixture(scope="module")
def drifting(tmp_path_factory):
    return drift_bag(tmp_path_factory.mktemp("drift"), angles=np.radians(np.arange(-180.0, 180.0, 1.0)))


def _errors(odom: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """The largest position (m) and heading (deg) error of poses against the truth."""
    tx, ty = (np.interp(odom[:, 0], truth[:, 0], truth[:, j]) for j in (1, 2))
    tyaw = np.interp(odom[:, 0], truth[:, 0], np.unwrap(truth[:, 3]))
    turn = np.abs(np.remainder(odom[:, 3] - tyaw + math.pi, 2 * math.pi) - math.pi)
    return float(np.hypot(odom[:, 1] - tx, odom[:, 2] - ty).max()), float(np.degrees(turn.max()))


@pytest.mark.parametrize("method", ["own", "kiss-icp"])
def test_scan_matching_puts_drifting_poses_back_on_the_truth(drifting, method):
    if method == "kiss-icp":
        pytest.importorskip("kiss_icp")
    path, truth = drifting
    data = read_bag(path)
    assert _errors(data.odom, truth)[0] > 0.3                  # the odometry as recorded
    note = correct_drift(data, choose_mount(data, None)[0], method)
    shift, turn = _errors(data.odom, truth)
    assert shift < 0.04 and turn < 0.5, (shift, turn)
    moved = re.search(r"poses moved by up to ([\d.]+) m and ([\d.]+) deg, ([\d.]+) m and ([\d.]+) deg at the "
                      r"window's end", note)
    assert moved and abs(float(moved[4]) - 6.0) < 0.5, note           # the drift was 6 deg at the end


def test_the_seed_of_a_drifting_bag_fits_its_scans(drifting):
    seed = scenario_from_bag(drifting[0], scan_match="own")
    fig = seed.fit
    assert fig.blocked <= 0.05 and fig.missed <= 0.15 and abs(fig.start_seed - fig.start_scan) <= 0.15, fig
    assert any(n.startswith("odometry drift corrected by scan matching (own correlative matcher") for n in seed.notes)


def test_kiss_icp_missing_is_said_with_how_to_install(drifting, monkeypatch):
    """The registration library is an optional extra: asked for, the error says how to install it;
    by default the importer falls back to its own matcher with a word."""
    for name in ("kiss_icp", "kiss_icp.pybind", "kiss_icp.pybind.kiss_icp_pybind"):
        monkeypatch.setitem(sys.modules, name, None)         # as if not installed
    data = read_bag(drifting[0])
    mount = choose_mount(data, None)[0]
    with pytest.raises(BagImportError, match=r"pip install 'pytest-navscenario\[drift\]'"):
        correct_drift(data, mount, "kiss-icp")
    assert "KISS-ICP is not installed, so the own matcher was used" in correct_drift(data, mount, "auto")


def test_scan_matching_off_keeps_the_odometry(drifting):
    data = read_bag(drifting[0])
    before = data.odom.copy()
    assert correct_drift(data, choose_mount(data, None)[0], "off") is None
    assert np.array_equal(before, data.odom)


def test_by_default_the_odometry_is_kept_and_a_disagreeing_fit_points_to_scan_matching(drifting):
    """Off by default (a corridor gives the matching nothing along it): the drifting bag's seed
    disagrees with its scans, and the warning says what would correct it."""
    seed = scenario_from_bag(drifting[0])
    assert not any("corrected by scan matching" in n for n in seed.notes)
    assert seed.fit.blocked > 0.05 and any("--scan-match auto aligns the scans" in w for w in seed.fit.warnings)
