"""Irregular obstacles (issue 12, part 2): polygon prisms and STL/OBJ meshes, through the format, the
simulation, the verdict, the pictures, the bags, the search and freezing."""
from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry import LineString, Polygon

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.dump import dump_scenario
from pytest_navscenario.scenario.geometry import convex_parts_local, footprint_polygon, obstacle_polygon
from pytest_navscenario.scenario.loader import load_scenario, loads_scenario
from pytest_navscenario.scenario.model import content_hash
from pytest_navscenario.sim.episode import simulate
from pytest_navscenario.verdict.paths import inflation_radius, shortest_path

U = [[0, 0], [3, 0], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3], [0, 3]]   # a U opening towards +y


def box_triangles(x0, y0, x1, y1, z0, z1):
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0), (x0, y0, z1), (x1, y0, z1), (x1, y1, z1),
         (x0, y1, z1)]
    faces = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (1, 2, 6), (1, 6, 5), (2, 3, 7),
             (2, 7, 6), (3, 0, 4), (3, 4, 7)]
    return [[v[a], v[b], v[c]] for a, b, c in faces]


ELL = box_triangles(0, 0, 2, 0.5, 0, 0.8) + box_triangles(0, 0.5, 0.5, 2, 0, 0.8)   # an L, 0.8 m high


def write_stl(path: Path, triangles) -> Path:
    with open(path, "wb") as fh:
        fh.write(b"\0" * 80 + struct.pack("<I", len(triangles)))
        for tri in triangles:
            fh.write(struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *p) for p in tri) + b"\0\0")
    return path


def write_obj(path: Path, triangles) -> Path:
    lines = [f"v {x} {y} {z}" for tri in triangles for x, y, z in tri]
    lines += [f"f {3 * i + 1} {3 * i + 2} {3 * i + 3}" for i in range(len(triangles))]
    path.write_text("\n".join(lines) + "\n")
    return path


def project(tmp_path: Path, obstacles: str, *, safety: str = "true", start="{x: 0, y: 0}",
            goal="{x: 8, y: 0}") -> Path:
    write_stl(tmp_path / "ell.stl", ELL)
    write_obj(tmp_path / "ell.obj", ELL)
    path = tmp_path / "s.yaml"
    path.write_text(f"version: 1\nrobot: {{safety: {{enabled: {safety}}}}}\n"
                    f"mission: {{start: {start}, goal: {goal}, timeout: 20}}\nobstacles:\n{obstacles}\n")
    return path


class Straight:
    """Drives along +x at 1 m/s, blind."""

    def reset(self, scenario):
        pass

    def act(self, obs):
        return (1.0, 0.0, 0.0)


# ---------------------------------------------------------------- the format

def test_polygons_and_meshes_load_dump_and_hash(tmp_path):
    sc = load_scenario(project(tmp_path, f"  - {{type: polygon, name: u, x: 3, y: -1.5, points: {U}}}\n"
                                         "  - {type: mesh, name: ell, file: ell.stl, x: 5, y: 2, yaw: 90}\n"
                                         "  - {type: mesh, name: small, file: ell.obj, x: -3, y: 2, scale: 0.5}"))
    u, ell, small = sc.obstacles
    assert u.points[4] == (2.0, 1.0) and u.height == 1.0
    assert ell.height == pytest.approx(0.8) and len(ell.footprint) == 6
    assert Polygon(ell.footprint).area == pytest.approx(2 * 0.5 + 0.5 * 1.5)
    assert small.scale == (0.5, 0.5, 0.5) and small.height == pytest.approx(0.4)
    assert Polygon(small.footprint).area == pytest.approx((2 * 0.5 + 0.5 * 1.5) / 4)
    # the mesh placed and turned: the L's long arm along +y now
    assert obstacle_polygon(ell).bounds == pytest.approx((3.0, 2.0, 5.0, 4.0))
    again = loads_scenario(dump_scenario(sc), source=tmp_path / "copy.yaml")
    assert again == sc and content_hash(again) == content_hash(sc)
    assert len(convex_parts_local(u.points)) == 3      # a U: the base and two arms


