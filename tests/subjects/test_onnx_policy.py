"""ONNX policies as subjects (subjects/policies): real models built with the onnx package's graph
helpers, run by ONNX Runtime in the real simulation on the shipped seeds."""
from __future__ import annotations

import math
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("onnxruntime", reason="the ONNX tests need onnxruntime: pip install -e '.[onnx]'")
pytest.importorskip("onnx", reason="the ONNX tests build their models with onnx: pip install -e '.[dev]'")

from onnx_models import (DECLARATION_24, constant_model, linear_model, mlp_model,  # noqa: E402
                         random_mlp, write_policy)

from pytest_navscenario import load_scenario, run_scenario  # noqa: E402
from pytest_navscenario.core.errors import SubjectLoadError  # noqa: E402
from pytest_navscenario.subjects.loading import load_subject  # noqa: E402
from pytest_navscenario.subjects.policies import is_model_spec  # noqa: E402
from pytest_navscenario.subjects.policies import PolicyWarning  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SEEDS = ROOT / "scenarios"

UNIT_SCALE = DECLARATION_24.replace("scale: limits", "scale: 1.0").replace("  clip: [-1.0, 1.0]\n", "")


class Recorder:
    """Runs a planner and keeps every observation it saw and every command it answered."""

    def __init__(self, planner):
        self.planner, self.seen, self.answers = planner, [], []
        self.name, self.version = planner.name, planner.version

    def reset(self, scenario):
        self.planner.reset(scenario)

    def act(self, obs):
        answer = self.planner.act(obs)
        self.seen.append(obs)
        self.answers.append(answer)
        return answer


def recorded(path: Path, seed: str = "boxes1", **changes) -> Recorder:
    scenario = load_scenario(SEEDS / f"{seed}.yaml")
    if changes:
        import dataclasses
        scenario = dataclasses.replace(scenario, **changes)
    rec = Recorder(load_subject(str(path))())
    run_scenario(scenario, rec)
    return rec


# ------------------------------------------------------------------------------------ the spelling

@pytest.mark.parametrize("spec, model", [
    ("policy.onnx", True), ("models/policy.onnx", True), ("./policy.onnx", True), ("/abs/p.ONNX", True),
    ("C:\\models\\policy.onnx", True), ("onnx:load", False), ("mypkg.mod:Policy", False),
    ("mypkg:Exports.onnx", False),     # an attribute named onnx stays a Python spec
    ("./mypkg:Exports.onnx", True), ("dwa", False), ("exec:./run.onnx", False),
])
def test_a_model_is_named_by_its_path_and_never_taken_for_a_python_spec(spec, model):
    assert is_model_spec(spec) is model


# ------------------------------------------------------------------------------------ behaviour

def test_a_constant_policy_drives_a_shipped_seed_with_its_constant_command(tmp_path):
    path = write_policy(tmp_path, "still", constant_model([0.3, -0.1, 0.2], 24), UNIT_SCALE)
    rec = recorded(path, "corridor")
    assert len(rec.answers) > 20
    assert all(a == pytest.approx((0.3, -0.1, 0.2), abs=1e-7) for a in rec.answers)
    assert rec.name == "still" and rec.version.startswith("sha256:")


def _features(obs, previous) -> np.ndarray:
    """DECLARATION_24's input row, computed here independently (plain loops): 16 beams over 360
    degrees, each the minimum of the scenario's beams within half a beam spacing (22.5/2 degrees),
    clipped to [0, 4] and divided by 4; the target's distance (clipped to [0, 10]) and bearing;
    the velocity; the previous command."""
    beams = []
    for k in range(16):
        centre = -math.pi + 2 * math.pi * k / 16
        near = [float(r) for r, a in zip(obs.ranges, obs.angles)
                if abs((a - centre + math.pi) % (2 * math.pi) - math.pi) <= math.pi / 16 + 1e-12]
        beams.append(min(max(min(near), 0.0), 4.0) / 4.0)
    x, y, yaw = obs.pose
    tx, ty = obs.target
    fx = math.cos(yaw) * (tx - x) + math.sin(yaw) * (ty - y)
    fy = -math.sin(yaw) * (tx - x) + math.cos(yaw) * (ty - y)
    return np.array(beams + [min(math.hypot(fx, fy), 10.0), max(-4.0, min(4.0, math.atan2(fy, fx)))]
                    + list(obs.velocity) + list(previous))


