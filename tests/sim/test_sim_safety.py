"""The safety layer's geometry against shapely (the slow, obvious way) on random layouts and states."""
from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from pytest_navscenario.scenario.geometry import footprint_polygons, obstacle_polygon
from pytest_navscenario.sim.safety import SAMPLE_SPACING, SafetyLayer, twist_poses
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle, Footprint, Mission, Pose, Robot, Safety, Scenario


def random_layout(rng, shape):
    obstacles = []
    for i in range(10):
        x, y = rng.uniform(-3, 3, 2)
        if rng.random() < 0.6:
            obstacles.append(BoxObstacle(f"b{i}", float(x), float(y), *map(float, rng.uniform(0.1, 2.0, 2)),
                                         yaw=float(rng.uniform(-180, 180))))
        else:
            obstacles.append(CylinderObstacle(f"c{i}", float(x), float(y), float(rng.uniform(0.1, 0.8))))
    return Scenario(mission=Mission(start=Pose(0, 0), goal=Pose(1, 1)), obstacles=tuple(obstacles),
                    robot=Robot(footprint=Footprint(shape=shape), safety=Safety(horizon=0.5, margin=0.05)))


@pytest.mark.parametrize("shape", ["box", "circle"])
def test_distances_match_shapely(shape):
    rng = np.random.default_rng(1)
    sc = random_layout(rng, shape)
    layer = SafetyLayer(sc)
    poses = np.column_stack([rng.uniform(-4, 4, 300), rng.uniform(-4, 4, 300), rng.uniform(-4, 4, 300)])
    mine = layer.distances(poses, np.arange(len(sc.obstacles)))
    ref = shapely.distance(footprint_polygons(sc.robot.footprint, poses)[:, None],
                           np.array([obstacle_polygon(o) for o in sc.obstacles])[None, :])
    # shapely's circles are 64-gons (0.1 % radius error); the rest is exact, overlaps read 0
    assert np.abs(mine - ref).max() < 2e-3
    assert ((mine == 0) == (ref == 0)).mean() > 0.999 and (ref == 0).sum() > 50


@pytest.mark.parametrize("shape", ["box", "circle"])
def test_check_agrees_with_a_dense_shapely_sweep(shape):
    rng = np.random.default_rng(2)
    sc = random_layout(rng, shape)
    layer = SafetyLayer(sc)
    polys = np.array([obstacle_polygon(o) for o in sc.obstacles])
    hits = misses = 0
    for _ in range(150):
        near = sc.obstacles[rng.integers(len(sc.obstacles))]            # start close to something
        x, y = near.x + rng.uniform(-2, 2), near.y + rng.uniform(-2, 2)
        yaw = rng.uniform(-math.pi, math.pi)
        vx, vy, wz = rng.uniform(-1, 1), rng.uniform(-0.5, 0.5), rng.uniform(-1.5, 1.5)
        poses = twist_poses(x, y, yaw, vx, vy, wz, np.linspace(0, 0.5, 61))
        if shape == "circle":   # a disc's distance is its centre's minus the radius (fast)
            dist = np.maximum(shapely.distance(shapely.points(poses[:, :2])[:, None], polys[None, :])
                              - sc.robot.footprint.radius, 0.0)
        else:
            dist = shapely.distance(footprint_polygons(sc.robot.footprint, poses)[:, None],
                                    polys[None, :])                  # (61, n)
        if (dist[0] == 0).any():
            continue                                                 # already in contact
        name = layer.check(x, y, yaw, vx, vy, wz)
        now = dist[0]
        approaching = (dist[1:] < now - 1e-6).any(axis=0)
        must = ((now > 0.05 + SAMPLE_SPACING / 2) & (dist[1:].min(axis=0) <= 0.05)).any()
        may = ((dist[1:].min(axis=0) <= 0.05 + SAMPLE_SPACING) & ((now > 0.05) | approaching)).any()
        if must:
            assert name is not None, (x, y, yaw, vx, vy, wz)
        if name is not None:
            assert may, (x, y, yaw, vx, vy, wz, name)
            j = [o.name for o in sc.obstacles].index(name)
            assert dist[1:, j].min() <= 0.05 + SAMPLE_SPACING
            hits += 1
        else:
            misses += 1
    assert hits >= 5 and misses >= 5, (hits, misses)   # both branches were exercised


def test_twist_poses_follow_the_arc():
    # a quarter circle of radius 1: vx = 1 m/s, wz = pi/2 rad/s for 1 s from the origin, heading +x
    end = twist_poses(0.0, 0.0, 0.0, 1.0, 0.0, math.pi / 2, np.array([0.0, 1.0]))
    r = 1 / (math.pi / 2)
    assert end[1] == pytest.approx([r, r, math.pi / 2])
    straight = twist_poses(1.0, 2.0, math.pi / 2, 0.5, 0.0, 0.0, np.array([2.0]))
    assert straight[0] == pytest.approx([1.0, 3.0, math.pi / 2])
