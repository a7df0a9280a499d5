"""Shortest collision-free paths for the footprint, and the obstacle-obstacle gap."""
import heapq
import math

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Polygon

from pytest_navscenario.verdict import grown, paths, visibility
from pytest_navscenario.scenario.geometry import obstacle_polygons
from pytest_navscenario.verdict.gaps import min_obstacle_gap
from pytest_navscenario.verdict.paths import path_exists, shortest_path
from pytest_navscenario.scenario.model import BoxObstacle, CylinderObstacle, Footprint, Mission, Pose, Robot, Scenario

CIRCLE = Footprint(shape="circle", radius=0.3)


def scenario(*obstacles, footprint=Footprint(), start=(0, 0), goal=(0, 10), waypoints=()):
    return Scenario(mission=Mission(start=Pose(*start, 90), goal=Pose(*goal, 90),
                                    waypoints=tuple(Pose(*w) for w in waypoints)),
                    obstacles=tuple(obstacles), robot=Robot(footprint=footprint))


def around_circle(d, rho):
    """Exact shortest length between two points at distance d on opposite sides of a disc
    of radius rho centred between them: two tangents and the arc between them."""
    return 2 * math.sqrt(d * d - rho * rho) + rho * (math.pi - 2 * math.acos(rho / d))


def clearance(path, s):
    line = LineString(path.points) if len(path.points) > 1 else shapely.Point(path.points[0])
    return min(line.distance(p) for p in obstacle_polygons(s))


def test_free_space_is_a_straight_line_through_the_waypoints():
    sp = shortest_path(scenario(waypoints=[(5, 5)]))
    assert sp.length == pytest.approx(2 * math.sqrt(50))
    np.testing.assert_allclose(sp.points, [[0, 0], [5, 5], [0, 10]])
    assert not sp.points.flags.writeable


def test_detour_around_a_cylinder_matches_the_tangent_arc_length():
    # circle robot r=0.3 around a cylinder r=0.7 at the middle of the way: a disc of radius 1
    s = scenario(CylinderObstacle("pillar", 0, 5, 0.7), footprint=CIRCLE)
    exact = around_circle(5.0, 1.0)
    sp = shortest_path(s)
    assert exact <= sp.length <= exact + paths.INFLATION_TOLERANCE
    assert clearance(sp, s) >= 0.3 - 1e-3        # shapely's cylinder is a 64-gon


def test_detour_around_one_box_grows_it_by_half_the_robot_width():
    # 1 x 1 box on the way; box robot 0.9 x 0.5 -> the centre keeps 0.25 m from the box:
    # a rounded square of half side 0.5 with corner radius 0.25
    s = scenario(BoxObstacle("box", 0, 5, 1, 1))
    sp = shortest_path(s)
    # exact: tangent from (0,0) to the corner circle at (0.5, 4.5), arc, the 1 m side, mirrored
    cx, cy, rho = 0.5, 4.5, 0.25
    dist = math.hypot(cx, cy)
    tangent = math.sqrt(dist * dist - rho * rho)
    heading = math.atan2(cy, cx) - math.asin(rho / dist)      # direction of the tangent line
    arc = rho * (math.pi / 2 - heading)                          # turn until heading north
    exact = 2 * (tangent + arc) + 1.0
    assert exact <= sp.length <= exact + 2 * paths.INFLATION_TOLERANCE
    assert clearance(sp, s) == pytest.approx(0.25, abs=1e-9)
    assert abs(sp.points[:, 0]).max() == pytest.approx(0.75)


@pytest.mark.parametrize("gap, straight", [(2.0, True), (0.7, True), (0.45, False)])
def test_robot_drives_lengthwise_through_gaps_wider_than_itself(gap, straight):
    # two 1 x 1 boxes left and right of the way; the robot is 0.9 long and 0.5 wide
    half = gap / 2 + 0.5
    s = scenario(BoxObstacle("left", -half, 5, 1, 1), BoxObstacle("right", half, 5, 1, 1))
    sp = shortest_path(s)
    assert (sp.length == pytest.approx(10.0)) is straight
    assert clearance(sp, s) >= 0.25 - 1e-9


LEVELS = (0.05, 0.1, 0.15, 0.2, 0.3, 0.45, 0.6)


