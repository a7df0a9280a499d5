"""An ONNX policy under pytest with one option, ``--nav-subject=models/nav.onnx``: the shipped
scenarios (serial and on two workers) and a failure search, in real pytest runs (pytester)."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("onnxruntime", reason="the ONNX tests need onnxruntime: pip install -e '.[onnx]'")
pytest.importorskip("onnx", reason="the ONNX tests build their models with onnx: pip install -e '.[dev]'")

from onnx_models import DECLARATION_24, linear_model, write_policy  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
PLUGIN = ("-p", "pytest_navscenario.plugin", "-p", "no:randomly")


def goal_seeker() -> bytes:
    """vx proportional to the target's distance, wz to its bearing: drives at its goal, blind."""
    w = np.zeros((24, 3), dtype=np.float32)
    w[16, 0] = 0.5
    w[17, 2] = 1.5
    return linear_model(w, np.zeros(3, dtype=np.float32))


@pytest.fixture
def project(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    shutil.copytree(ROOT / "scenarios", pytester.path / "scenarios")
    write_policy(pytester.path / "models", "nav", goal_seeker(), DECLARATION_24)
    pytester.makeini("[pytest]\nnav_scenario_paths = scenarios\n")
    return pytester


def records(path: Path) -> list[dict]:
    return [r for r in map(json.loads, path.read_text().splitlines()) if r.get("record", "episode") == "episode"]


@pytest.mark.parametrize("workers", [[], pytest.param(["-p", "xdist.plugin", "-n", "2"], marks=pytest.mark.heavy)],
                         ids=["serial", "n2"])
def test_the_shipped_scenarios_run_against_an_onnx_policy_with_one_option(project, workers):
    result = project.runpytest_subprocess(*PLUGIN, *workers, "--nav-subject=models/nav.onnx",
                                          "--nav-results=results.jsonl", "scenarios")
    text = result.stdout.str()
    assert "models/nav.onnx" in text, text
    episodes = [r for r in records(project.path / "results.jsonl") if "outcome" in r]
    shipped = sorted(p.stem for p in (ROOT / "scenarios").glob("*.yaml"))
    assert sorted(r["scenario"] for r in episodes) == shipped, text
    assert {(r["subject"], r["subject_version"][:7]) for r in episodes} == {("nav", "sha256:")}
    outcomes = {r["scenario"]: r["outcome"] for r in episodes}
    assert outcomes["corridor"] == "success"            # a straight corridor: a blind goal-seeker passes
    assert "subject-error" not in outcomes.values(), outcomes


def test_a_search_runs_against_an_onnx_policy_with_one_option(project):
    result = project.runpytest_subprocess(*PLUGIN, "--nav-subject=models/nav.onnx", "--navsearch", "boxes1",
                                          "--budget", "6", "--navsearch-seed", "1",
                                          "--navsearch-shrink-budget", "4")
    text = result.stdout.str()
    assert result.ret in (0, 1), text
    result.stdout.fnmatch_lines(["*navsearch summary*", "boxes1 vs models/nav.onnx sha256:* 6/6 sims*"])


def test_a_model_named_in_the_ini_is_found_in_the_rootdir_from_a_subfolder(project):
    """pytest started in a subfolder: the ini's relative path is looked up in the rootdir too, and
    every episode (and the reproduce line) gets the path that was found."""
    project.makeini("[pytest]\nnav_scenario_paths = scenarios\nnav_subject = models/nav.onnx\n")
    out = subprocess.run([sys.executable, "-m", "pytest", *PLUGIN, "corridor.yaml", "boxes2.yaml"],
                         cwd=project.path / "scenarios", capture_output=True, text=True,
                         env={**os.environ, "PYTEST_DISABLE_PLUGIN_AUTOLOAD": "1"})
    text = out.stdout + out.stderr
    model = project.path / "models" / "nav.onnx"
    assert f"subject {model} (ini nav_subject)" in text, text
    assert "1 failed, 1 passed" in text, text                 # boxes2 is a safety stop, as from the rootdir
    assert f"--nav-subject={model}" in text, text


def test_a_model_with_a_fixed_batch_of_one_says_so_in_the_header(project):
    from onnx_models import mlp_model, random_mlp

    write_policy(project.path / "models", "fixed", mlp_model(random_mlp(24, [8], 3), batch=1), DECLARATION_24)
    result = project.runpytest_subprocess(*PLUGIN, "--nav-subject=models/fixed.onnx", "scenarios/corridor.yaml")
    result.stdout.fnmatch_lines([
        "navscenario: subject note: models/fixed.onnx: the model's input 'obs' has a fixed batch dimension "
        "([[]1, 24]), so it is called once per episode per tick, not once per tick for a whole batch; export it "
        "with a dynamic batch dimension*"])
    assert "PolicyWarning" not in result.stdout.str() + result.stderr.str()    # said once, in the header