BAD = [
    ("{type: polygon, points: [[0, 0], [2, 2], [2, 0], [0, 2]]}", "obstacles[0].points", "not simple: Self-intersection"),
    ("{type: polygon, points: [[0, 0], [2, 2]]}", "obstacles[0].points", "at least three points, got 2"),
    ("{type: polygon, points: [[0, 0], [1, 1], [2, 2]]}", "obstacles[0].points", "no area"),
    ("{type: polygon, x: 1}", "obstacles[0].points", "missing required field 'points'"),
    ("{type: polygon, points: [[0, 0], [2, 0], [2]]}", "obstacles[0].points[2]", "expected a point [x, y]"),
    ("{type: polygon, points: [[4, 4], [5, 4], [5, 5]], radius: 1}", "obstacles[0].radius",
     "does not apply to type: polygon"),
    ("{type: mesh, x: 1, y: 1}", "obstacles[0].file", "missing required field 'file'"),
    ("{type: mesh, file: nothing.stl}", "obstacles[0].file", "does not exist"),
    ("{type: mesh, file: ../outside.stl}", "obstacles[0].file", "leaves the scenario's folder"),
    ("{type: mesh, file: /etc/passwd.stl}", "obstacles[0].file", "is an absolute path"),
    ("{type: mesh, file: folder.stl}", "obstacles[0].file", "is not a file"),
    ("{type: mesh, file: huge.stl}", "obstacles[0].file", "more than the limit of 20 MB"),
    ("{type: mesh, file: garbage.stl}", "obstacles[0].file", "neither a binary STL"),
    ("{type: mesh, file: bad.obj}", "obstacles[0].file", "bad.obj:2: a face refers to a vertex that is not defined"),
    ("{type: mesh, file: two.stl}", "obstacles[0].file", "falls apart into 2 separate pieces"),
    ("{type: mesh, file: ell.ply}", "obstacles[0].file", "unknown mesh format .ply"),
    ("{type: mesh, file: ell.stl, scale: 0}", "obstacles[0].scale", "must be > 0"),
    ("{type: mesh, file: ell.stl, scale: [1, 2]}", "obstacles[0].scale", "expected one number or three"),
]


@pytest.mark.parametrize("obstacle, field, message", BAD, ids=[f"{b[1]}:{b[2][:24]}" for b in BAD])
def test_bad_polygon_and_mesh_input_names_file_line_and_field(tmp_path, obstacle, field, message):
    (tmp_path / "folder.stl").mkdir()
    with open(tmp_path / "huge.stl", "wb") as fh:
        fh.truncate(21_000_000)
    (tmp_path / "garbage.stl").write_bytes(b"\x01\x02 not a mesh")
    (tmp_path / "bad.obj").write_text("v 0 0 0\nf 1 2 3\n")
    write_stl(tmp_path / "two.stl", box_triangles(0, 0, 1, 1, 0, 1) + box_triangles(3, 0, 4, 1, 0, 1))
    (tmp_path / "ell.ply").write_text("ply\n")
    (tmp_path.parent / "outside.stl").write_bytes(b"")
    path = project(tmp_path, "  - " + obstacle, start="{x: -5, y: -5}", goal="{x: -8, y: -5}")
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    text = str(err.value)
    assert str(path) in text and field in text and message in text, text
    assert err.value.line == 5, text


# ---------------------------------------------------------------- simulation and verdict

@pytest.mark.parametrize("kind", ["polygon", "mesh"])
def test_collision_with_a_polygon_or_a_mesh_is_where_its_outline_is(tmp_path, kind):
    # the robot drives along y = 0 into the inside of the U's bottom (x = 3) / the L's foot (x = 4)
    obstacle = (f"  - {{type: polygon, name: shape, x: 3, y: -1.5, points: {U}}}" if kind == "polygon"
                else "  - {type: mesh, name: shape, file: ell.stl, x: 4, y: -1}")
    sc = load_scenario(project(tmp_path, obstacle, safety="false"))
    result = run_scenario(sc, Straight)
    assert result.outcome.value == "collision" and result.collision.obstacle == "shape"
    front = result.trajectory.pose[-1, 0] + 0.45          # the box footprint's front edge
    assert front == pytest.approx(3.0 if kind == "polygon" else 4.0, abs=0.03)
    # with the safety layer on, it halts the robot in front of it instead
    stopped = run_scenario(load_scenario(project(tmp_path, obstacle)), Straight)
    assert stopped.outcome.value == "safety-stop" and stopped.safety_stop.obstacle == "shape"