def pen(gap):
    """Walls round the start (0, 0), the one way out a gap ``gap`` wide in the north wall (y = 5)."""
    half = (6.0 - gap) / 2
    return [BoxObstacle("west", -3.1, 1.5, 0.2, 7.4), BoxObstacle("east", 3.1, 1.5, 0.2, 7.4),
            BoxObstacle("south", 0, -2.1, 6.4, 0.2),
            BoxObstacle("nw", -3 + half / 2, 5.1, half, 0.2), BoxObstacle("ne", 3 - half / 2, 5.1, half, 0.2)]


@pytest.mark.parametrize("gap, room", [(0.45, 0.0), (0.6, 0.05), (0.75, 0.1), (0.95, 0.2), (3.0, 0.6)])
def test_passage_room_is_what_the_narrowest_passage_leaves_the_robot(gap, room):
    """The only way out of a pen is a gap ``gap`` wide (the robot is 0.5 wide): the footprint
    could grow by (gap - 0.5) / 2 all round and still pass; the largest level within that is
    the room (none: 0.0)."""
    assert paths.passage_room(scenario(*pen(gap)), LEVELS) == room


def test_passage_room_leaves_out_a_box_crowding_the_start():
    """A box just beside the start is no passage (the robot turns away from it); a gap further
    on still is."""
    beside = BoxObstacle("beside", 0.6, 0, 0.3, 0.3)            # 0.2 m from the footprint's side
    assert paths.passage_room(scenario(beside), LEVELS) == 0.6
    assert paths.passage_room(scenario(beside, *pen(0.6)), LEVELS) == 0.05


def test_a_closed_wall_leaves_no_path():
    ring = [BoxObstacle("n", 0, 12, 6, 0.2), BoxObstacle("s", 0, 8, 6, 0.2),
            BoxObstacle("e", 3, 10, 0.2, 4.2), BoxObstacle("w", -3, 10, 0.2, 4.2)]
    assert shortest_path(scenario(*ring)) is None
    assert not path_exists(scenario(*ring))
    assert path_exists(scenario(*ring[:3]))      # open on the west side


def test_a_goal_the_robot_cannot_stand_on_has_no_path():
    s = scenario(BoxObstacle("box", 0.4, 10, 1, 1))     # goal 0.1 m from the box: the 0.5 m wide robot overlaps it
    assert shortest_path(s) is None


def test_results_are_cached_on_the_layout():
    s = scenario(BoxObstacle("box", 0, 5, 1, 1))
    first = shortest_path(s)
    same_layout = scenario(BoxObstacle("box", 0, 5, 1, 1))
    assert shortest_path(same_layout) is first
    moved = scenario(BoxObstacle("box", 0.1, 5, 1, 1))
    assert shortest_path(moved).length != first.length


def _brute_force_length(s):
    """Shapely visibility graph over the same grown polygons, every pair of vertices, Dijkstra."""
    r = paths.inflation_radius(s.robot.footprint)
    polys = [Polygon(paths.inflated_polygon(o, r)) for o in s.obstacles]
    m = s.mission
    stops = [(m.start.x, m.start.y), *[(w.x, w.y) for w in m.waypoints], (m.goal.x, m.goal.y)]
    if any(p.contains(shapely.Point(stop)) for p in polys for stop in stops):
        return None
    nodes = stops + [tuple(v) for p in polys for v in p.exterior.coords[:-1]]
    adj = {i: [] for i in range(len(nodes))}
    for i in range(len(nodes)):
        for j in range(i + 1, len(nodes)):
            seg = LineString([nodes[i], nodes[j]])
            if not any(seg.relate_pattern(p, "T********") for p in polys):
                w = math.dist(nodes[i], nodes[j])
                adj[i].append((j, w))
                adj[j].append((i, w))
    total = 0.0
    for leg in range(len(stops) - 1):
        best, heap = {leg: 0.0}, [(0.0, leg)]
        while heap:
            d, u = heapq.heappop(heap)
            if u == leg + 1:
                break
            for v, w in adj[u]:
                if d + w < best.get(v, math.inf):
                    best[v] = d + w
                    heapq.heappush(heap, (d + w, v))
        if leg + 1 not in best:
            return None
        total += best[leg + 1]
    return total


