"""Episodes of layouts that only move or resize obstacles reuse each other's MjData and MjSpec
(issue 35): the search compiles a model per candidate, from the spec of the structure edited in
place, with a pooled MjData, and the model and the episode are the same bit for bit."""
from __future__ import annotations

import dataclasses

import numpy as np

from pytest_navscenario.harness.runner import run_scenario
from pytest_navscenario.scenario.loader import loads_scenario
from pytest_navscenario.sim.world import build_spec, clear_model_cache, compiled_world, layout_spec

YAML = """\
version: 1
name: two
mission:
  start: {x: 0.0, y: 0.0, yaw: 90.0}
  goal: {x: 0.0, y: 5.0, yaw: 90.0}
  timeout: 12.0
obstacles:
  - {type: box, name: crate, x: 0.9, y: 2.5, length: 0.6, width: 0.6}
  - {type: cylinder, name: post, x: -1.0, y: 3.5, radius: 0.2}
"""


def _moved(sc, dx, size):
    crate, post = sc.obstacles
    return dataclasses.replace(sc, obstacles=(dataclasses.replace(crate, x=crate.x + dx, length=size),
                                              dataclasses.replace(post, y=post.y - dx)))


def test_layouts_of_one_structure_share_their_mjdata_and_keep_their_bits():
    seed = loads_scenario(YAML, "two.yaml")
    a, b = _moved(seed, 0.3, 0.8), _moved(seed, -0.2, 0.5)
    clear_model_cache()
    assert compiled_world(a).free_data is compiled_world(b).free_data       # one pool for the structure
    assert compiled_world(a).model is not compiled_world(b).model
    run_scenario(a, "dwa")                     # leaves an MjData in the pool that b's episode takes
    reused = run_scenario(b, "dwa")
    clear_model_cache()
    fresh = run_scenario(b, "dwa")             # b's own model and a new MjData
    for name in ("t", "pose", "velocity", "command", "ranges"):
        assert np.array_equal(getattr(reused.trajectory, name), getattr(fresh.trajectory, name)), name
    assert reused.outcome == fresh.outcome and reused.metrics.as_dict() == fresh.metrics.as_dict()
    other = dataclasses.replace(seed, obstacles=seed.obstacles[:1])   # one obstacle fewer: another pool
    assert compiled_world(other).free_data is not compiled_world(a).free_data


def _arrays(model) -> dict:
    """Every array and number of an MjModel, its options and statistics, as bytes."""
    out = {}
    for owner, prefix in ((model, ""), (model.opt, "opt."), (model.stat, "stat.")):
        for name in dir(owner):
            value = getattr(owner, name, None) if not name.startswith("_") else None
            if isinstance(value, np.ndarray):
                out[prefix + name] = value.tobytes()
            elif isinstance(value, (int, float)):
                out[prefix + name] = value
    return out


def test_the_spec_edited_for_a_new_layout_compiles_to_the_model_of_a_new_spec():
    seed = loads_scenario(YAML, "two.yaml")
    clear_model_cache()
    layouts = [_moved(seed, dx, size) for dx, size in ((0.3, 0.8), (-0.2, 0.5), (0.3, 0.8), (0.05, 1.1))]
    turned = dataclasses.replace(seed, obstacles=(dataclasses.replace(seed.obstacles[0], yaw=33.0),
                                                  seed.obstacles[1]), name="turned")
    specs = set()
    for sc in [*layouts, turned]:
        spec = layout_spec(sc)
        specs.add(id(spec))
        fresh, edited = _arrays(build_spec(sc).compile()), _arrays(spec.compile())
        assert fresh.keys() == edited.keys()
        assert [k for k in fresh if fresh[k] != edited[k]] == []
    assert len(specs) == 1                      # one spec for the structure, edited for each layout
    assert _arrays(build_spec(layouts[0]).compile())["geom_size"] != _arrays(
        build_spec(layouts[1]).compile())["geom_size"]    # the layouts do differ
    renamed = dataclasses.replace(seed, obstacles=(dataclasses.replace(seed.obstacles[0], name="box"),
                                                   seed.obstacles[1]))
    assert id(layout_spec(renamed)) not in specs   # other geom names: a spec of its own