def test_a_linear_policy_answers_its_linear_function_of_the_declared_observation(tmp_path):
    rng = np.random.default_rng(7)
    w = rng.normal(0, 0.2, (24, 3)).astype(np.float32)
    b = rng.normal(0, 0.1, 3).astype(np.float32)
    path = write_policy(tmp_path, "linear", linear_model(w, b), UNIT_SCALE)
    rec = recorded(path, "boxes1")
    assert len(rec.seen) > 50
    previous = np.zeros(3)
    for obs, answer in zip(rec.seen, rec.answers):
        expected = _features(obs, previous).astype(np.float32).astype(np.float64) @ w.astype(np.float64) + b
        assert np.allclose(answer, expected, rtol=1e-5, atol=1e-5), (obs.tick, answer, expected)
        previous = np.array(answer)


def test_scale_limits_and_clip_turn_outputs_into_the_robots_speeds(tmp_path):
    path = write_policy(tmp_path, "sat", constant_model([5.0, -0.5, 0.25], 24), DECLARATION_24)
    rec = recorded(path, "corridor")
    limits = load_scenario(SEEDS / "corridor.yaml").robot.limits
    assert rec.answers[0] == pytest.approx((limits.max_speed, -0.5 * limits.max_lateral_speed,
                                            0.25 * math.radians(limits.max_yaw_rate)))


def test_a_differential_policy_answers_vx_and_wz(tmp_path):
    decl = textwrap.dedent("""\
        navscenario-policy: 1
        name: diff-policy
        version: "7"
        observation:
          - target: {form: cartesian}
          - velocity: {components: [vx, wz]}
        action: {components: [vx, wz]}
        """)
    w = np.zeros((4, 2))
    w[0, 0] = 0.5      # vx = x / 2
    w[1, 1] = 1.0      # wz = y
    path = write_policy(tmp_path, "diff", linear_model(w, np.zeros(2)), decl)
    rec = recorded(path, "boxes1")
    first = rec.seen[0]
    x, y, yaw = first.pose
    fx = math.cos(yaw) * (first.target[0] - x) + math.sin(yaw) * (first.target[1] - y)
    fy = -math.sin(yaw) * (first.target[0] - x) + math.cos(yaw) * (first.target[1] - y)
    assert rec.answers[0] == pytest.approx((fx / 2, 0.0, fy), rel=1e-6)
    assert (rec.name, rec.version) == ("diff-policy", "7")


def test_a_dynamic_batch_answers_a_batch_in_one_call_with_each_episodes_own_bits(tmp_path):
    layers = random_mlp(24, [32, 32], 3, seed=3)
    path = write_policy(tmp_path, "mlp", mlp_model(layers, final_tanh=True), DECLARATION_24)
    seeds = ["boxes1", "corridor", "L-corridor"]
    alone = [recorded(path, s) for s in seeds]
    scenarios = [load_scenario(SEEDS / f"{s}.yaml") for s in seeds]
    planner = load_subject(str(path))()
    calls = []
    session = planner.model.session
    real_run = session.run

    class Counting:         # counts the calls, runs the real session
        def run(self, *args, **kwargs):
            calls.append(args[1][planner.model.input_name].shape)
            return real_run(*args, **kwargs)
    planner.model.session = Counting()
    try:
        planner.reset_batch(scenarios)
        ticks = min(len(r.seen) for r in alone)
        for t in range(ticks):
            ids = [0, 1, 2] if t % 3 else [0, 2]      # gaps, as when an episode ended
            answers = planner.act_batch(ids, [alone[i].seen[t] for i in ids])
            if t % 3 == 0:                            # episode 1 skipped a tick: keep its previous command
                planner._episodes[1].previous = np.array(alone[1].answers[t])
            for i, answer in zip(ids, answers):
                assert answer == alone[i].answers[t], (t, i)       # the same bits as alone
    finally:
        planner.model.session = session
    assert len(calls) == ticks and {c[0] for c in calls} == {2, 3}


