"""A moving obstacle faster than the physics step can follow is refused when the scenario loads
(issue 26, item 8): a box crossing the robot at 100 m/s moved 1 m per step and passed through it
unseen (an episode that "succeeded" with 0.15 m clearance). Every speed the loader accepts is
seen: crossings at the limit, in any phase and at any offset that overlaps, are collisions."""
from __future__ import annotations

import pytest

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.scenario.loader import load_scenario, loads_scenario, max_resolved_speed
from pytest_navscenario.sim.episode import simulate


class Still:
    """Stands where it starts: whatever hits it is the mover's doing."""

    def reset(self, scenario):
        pass

    def act(self, obs):
        return (0.0, 0.0, 0.0)


def crossing(speed: float, *, x: float = 0.0, y: float = -3.0, timestep: float = 0.01, shape: str = "box",
             footprint: str = "{shape: box, length: 0.9, width: 0.5}") -> str:
    obstacle = ("{type: box, name: crate, length: 0.4, width: 0.4" if shape == "box"
                else "{type: cylinder, name: drum, radius: 0.2")
    return (f"version: 1\nrobot: {{footprint: {footprint}, safety: {{enabled: false}}}}\n"
            f"mission: {{start: {{x: 0, y: 0}}, goal: {{x: 6, y: 0}}, timeout: 2}}\n"
            f"obstacles:\n  - {obstacle}, x: {x}, y: {y}, motion: {{velocity: [0, {speed}]}}}}\n"
            f"simulation: {{timestep: {timestep}, control_rate: 10}}\n")


def test_a_box_at_100_m_s_is_refused_with_file_line_field_and_a_timestep_that_follows_it(tmp_path):
    path = tmp_path / "fast.yaml"
    path.write_text(crossing(100.0))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    text = str(err.value)
    assert err.value.line == 5 and "obstacles[0].motion.velocity" in text, text
    assert "100 m/s is faster than the simulation can follow at a timestep of 0.01 s" in text
    assert "'crate' would move 1 m per physics step" in text and "at most 16.9 m/s" in text
    assert "give simulation.timestep: 0.0015625 (64 steps per control tick)" in text
    # the suggested timestep loads, and there the crossing is the collision it is
    result = simulate(loads_scenario(crossing(100.0, timestep=0.0015625)), Still(), seed=0)
    assert result.end == "collision" and result.collision.obstacle == "crate"


@pytest.mark.parametrize("shape, footprint", [
    ("box", "{shape: box, length: 0.9, width: 0.5}"),
    ("cylinder", "{shape: circle, radius: 0.3}"),
])
def test_every_accepted_speed_is_seen_crossing_the_robot(shape, footprint):
    limit = max_resolved_speed(loads_scenario(crossing(1.0, shape=shape, footprint=footprint)),
                               loads_scenario(crossing(1.0, shape=shape, footprint=footprint)).obstacles[0])
    reach = 0.45 + 0.2 if shape == "box" else 0.3 + 0.2      # centre offsets that still overlap
    for speed in (0.5 * limit, 0.999 * limit):
        for phase in (0.0, 0.37, 0.81):                      # where the steps fall along the crossing
            for offset in (0.0, 0.5 * reach, 0.9 * reach):    # head on, and glancing
                sc = loads_scenario(crossing(speed, x=offset, y=-3.0 - phase * speed * 0.01, shape=shape,
                                             footprint=footprint))
                result = simulate(sc, Still(), seed=0)
                assert result.end == "collision", (shape, speed, phase, offset, result.end)


def test_the_limit_follows_the_timestep_the_sizes_and_the_robots_speed():
    sc = loads_scenario(crossing(1.0))
    box = sc.obstacles[0]
    assert max_resolved_speed(sc, box) == pytest.approx(0.2 * (0.4 + 0.5) / 0.01 - (1.0 ** 2 + 0.5 ** 2) ** 0.5)
    assert max_resolved_speed(sc, box, timestep=0.001) > 9 * max_resolved_speed(sc, box)
    person = loads_scenario("version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 6, y: 0}, timeout: 20}\n"
                            "obstacles: [{type: person, motion: {path: [[3, -4], [3, 4]]}}]\n")
    assert max_resolved_speed(person, person.obstacles[0]) > 15      # people walk at 1.3 m/s