def test_a_robot_can_drive_into_the_notch_of_a_u_a_hull_would_fill(tmp_path):
    # the U's notch is 1 m wide between x = 4 and 5 (y from -0.5 up): a circle robot of radius 0.3
    # drives into it from above and stops before the bottom; a convex hull would block the notch
    import dataclasses

    sc = load_scenario(project(tmp_path, f"  - {{type: polygon, name: u, x: 3, y: -1.5, points: {U}}}",
                               safety="false", start="{x: 4.5, y: 3.0, yaw: -90}", goal="{x: 4.5, y: 0.0}"))
    circle = dataclasses.replace(sc.robot.footprint, shape="circle", radius=0.3)
    sc = dataclasses.replace(sc, robot=dataclasses.replace(sc.robot, footprint=circle))
    result = run_scenario(sc, Straight)         # forward = -y here
    assert result.outcome.value == "success", result.message
    assert result.metrics.min_clearance == pytest.approx(0.2, abs=0.02)   # the notch's walls, 0.5 - 0.3


def test_the_lidar_sees_the_outline_not_its_hull(tmp_path):
    sc = load_scenario(project(tmp_path, f"  - {{type: polygon, name: u, x: 3, y: -1.5, points: {U}}}",
                               start="{x: 4.5, y: 3.0}", goal="{x: -4, y: 3}"))
    seen = []

    class Look:
        def reset(self, scenario):
            pass

        def act(self, obs):
            seen.append(np.array(obs.ranges))
            return (0.0, 0.0, 0.0)

    result = simulate(sc, Look(), seed=0, max_ticks=1)
    down = int(np.argmin(np.abs(np.asarray(result.trajectory.angles) + math.pi / 2)))
    assert seen[0][down] == pytest.approx(3.0 - (-0.5), abs=1e-4)   # into the notch, to its bottom (y = -0.5)


@pytest.mark.parametrize("kind", ["polygon", "mesh"])
def test_clearance_and_shortest_path_follow_the_outline(tmp_path, kind):
    obstacle = (f"  - {{type: polygon, name: shape, x: 3, y: -1.5, points: {U}, yaw: 30}}" if kind == "polygon"
                else "  - {type: mesh, name: shape, file: ell.stl, x: 3.5, y: -1, yaw: 30}")
    sc = load_scenario(project(tmp_path, obstacle))
    outline = obstacle_polygon(sc.obstacles[0])
    # the clearance of a robot parked beside it: the exact footprint-outline distance
    parked = load_scenario(project(tmp_path, obstacle, start="{x: 6.0, y: 1.5, yaw: 10}", goal="{x: 8, y: 3}"))
    standing = run_scenario(parked, lambda: type("Still", (), {"reset": lambda s, sc: None,
                                                               "act": lambda s, o: (0, 0, 0)})())
    expected = footprint_polygon(sc.robot.footprint, 6.0, 1.5, math.radians(10)).distance(outline)
    assert 0.5 < expected < 1.0
    assert standing.metrics.min_clearance == pytest.approx(expected, abs=1e-6)
    assert standing.metrics.min_clearance_obstacle == "shape"
    # the shortest path goes around it, never closer than half the robot's width, and not much longer
    path = shortest_path(sc)
    r = inflation_radius(sc.robot.footprint)
    line = LineString(path.points)
    assert line.distance(outline) >= r - 1e-6
    assert not line.intersects(outline.buffer(r - 0.005))
    assert 8.0 < path.length < 8.0 + 2.0


def test_a_fifty_corner_polygon_is_split_into_convex_parts_that_cover_it_exactly():
    star = tuple(((1 + (i % 2)) * math.cos(2 * math.pi * i / 50), (1 + (i % 2)) * math.sin(2 * math.pi * i / 50))
                 for i in range(50))
    parts = convex_parts_local(star)
    union = Polygon(star)
    assert sum(Polygon(p).area for p in parts) == pytest.approx(union.area)
    for p in parts:
        poly = Polygon(p)
        assert poly.convex_hull.area == pytest.approx(poly.area) and poly.exterior.is_ccw
        assert union.buffer(1e-9).contains(poly)