def test_a_fixed_batch_of_one_still_runs_a_batch_one_episode_at_a_time_and_says_so(tmp_path):
    layers = random_mlp(24, [16], 3, seed=5)
    dynamic = write_policy(tmp_path / "a", "mlp", mlp_model(layers), DECLARATION_24)
    fixed = write_policy(tmp_path / "b", "mlp", mlp_model(layers, batch=1), DECLARATION_24)
    with pytest.warns(PolicyWarning, match=r"fixed batch dimension \(\[1, 24\]\).*once per episode per tick"):
        planner = load_subject(str(fixed))()
    assert planner.model.fixed_batch == 1
    reference = recorded(dynamic, "boxes1")
    rec = recorded(fixed, "boxes1")
    assert rec.answers == reference.answers
    scenarios = [load_scenario(SEEDS / "boxes1.yaml")] * 3
    planner.reset_batch(scenarios)
    answers = planner.act_batch([0, 1, 2], [reference.seen[0]] * 3)
    assert answers == [reference.answers[0]] * 3


def test_a_model_without_a_batch_dimension_runs_once_per_episode(tmp_path):
    layers = random_mlp(24, [8], 3, seed=2)
    path = write_policy(tmp_path / "r1", "flat", mlp_model(layers, batch=None), DECLARATION_24)
    reference = recorded(write_policy(tmp_path / "r2", "flat", mlp_model(layers), DECLARATION_24), "corridor")
    with pytest.warns(PolicyWarning, match=r"\[24\]"):
        rec = recorded(path, "corridor")
    assert rec.answers == reference.answers


def test_the_declaration_may_live_in_the_models_metadata(tmp_path):
    path = write_policy(tmp_path, "meta", constant_model([0.2, 0, 0], 24, metadata={
        "navscenario.policy": UNIT_SCALE}), None)
    rec = recorded(path, "corridor")
    assert rec.answers[0] == pytest.approx((0.2, 0.0, 0.0))


def test_the_same_model_file_is_loaded_once_per_process(tmp_path):
    path = write_policy(tmp_path, "once", constant_model([0.2, 0, 0], 24), UNIT_SCALE)
    assert load_subject(str(path))().model is load_subject(str(path))().model


# ------------------------------------------------------------------------------------ errors

def load_error(path, match: str) -> str:
    with pytest.raises(SubjectLoadError) as info:
        load_subject(str(path))
    text = str(info.value)
    assert any(m in text for m in [match]), text
    return text


def test_an_input_of_the_wrong_width_names_both_shapes_and_the_declared_fields(tmp_path):
    path = write_policy(tmp_path, "wide", constant_model([0, 0, 0], 30), DECLARATION_24)
    text = load_error(path, "input 'obs' has shape [batch, 30]")
    assert "24 values: lidar (16 beams) 16 + target (polar: distance, bearing) 2 + velocity (vx, vy, wz) 3 " \
           "+ previous_command (vx, vy, wz) 3" in text
    assert "should take [batch, 24]" in text


def test_an_output_of_the_wrong_width_names_both_shapes(tmp_path):
    path = write_policy(tmp_path, "two", constant_model([0, 0], 24), DECLARATION_24)
    text = load_error(path, "output 'action' has shape [batch, 2]")
    assert "action has 3 values (vx, vy, wz)" in text and "should answer [batch, 3]" in text


