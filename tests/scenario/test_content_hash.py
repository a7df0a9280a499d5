"""content_hash pairs scenarios across results files written by different versions: the hashes of
the shipped scenarios (boxes, cylinders, moving obstacles, polygons and meshes, lidar options) are
pinned, so a faster or refactored implementation cannot change them unnoticed."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from pytest_navscenario.scenario.loader import load_scenario
from pytest_navscenario.scenario.model import content_hash

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"

PINNED = {  # written by the implementation before issue 14's speed-up
    "L-corridor": "485472539df6322b", "boxes1": "1bfa4415005c2e02", "boxes2": "aeb896a18fd92360",
    "corridor": "38b126911cdbd6fe", "cylinders": "40b0696933c5e63c", "forklift-aisle": "5d0c328376f39bc4",
    "glass-door": "205c53db6c1558ba", "person-crossing": "3af2d3c344e4a04b",
    "workshop-irregular": "6d801cd30ac0483e",
}


@pytest.mark.parametrize("name", sorted(PINNED))
def test_shipped_scenarios_keep_their_hash(name):
    assert content_hash(load_scenario(SCENARIOS / f"{name}.yaml")) == PINNED[name]


def test_labels_do_not_change_the_hash_and_content_does():
    base = load_scenario(SCENARIOS / "boxes1.yaml")
    renamed = dataclasses.replace(base, name="other", family="elsewhere", description="x",
                                  obstacles=tuple(dataclasses.replace(o, name=f"o{i}")
                                                  for i, o in enumerate(base.obstacles)))
    assert content_hash(renamed) == content_hash(base)
    moved = dataclasses.replace(base, obstacles=(dataclasses.replace(base.obstacles[0], x=base.obstacles[0].x + 1e-9),
                                                 *base.obstacles[1:]))
    assert content_hash(moved) != content_hash(base)
    integral = dataclasses.replace(base, mission=dataclasses.replace(
        base.mission, timeout=int(base.mission.timeout)))
    assert float(base.mission.timeout).is_integer()
    assert content_hash(integral) == content_hash(base)     # 1 and 1.0 hash alike