def test_pruned_visibility_graph_matches_a_brute_force_one():
    rng = np.random.default_rng(4)
    found = 0
    for _ in range(6):
        obstacles = [BoxObstacle(f"b{i}", rng.uniform(-2, 2), rng.uniform(2, 8), rng.uniform(0.3, 3),
                                 rng.uniform(0.3, 1.5), rng.uniform(-180, 180)) for i in range(3)]
        obstacles.append(CylinderObstacle("c", rng.uniform(-2, 2), rng.uniform(2, 8), 0.5))
        s = scenario(*obstacles, waypoints=[(2.5, 5)])
        sp, expected = shortest_path(s), _brute_force_length(s)
        if expected is None:
            assert sp is None
            continue
        found += 1
        assert sp.length == pytest.approx(expected, abs=1e-9)
        assert clearance(sp, s) >= 0.25 - 1e-3
    assert found >= 3


def test_min_obstacle_gap():
    assert min_obstacle_gap(scenario()) == (math.inf, "", "")
    assert min_obstacle_gap(scenario(BoxObstacle("a", 0, 0, 1, 1))) == (math.inf, "", "")
    s = scenario(BoxObstacle("left", -1.5, 5, 1, 1), BoxObstacle("right", 1.5, 5, 1, 1),
                 CylinderObstacle("far", 0, 20, 0.5))
    assert min_obstacle_gap(s) == pytest.approx((2.0, "left", "right"))
    # a box turned 45 degrees: its corner points at the cylinder, sqrt(0.5) from its centre
    s = scenario(BoxObstacle("diamond", 0, 0, 1, 1, yaw=45), CylinderObstacle("pillar", 2, 0, 0.5))
    assert min_obstacle_gap(s)[0] == pytest.approx(2 - math.sqrt(0.5) - 0.5, abs=1e-12)
    overlapping = scenario(BoxObstacle("a", 0, 0, 2, 0.2), BoxObstacle("b", 0, 0, 0.2, 2))   # a cross
    assert min_obstacle_gap(overlapping) == (0.0, "a", "b")


def test_box_distances_agree_with_shapely():
    rng = np.random.default_rng(2)
    obstacles = [BoxObstacle(f"b{i}", *rng.uniform(-3, 3, 2), *rng.uniform(0.05, 3, 2), rng.uniform(-180, 180))
                 for i in range(12)]
    s = scenario(*obstacles)
    polys = obstacle_polygons(s)
    expected = min((polys[i].distance(polys[j]), i, j) for i in range(12) for j in range(i + 1, 12))
    gap, a, b = min_obstacle_gap(s)
    assert gap == pytest.approx(expected[0], abs=1e-12)
    assert (a, b) == (f"b{expected[1]}", f"b{expected[2]}")


def test_segment_visibility_agrees_with_shapely():
    # the batched separating-axis test (both rounds: > 64 segments) against shapely's relate
    rng = np.random.default_rng(8)
    obstacles = [BoxObstacle(f"b{i}", *rng.uniform(-4, 4, 2), *rng.uniform(0.2, 2, 2), rng.uniform(-180, 180))
                 for i in range(6)] + [CylinderObstacle(f"c{i}", *rng.uniform(-4, 4, 2), 0.4) for i in range(3)]
    g = grown.grow(obstacles, 0.25)
    polys = [Polygon(paths.inflated_polygon(o, 0.25)) for o in obstacles]
    vertices = np.concatenate([np.asarray(p.exterior.coords[:-1]) for p in polys])
    p = np.concatenate([rng.uniform(-5, 5, (150, 2)), vertices[rng.integers(len(vertices), size=100)]])
    q = np.concatenate([rng.uniform(-5, 5, (150, 2)), vertices[rng.integers(len(vertices), size=100)]])
    free = grown.segments_free(p, q, g)
    expected = [not any(LineString([a, b]).relate_pattern(poly, "T********") for poly in polys)
                for a, b in zip(p, q)]
    assert free.tolist() == expected
    assert 20 < free.sum() < len(free) - 20


def _random_layout(rng, n):
    """Boxes, cylinders and non-convex polygons in a 12 x 6 m field, overlapping at times (so
    some grown polygons' vertices lie inside others)."""
    from pytest_navscenario.scenario.obstacles import PolygonObstacle

    shapes = [((0, 0), (1, 0), (1, 1), (0.5, 0.3), (0, 1)), ((0, 0), (0.8, 0.1), (0.2, 0.9))]
    out = []
    for i in range(n):
        x, y, kind = rng.uniform(-1, 11), rng.uniform(-3, 3), rng.integers(3)
        if kind == 0:
            out.append(BoxObstacle(f"b{i}", x, y, rng.uniform(0.1, 1.5), rng.uniform(0.1, 1.5),
                                   rng.uniform(-180, 180)))
        elif kind == 1:
            out.append(CylinderObstacle(f"c{i}", x, y, rng.uniform(0.05, 0.6)))
        else:
            out.append(PolygonObstacle(f"p{i}", x, y, shapes[int(rng.integers(2))], yaw=rng.uniform(-180, 180)))
    return out