def test_a_missing_model_says_where_it_looked(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    text = load_error("models/gone.onnx", "no such model file")
    assert str(tmp_path / "models" / "gone.onnx") in text


def test_a_file_that_is_not_a_model_is_refused_at_load(tmp_path):
    (tmp_path / "junk.onnx").write_bytes(b"version https://git-lfs.github.com/spec/v1\noid sha256:00\n")
    (tmp_path / "junk.policy.yaml").write_text(DECLARATION_24)
    load_error(tmp_path / "junk.onnx", "ONNX Runtime cannot load")


def test_a_model_without_a_declaration_points_at_the_template_command(tmp_path):
    path = write_policy(tmp_path, "bare", constant_model([0, 0, 0], 24), None)
    text = load_error(path, "no policy declaration")
    assert str(tmp_path / "bare.policy.yaml") in text and "navscenario policy-template" in text


@pytest.mark.parametrize("change, where", [
    (("beams: 16", "beam: 16"), "bad.policy.yaml:3: observation[0].lidar: unknown key 'beam' (fix: did you mean 'beams'?)"),
    (("beams: 16", "beams: 16.5"), "bad.policy.yaml:3: observation[0].lidar.beams: expected a whole number"),
    (("form: polar", "form: polr"), "bad.policy.yaml:4: observation[1].target.form: 'polr' is not one of polar, "
                                    "cartesian (fix: did you mean 'polar'?)"),
    (("std: 4.0", "std: 0"), "bad.policy.yaml:3: observation[0].lidar.std: must be > 0"),
    (("components: [vx, vy, wz]\n  clip", "components: [vx, vz]\n  clip"),
     "bad.policy.yaml:8: action.components[1]: 'vz' is not one of vx, vy, wz"),
    (("navscenario-policy: 1", "navscenario-policy: 2"), "bad.policy.yaml:1: navscenario-policy: format version 2"),
    (("  - velocity", "  -velocity"), "bad.policy.yaml:"),
    # a name or version is printed in headers, results and JUnit: one line (it went into them with its line break)
    (("navscenario-policy: 1", 'navscenario-policy: 1\nname: "ppo\\nv2"'),
     "bad.policy.yaml:2: name: must be one line without tabs (fix: remove the line breaks)"),
    (("navscenario-policy: 1", "navscenario-policy: 1\nversion: " + "9" * 201),
     "bad.policy.yaml:2: version: is 201 characters long, more than 200"),
])
def test_a_wrong_declaration_names_file_line_and_field(tmp_path, change, where):
    path = write_policy(tmp_path, "bad", constant_model([0, 0, 0], 24), DECLARATION_24.replace(*change))
    text = load_error(path, "bad.policy.yaml")
    assert where in text, text


def test_a_yaml_bomb_as_the_declaration_is_refused_with_a_hint_about_declarations(tmp_path):
    lines = ["navscenario-policy: 1", 'a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 10)]
    path = write_policy(tmp_path, "bomb", constant_model([0, 0, 0], 24), "\n".join(lines) + "\nobservation: *a9\n")
    text = load_error(path, "alias bomb")
    assert "scenario" not in text and "policy declarations need far fewer values" in text, text
    path = write_policy(tmp_path, "deep", constant_model([0, 0, 0], 24),
                        "navscenario-policy: 1\nobservation: " + "[" * 1000 + "]" * 1000 + "\n")
    text = load_error(path, "nests more than 20 levels")
    assert "scenario" not in text and "this file is not a policy declaration" in text, text


def test_a_declaration_of_a_huge_observation_is_refused_before_anything_that_wide_is_made(tmp_path):
    """3000 lidar fields of 100000 beams (3e8 values) over a model of symbolic width asked numpy for
    2.24 GiB at load (issue 38): the declaration is refused at the field that crosses the limit."""
    import time
    fields = "".join("  - lidar: {beams: 100000, fov: 360, clip: [0.0, 4.0], std: 4.0}\n" for _ in range(3000))
    decl = "navscenario-policy: 1\nobservation:\n" + fields + "action:\n  components: [vx, vy, wz]\n"
    path = write_policy(tmp_path, "huge", constant_model([0, 0, 0], 24), decl)
    t0 = time.monotonic()
    text = load_error(path, "huge.policy.yaml:4: observation[1].lidar: brings the observation to 200000 values, "
                            "more than the limit of 100000")
    assert time.monotonic() - t0 < 10 and "fix: " in text
    many = "".join("  - velocity: {components: [vx]}\n" for _ in range(1001))
    path = write_policy(tmp_path, "many", constant_model([0, 0, 0], 24),
                        "navscenario-policy: 1\nobservation:\n" + many + "action:\n  components: [vx, vy, wz]\n")
    load_error(path, "more than 1000 fields")


def test_a_number_written_with_an_exponent_is_a_number_as_in_scenario_files(tmp_path):
    from pytest_navscenario.subjects.policies.declaration import read_declaration
    decl = DECLARATION_24.replace("scale: limits", "scale: 2e-1").replace("std: 4.0", "std: 4e0")
    path = tmp_path / "e.policy.yaml"
    path.write_text(decl)
    read = read_declaration(path.read_text(), str(path))
    assert read.action.scale == (0.2, 0.2, 0.2)
    assert read.observation[0].std[0] == 4.0


def test_file_and_metadata_declarations_that_differ_are_refused(tmp_path):
    path = write_policy(tmp_path, "two", constant_model([0, 0, 0], 24, metadata={
        "navscenario.policy": UNIT_SCALE}), DECLARATION_24)
    load_error(path, "declares a different observation or action")


def test_nan_outputs_end_the_episode_as_a_subject_error(tmp_path):
    path = write_policy(tmp_path, "nan", constant_model([0.1, float("nan"), 0.0], 24), UNIT_SCALE)
    result = run_scenario(load_scenario(SEEDS / "corridor.yaml"), str(path))
    assert result.outcome == "subject-error" and "non-finite command" in result.message, result.message
    assert "tick 0" in result.message


def test_a_scenario_with_a_narrower_lidar_is_that_episodes_subject_error(tmp_path):
    import dataclasses
    path = write_policy(tmp_path, "wide", constant_model([0.1, 0, 0], 24), UNIT_SCALE)
    scenario = load_scenario(SEEDS / "corridor.yaml")
    robot = dataclasses.replace(scenario.robot, lidar=dataclasses.replace(scenario.robot.lidar, fov=270.0))
    result = run_scenario(dataclasses.replace(scenario, robot=robot), str(path))
    assert result.outcome == "subject-error"
    assert "trained on a 360 degree lidar" in result.message and "covers 270 degrees" in result.message


def test_without_onnxruntime_the_error_names_the_extra(tmp_path):
    path = write_policy(tmp_path, "p", constant_model([0, 0, 0], 24), DECLARATION_24)
    code = ("import sys; sys.modules['onnxruntime'] = None\n"     # as if it were not installed
            "from pytest_navscenario.subjects.loading import load_subject\n"
            f"load_subject({str(path)!r})\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 1
    assert "needs ONNX Runtime, which is not installed" in out.stderr
    assert "pip install 'pytest-navscenario[onnx]'" in out.stderr


def test_a_shape_that_only_shows_when_run_is_found_at_load(tmp_path):
    """Output declared [batch, 3] but computed [1, 3] whatever the batch: the trial run finds it."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    nodes = [helper.make_node("ReduceMean", ["obs", "axes"], ["m"], keepdims=1),
             helper.make_node("Gemm", ["m", "W", "B"], ["action"])]
    inits = [numpy_helper.from_array(np.array([0], dtype=np.int64), "axes"),
             numpy_helper.from_array(np.zeros((24, 3), dtype=np.float32), "W"),
             numpy_helper.from_array(np.zeros(3, dtype=np.float32), "B")]
    graph = helper.make_graph(nodes, "odd", [helper.make_tensor_value_info("obs", TensorProto.FLOAT, ["batch", 24])],
                              [helper.make_tensor_value_info("action", TensorProto.FLOAT, ["batch", 3])], inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)])
    model.ir_version = 8
    path = write_policy(tmp_path, "odd", model.SerializeToString(), DECLARATION_24)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        load_error(path, "for input rows of shape [2, 24] the model answered shape [1, 3]")


# ------------------------------------------------------------------------------------ the template

def test_the_template_command_writes_a_declaration_that_fits_the_model(tmp_path, capsys):
    from pytest_navscenario.cli.main import main
    from pytest_navscenario.subjects.policies.declaration import read_declaration

    path = write_policy(tmp_path, "ppo", mlp_model(random_mlp(72, [16], 2)), None)
    assert main(["policy-template", str(path)]) == 0
    written = tmp_path / "ppo.policy.yaml"
    assert f"wrote {written}" in capsys.readouterr().out
    decl = read_declaration(written.read_text(), str(written))
    assert decl.width == 72 and [f.kind for f in decl.observation] == ["lidar", "target", "velocity",
                                                                        "previous_command"]
    assert decl.action.components == (0, 2) and decl.input == "obs" and decl.name == "ppo"
    assert recorded(path, "corridor").answers           # the model runs with it as written
    assert main(["policy-template", str(path)]) == 2    # not overwritten
    assert "exists already: not overwritten (--force overwrites it" in capsys.readouterr().err
    assert main(["policy-template", str(path), "--print"]) == 0
    assert capsys.readouterr().out == written.read_text()


def test_the_template_refuses_a_model_whose_output_is_not_a_command(tmp_path, capsys):
    from pytest_navscenario.cli.main import main

    path = write_policy(tmp_path, "five", mlp_model(random_mlp(20, [4], 5)), None)
    assert main(["policy-template", str(path)]) == 2
    assert "has shape [batch, 5]: 5 values, but a command is 3 (vx, vy, wz) or 2 (vx, wz) values" in \
        capsys.readouterr().err


# ------------------------------------------------------------------------------------ hostile models

def _with_last_node(model: bytes, node_type: str, out_shape: list, elem: int | None = None, **attrs) -> bytes:
    """``model`` with one more node after its output ``action`` (its inputs: the output, then the
    initializers given as numpy arrays in ``attrs['inits']``), whose result is the new output."""
    import onnx
    from onnx import helper, numpy_helper

    m = onnx.load_from_string(model)
    inits = attrs.pop("inits", {})
    for name, value in inits.items():
        m.graph.initializer.append(numpy_helper.from_array(value, name))
    old = m.graph.output[0]
    m.graph.node.append(helper.make_node(node_type, [old.name, *inits], ["answer"], **attrs))
    elem = old.type.tensor_type.elem_type if elem is None else elem
    m.graph.output.remove(old)
    m.graph.output.append(helper.make_tensor_value_info("answer", elem, out_shape))
    return m.SerializeToString()


def test_a_model_answering_fewer_rows_than_its_batch_ends_those_episodes_saying_both_shapes(tmp_path):
    # it passes the 2-row trial at load (it answers the first 2 rows); a batch of 3 got "act_batch raised
    # ValueError: cannot reshape array of size 9 into shape (2,3)" from our own code
    from pytest_navscenario.harness.batch import run_batch

    model = _with_last_node(constant_model([0.1, 0, 0], 24), "Slice", ["n", 3], inits={
        "s0": np.array([0]), "s2": np.array([2]), "ax": np.array([0])})
    path = write_policy(tmp_path, "two", model, UNIT_SCALE)
    scenarios = [load_scenario(SEEDS / f"{s}.yaml") for s in ("boxes1", "corridor", "L-corridor")]
    results = run_batch(scenarios, str(path), batch=3)
    for r in results:
        assert r.outcome == "subject-error", r
        assert ("the model answered shape [2, 3] for 3 input rows of 24 values: one row of 3 values per "
                "input row is needed") in r.message, r.message
        assert "ValueError" not in r.message and "reshape" not in r.message


def test_an_output_that_is_not_floats_is_refused_at_load(tmp_path):
    # an int64 output (a discrete action's index, say) was read as velocities: tanh's outputs cast to 0,
    # the robot stood still to its timeout; a string output was parsed as numbers
    from onnx import TensorProto

    for elem, name in ((TensorProto.INT64, "tensor(int64)"), (TensorProto.STRING, "tensor(string)")):
        model = _with_last_node(constant_model([0.1, 0, 0], 24), "Cast", ["batch", 3], elem, to=elem)
        path = write_policy(tmp_path / str(elem), "ints", model, UNIT_SCALE)
        text = load_error(path, f"output 'answer' is of type {name}")
        assert "navscenario reads the action as floats" in text


@pytest.mark.parametrize("fifo", ["nav.onnx", "nav.policy.yaml"])
def test_a_named_pipe_as_the_model_or_its_declaration_is_an_error_not_a_hang(tmp_path, fifo):
    import os
    if not hasattr(os, "mkfifo"):
        pytest.skip("named pipes are POSIX")
    write_policy(tmp_path, "nav", constant_model([0, 0, 0], 24), UNIT_SCALE)
    (tmp_path / fifo).unlink()
    os.mkfifo(tmp_path / fifo)
    code = ("import sys\nfrom pytest_navscenario.subjects.loading import load_subject\n"
            "try:\n    load_subject(sys.argv[1])\nexcept Exception as e:\n    print(type(e).__name__, e)\n")
    try:
        done = subprocess.run([sys.executable, "-c", code, str(tmp_path / "nav.onnx")], capture_output=True,
                              text=True, timeout=30)
    except subprocess.TimeoutExpired:
        pytest.fail(f"loading the policy hung on the named pipe {fifo}")
    finally:
        (tmp_path / fifo).unlink()
    assert f"{tmp_path / fifo} is not a regular file" in done.stdout, done.stdout + done.stderr
