"""An ONNX policy in the batch engine (harness/batch.run_batch): one inference call a tick for the
batch, and every episode exactly as it runs alone; an episode that cannot feed the policy fails
alone. Skips until the batch engine is in this tree (the 'batch' branch of issue 27)."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("onnxruntime", reason="the ONNX tests need onnxruntime: pip install -e '.[onnx]'")
pytest.importorskip("onnx", reason="the ONNX tests build their models with onnx: pip install -e '.[dev]'")
pytest.importorskip("pytest_navscenario.harness.batch", reason="the batch engine (issue 27) is not in this tree")

from onnx_models import DECLARATION_24, mlp_model, random_mlp, write_policy  # noqa: E402

from pytest_navscenario import load_scenario, run_scenario  # noqa: E402
from pytest_navscenario.harness.batch import Batching, run_batch  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = sorted((ROOT / "scenarios").glob("*.yaml"))


def same(a, b) -> bool:
    ta, tb = a.trajectory, b.trajectory
    return (a.outcome == b.outcome and a.message == b.message
            and all(np.array_equal(getattr(ta, k), getattr(tb, k)) for k in ("t", "pose", "command", "ranges")))


def test_every_shipped_seed_in_one_batch_runs_as_it_runs_alone(tmp_path):
    path = str(write_policy(tmp_path, "mlp", mlp_model(random_mlp(24, [32, 32], 3, seed=4), final_tanh=True),
                            DECLARATION_24))
    scenarios = [load_scenario(p) for p in SHIPPED]
    how = Batching()
    batched = run_batch(scenarios, path, batch=len(scenarios), batching=how)
    assert how.batched + how.alone == len(scenarios) and how.batched >= 5, how.describe()
    for scenario, result in zip(scenarios, batched):
        alone = run_scenario(scenario, path)
        assert same(result, alone), (scenario.name, result.outcome, alone.outcome)
        assert (result.subject, result.subject_version) == ("mlp", alone.subject_version)


def test_an_episode_that_cannot_feed_the_policy_fails_alone_in_its_batch(tmp_path):
    path = str(write_policy(tmp_path, "mlp", mlp_model(random_mlp(24, [16], 3, seed=1)), DECLARATION_24))
    corridor = load_scenario(ROOT / "scenarios" / "corridor.yaml")
    narrow = dataclasses.replace(corridor, name="narrow", robot=dataclasses.replace(
        corridor.robot, lidar=dataclasses.replace(corridor.robot.lidar, fov=270.0)))
    scenarios = [corridor, narrow, load_scenario(ROOT / "scenarios" / "boxes1.yaml")]
    batched = run_batch(scenarios, path, batch=3)
    assert batched[1].outcome.value == "subject-error"
    assert "trained on a 360 degree lidar" in batched[1].message and "covers 270 degrees" in batched[1].message
    assert batched[1].message == run_scenario(narrow, path).message      # as it fails alone
    for i in (0, 2):
        assert same(batched[i], run_scenario(scenarios[i], path)), scenarios[i].name
