"""Issue 26 items 3 and 6: a seed's ``search:`` section is checked when the seed loads (plain runs
too), every range and count has a documented limit, and the search space never leaves what the
loader accepts (so every frozen failure loads again)."""
from __future__ import annotations

import textwrap

import pytest
from hypothesis import HealthCheck, given, settings

from pytest_navscenario import ScenarioError, dump_scenario, load_scenario, loads_scenario
from pytest_navscenario.scenario.search_keys import RANGES, SEARCH
from pytest_navscenario.search.space import SearchSpace, invalid_reason, offsets_strategy

PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none"]
SEED = textwrap.dedent("""\
    version: 1
    mission:
      start: {x: 0, y: 0, yaw: 90}
      goal: {x: 0, y: 10, yaw: 90}
    obstacles:
      - {type: box, name: crate, x: 1.5, y: 5, length: 1, width: 1}
      - {type: person, name: walker, motion: {path: [[-3, 7], [3, 7]]}}
    search:
    """)


@pytest.mark.parametrize("setting, field, message", [
    ("motion_speed: [0.5, -0.5]", "search.motion_speed", "inverted bounds [0.5, -0.5]"),
    ("obstacle_dx: 10000000", "search.obstacle_dx", "beyond the supported magnitude"),
    ("obstacle_dx: 5000", "search.obstacle_dx", "5000 m is more than the limit of 1000 m"),
    ("obstacle_dy: [-2000, 1]", "search.obstacle_dy", "reach beyond the limit of 1000 m"),
    ("drift_per_metre: [0, 27]", "search.drift_per_metre", "reach beyond the limit of 10"),
    ("lidar_spurious: 2", "search.lidar_spurious", "more than the limit of 1"),
    ("insert: 100000000", "search.insert", "must be between 0 and 100"),
    ("remove: 7", "search.remove", "the seed has 2 obstacle(s)"),
    ("insert_size: [0.5, 500]", "search.insert_size", "more than the limit of 100 m"),
    ("insert_margin: 1e9", "search.insert_margin", "beyond the supported magnitude"),
    ("frozen: [crat]", "search.frozen[0]", "'crat' is not an obstacle, terrain element or mission part"),
    ("obstacle_yw: 5", "search.obstacle_yw", "did you mean 'obstacle_yaw'"),
    ("motion_start: [1, 5]", "search.motion_start", "do not contain 0"),
])
def test_bad_search_settings_fail_when_the_seed_loads(tmp_path, setting, field, message):
    path = tmp_path / "seed.yaml"
    path.write_text(SEED + f"  {setting}\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    err = info.value
    assert (err.path, err.line, err.field) == (str(path), 9, field), str(err)
    assert message in str(err) and err.hint


def test_every_search_key_has_a_documented_upper_limit():
    for key in SEARCH.keys:
        limit = getattr(key, "limit", None) or getattr(key, "le", None) or getattr(key, "max", None)
        assert limit and limit < float("inf"), key.name


def test_a_plain_run_refuses_a_seed_with_an_inverted_range(pytester, monkeypatch):
    """Not only under --navsearch: ``pytest scenarios`` reports the seed's mistake."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    (pytester.path / "s").mkdir()
    (pytester.path / "s" / "seed.yaml").write_text(SEED + "  motion_speed: [0.5, -0.5]\n")
    result = pytester.runpytest(*PLUGIN, "-q", "s")
    assert result.ret != 0
    assert "seed.yaml:9: search.motion_speed: inverted bounds [0.5, -0.5]" in result.stdout.str()


FAR = textwrap.dedent("""\
    version: 1
    robot:
      lidar: {noise_per_metre: 0.9, spurious: 0.8}
      localisation: {drift_per_metre: 9.5, drift_per_second: 0.1, yaw_drift_per_metre: 80}
    mission:
      start: {x: 999990, y: 0, yaw: 90}
      goal: {x: 999990, y: 10, yaw: 90}
      waypoints: [{x: 999990, y: 5}]
    obstacles:
      - {type: box, name: crate, x: 999992, y: 5, length: 1, width: 1}
      - {type: cylinder, name: post, radius: 0.3, motion: {path: [[999988, 3], [999988, 8]], speed: 0.2}}
    search:
      obstacle_dx: 1000
      obstacle_size: [-100, 100]
      motion_speed: [-100, 100]
      motion_start: [-3600, 3600]
      lidar_noise_per_metre: 1
      lidar_spurious: 1
      drift_per_metre: [0, 10]
      drift_per_second: [0, 10]
      yaw_drift_per_metre: [0, 90]
      waypoint_dx: 3
      insert: 1
    """)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(offsets_strategy(SearchSpace(loads_scenario(FAR, "far.yaml"))))
def test_the_search_never_writes_a_scenario_the_loader_refuses(offsets):
    """A seed at the edges of every range (1e6 m out, drifts near their maximum) with ranges at
    their limits: every candidate either loads again as written, or the search's validity check
    discards it before it is simulated (and so before it could be frozen)."""
    space = SearchSpace(loads_scenario(FAR, "far.yaml"))
    candidate = space.apply(offsets)
    try:
        back = loads_scenario(dump_scenario(candidate), "far-candidate.yaml")
    except ScenarioError as exc:
        assert invalid_reason(candidate) is not None, f"simulated and frozen, but the loader says: {exc}"
    else:
        assert back == candidate


def test_fault_offsets_stay_within_what_the_loader_allows():
    """The issue's case: drift_per_metre 5 plus an offset up to 10 was 15 (the search allowed 90,
    the loader 10), and the frozen file failed to load."""
    seed = loads_scenario(FAR.replace("drift_per_metre: 9.5", "drift_per_metre: 5"), "far.yaml")
    space = SearchSpace(seed, {"insert": 0})
    top = space.apply(tuple(p.hi for p in space.params))
    assert top.robot.localisation.drift_per_metre == 10.0
    assert top.robot.localisation.yaw_drift_per_metre == 90.0 and top.robot.lidar.spurious == 1.0
    assert top.obstacle("crate").x == 1e6       # 999992 + 1000, kept within the magnitude bound


def test_a_waypoint_covered_by_a_moved_obstacle_is_invalid_not_simulated():
    """The loader refuses a waypoint inside an obstacle; the search discards such a candidate."""
    seed = loads_scenario(FAR, "far.yaml")
    space = SearchSpace(seed, {"insert": 0})
    offsets = [0.0] * len(space)
    offsets[space.index["obstacles.crate.dx"]] = -2.0      # the crate onto the waypoint (999990, 5)
    candidate = space.apply(offsets)
    with pytest.raises(ScenarioError, match="waypoint 0"):
        loads_scenario(dump_scenario(candidate))
    assert invalid_reason(candidate) == "loader-refuses:mission.waypoints[0]"


def test_range_limits_are_the_targets_limits_for_faults():
    by_name = {key.name: key for key in RANGES}
    assert by_name["drift_per_metre"].limit == 10.0 and by_name["yaw_drift_per_metre"].limit == 90.0
    assert by_name["lidar_dropout_at_max"].limit == 1.0


def test_a_sped_up_obstacle_stays_as_fast_as_the_physics_step_can_follow():
    """The loader refuses an obstacle faster than the step can follow (issue 26.8): a candidate the
    search speeds up is kept at that speed, so it is simulated and loads again when frozen."""
    from pytest_navscenario.scenario.loader import max_resolved_speed
    seed = loads_scenario(SEED + "  motion_speed: [-1, 100]\n  insert: 0\n", "seed.yaml")
    space = SearchSpace(seed)
    offsets = [0.0] * len(space)
    offsets[space.index["obstacles.walker.motion.speed"]] = 100.0
    candidate = space.apply(offsets)
    walker = candidate.obstacle("walker")
    assert walker.motion.speed <= max_resolved_speed(candidate, walker) and walker.motion.speed > 10
    assert loads_scenario(dump_scenario(candidate)).obstacle("walker").motion.speed == walker.motion.speed
    assert invalid_reason(candidate) is None