# ---------------------------------------------------------------- pictures, bags, search, freezing

def test_the_plot_and_the_bag_show_polygons_and_meshes(tmp_path):
    pytest.importorskip("matplotlib")
    from rosbags.highlevel import AnyReader

    from pytest_navscenario.report.html import view_data
    from pytest_navscenario.report.plots import trajectory_figure
    from pytest_navscenario.ros.bag_writer import write_episode_bag

    sc = load_scenario(project(tmp_path, f"  - {{type: polygon, name: u, x: 3, y: -1.5, points: {U}}}\n"
                                         "  - {type: mesh, name: ell, file: ell.stl, x: 5, y: 2}"))
    result = run_scenario(sc, "dwa")
    fig = trajectory_figure(result)
    drawn = [np.asarray(p.vertices) for coll in fig.axes[0].collections for p in coll.get_paths()]
    for obs in sc.obstacles:
        ring = np.asarray(obstacle_polygon(obs).exterior.coords)
        assert any(len(d) >= len(ring) and np.allclose(d[:len(ring)], ring) for d in drawn), obs.name
    assert {t.get_text() for t in fig.axes[0].texts} >= {"u", "ell"}
    fig.savefig(tmp_path / "shapes.png")
    assert len(view_data(result)["obs"][0]) == len(U) + 1
    bag = write_episode_bag(result, tmp_path / "bag")
    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic == "/navscenario/obstacles"]
        (msg,) = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=conns)]
    u, ell = msg.markers
    assert u.type == ell.type == 11 and len(u.points) % 3 == 0
    assert max(p.z for p in ell.points) == pytest.approx(0.8)


def test_the_search_moves_polygon_corners_and_discards_crossed_outlines(tmp_path):
    from pytest_navscenario.search.space import SearchSpace, invalid_reason

    sc = load_scenario(project(tmp_path, f"  - {{type: polygon, name: u, x: 3, y: -1.5, points: {U}}}\n"
                                         "  - {type: mesh, name: ell, file: ell.stl, x: 5, y: 2}"))
    assert [p.name for p in SearchSpace(sc, {"insert": 0}).params] == [
        "obstacles.u.dx", "obstacles.u.dy", "obstacles.u.yaw", "obstacles.ell.dx", "obstacles.ell.dy",
        "obstacles.ell.yaw"]
    space = SearchSpace(sc, {"polygon_vertex": 1.5, "insert": 0})
    offsets = [0.0] * len(space)
    offsets[space.index["obstacles.u.points[4].dy"]] = 0.5
    moved = space.apply(offsets)
    assert moved.obstacle("u").points[4] == (2.0, 1.5) and invalid_reason(moved) is None
    offsets[space.index["obstacles.u.points[5].dx"]] = 1.5
    offsets[space.index["obstacles.u.points[4].dx"]] = -1.5     # corners 4 and 5 swap: the outline crosses
    assert invalid_reason(space.apply(offsets)) == "polygon-invalid:u"


def test_frozen_polygon_and_mesh_failures_fail_again_the_same_way(tmp_path):
    from pytest_navscenario.search.engine import run_search
    from pytest_navscenario.search.freeze import freeze_failures
    from pytest_navscenario.search.space import SearchSpace

    seed_dir = tmp_path / "seeds"
    seed_dir.mkdir()
    sc = load_scenario(project(seed_dir, f"  - {{type: polygon, name: u, x: 3, y: 0.6, points: {U}}}\n"
                                         "  - {type: mesh, name: ell, file: ell.stl, x: 5, y: -2.6}"))
    space = SearchSpace(sc)
    report = run_search(sc, Straight, budget=8, seed_value=3, shrink_budget=4, space=space)
    assert report.failures
    written = freeze_failures(report, space, tmp_path / "regressions")
    for frozen in written:
        again = load_scenario(frozen.path)          # its mesh was copied beside it
        assert (frozen.path.parent / again.obstacle("ell").file).is_file()
        assert again.obstacle("ell").file.startswith("meshes/ell-")
        assert run_scenario(again, Straight).outcome.value == frozen.outcome