def test_a_graph_built_a_node_at_a_time_has_the_whole_builds_edges(monkeypatch):
    # the path search asks for a large graph's edges as it reaches a node; each list must be the
    # one the whole build gives, in the same order and with the same lengths bit for bit, or the
    # search would take other steps (and a tie another way) than before
    monkeypatch.setattr(visibility, "WHOLE_NODES", 0)        # every graph a node at a time
    rng = np.random.default_rng(7)
    compared = 0
    for n in (2, 6, 15, 40):
        for _ in range(3):
            obstacles = _random_layout(rng, n)
            g = grown.grow(obstacles, 0.25)
            stops = np.array([(0.0, 0.0), (5.0, rng.uniform(-2, 2)), (10.0, 0.0)])
            nodes, lazy = visibility.graph(stops, g)
            again, whole = visibility.graph(stops, g, whole=True)
            np.testing.assert_array_equal(nodes, again)
            for u in rng.permutation(len(nodes)).tolist():     # in any order, as a search asks
                assert lazy[u] == whole[u]
                compared += len(whole[u])
    assert compared > 1000


def test_buried_vertices_are_those_inside_another_grown_polygon(monkeypatch):
    monkeypatch.setattr(grown, "PAIRS_AT_ONCE", 500)    # many chunks of pairs
    rng = np.random.default_rng(11)
    buried_seen = 0
    for n in (1, 5, 30, 80):
        g = grown.grow(_random_layout(rng, n), 0.3)
        k, m = g.offsets.shape
        valid = np.arange(m)[None, :] < g.sizes[:, None]
        owner = np.broadcast_to(np.arange(k)[:, None], valid.shape)[valid]
        verts = g.verts[valid]
        every = grown.inside(verts, g)                 # every vertex against every polygon
        every[np.arange(len(verts)), owner] = False
        np.testing.assert_array_equal(grown.buried(verts, owner, g), every.any(axis=1))
        buried_seen += int(every.any(axis=1).sum())
    assert buried_seen > 50


def test_a_path_through_the_barn_worlds_209_cylinders():
    # a real world (BARN world 0, by others): the path is clear of every cylinder and the one
    # a search over the whole graph finds
    from pathlib import Path

    from pytest_navscenario.ros.world_import import sdf_obstacles

    world = sdf_obstacles(Path(__file__).resolve().parents[1] / "data" / "barn_world_0.world")
    assert len(world.obstacles) == 209
    s = scenario(*world.obstacles, footprint=Footprint(length=0.5, width=0.43), start=(-2.25, 3), goal=(-2.25, 13))
    sp = shortest_path(s)
    assert sp is not None and 10.0 <= sp.length <= 10.5
    assert clearance(sp, s) >= 0.215 - 1e-3
    stops = np.array([(-2.25, 3.0), (-2.25, 13.0)])
    nodes, whole = visibility.graph(stops, grown.grow(world.obstacles, paths.inflation_radius(s.robot.footprint)),
                                whole=True)
    hops = visibility.astar(whole, nodes, 0, 1)
    np.testing.assert_array_equal(sp.points, nodes[hops])


def test_segments_among_many_polygons_are_judged_as_against_every_polygon(monkeypatch):
    # a crowded world's segments meet only the polygons near their extent, a bounded chunk at a
    # time; the answer must be the one every segment against every polygon gives
    rng = np.random.default_rng(3)
    g = grown.grow(_random_layout(rng, 120), 0.25)
    p = rng.uniform([-2, -4], [12, 4], size=(900, 2))
    q = p + rng.normal(0, 3, size=(900, 2))
    q[::7] = p[::7]                                   # some of no length
    monkeypatch.setattr(grown, "PAIRS_AT_ONCE", 5000)   # many chunks
    sparse = grown.segments_free(p, q, g)
    monkeypatch.setattr(grown, "DENSE_PAIRS", 10**9)
    every = grown.segments_free(p, q, g)
    np.testing.assert_array_equal(sparse, every)
    assert 100 < int(every.sum()) < 800               # both answers common
