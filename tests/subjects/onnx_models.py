"""Small ONNX policies built with the ``onnx`` package's graph helpers (no downloaded weights), for
the tests and benchmarks/bench_onnx.py: a linear policy (one Gemm), a multilayer perceptron
(Gemm + Tanh layers), written beside a declaration as a user would keep them."""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

BATCH = "batch"     # a dynamic batch dimension


def mlp_model(layers: Sequence[tuple[np.ndarray, np.ndarray]], *, batch: int | str | None = BATCH,
              hidden_tanh: bool = True, final_tanh: bool = False, input_name: str = "obs",
              output_name: str = "action", dtype: type = np.float32, metadata: dict[str, str] | None = None,
              opset: int = 17) -> bytes:
    """The serialised model ``y = L_n(...tanh(L_1(x)))`` with ``L_k(x) = x @ W_k + b_k`` (Gemm),
    input ``[batch, in]`` (``batch`` None: a rank-1 input ``[in]``, no batch dimension)."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    elem = TensorProto.FLOAT if np.dtype(dtype) == np.float32 else TensorProto.DOUBLE
    nodes, inits = [], []
    x = input_name
    rank1 = batch is None
    if rank1:   # Gemm needs rank 2: [in] -> [1, in] -> ... -> [out]
        inits.append(numpy_helper.from_array(np.array([1, -1], dtype=np.int64), "to_row"))
        inits.append(numpy_helper.from_array(np.array([-1], dtype=np.int64), "to_flat"))
        nodes.append(helper.make_node("Reshape", [x, "to_row"], ["row"]))
        x = "row"
    for k, (w, b) in enumerate(layers):
        inits += [numpy_helper.from_array(np.asarray(w, dtype=dtype), f"W{k}"),
                  numpy_helper.from_array(np.asarray(b, dtype=dtype), f"B{k}")]
        last = k == len(layers) - 1
        out = output_name if last and not final_tanh and not rank1 else f"h{k}"
        nodes.append(helper.make_node("Gemm", [x, f"W{k}", f"B{k}"], [out]))
        x = out
        if (hidden_tanh and not last) or (last and final_tanh):
            out = output_name if last and not rank1 else f"t{k}"
            nodes.append(helper.make_node("Tanh", [x], [out]))
            x = out
    if rank1:
        nodes.append(helper.make_node("Reshape", [x, "to_flat"], [output_name]))
    n_in, n_out = np.shape(layers[0][0])[0], np.shape(layers[-1][0])[1]
    in_shape = [n_in] if rank1 else [batch, n_in]
    out_shape = [n_out] if rank1 else [batch, n_out]
    graph = helper.make_graph(nodes, "policy", [helper.make_tensor_value_info(input_name, elem, in_shape)],
                              [helper.make_tensor_value_info(output_name, elem, out_shape)], inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", opset)], producer_name="tests")
    model.ir_version = 8
    for key, value in (metadata or {}).items():
        entry = model.metadata_props.add()
        entry.key, entry.value = key, value
    onnx.checker.check_model(model)
    return model.SerializeToString()


def linear_model(w: np.ndarray, b: np.ndarray, **kwargs) -> bytes:
    """``y = x @ w + b``: one Gemm, no activation."""
    return mlp_model([(w, b)], **kwargs)


def constant_model(command: Sequence[float], width: int, **kwargs) -> bytes:
    """Answers ``command`` whatever it sees (zero weights, the command as the bias)."""
    return linear_model(np.zeros((width, len(command))), np.asarray(command, dtype=np.float64), **kwargs)


def random_mlp(width: int, hidden: Sequence[int], n_out: int, seed: int = 0) -> list[tuple[np.ndarray, np.ndarray]]:
    """Layers with Glorot-scaled random weights (a stand-in for trained ones)."""
    rng = np.random.default_rng(seed)
    sizes = [width, *hidden, n_out]
    return [(rng.standard_normal((a, b)) * np.sqrt(2.0 / (a + b)), rng.standard_normal(b) * 0.1)
            for a, b in zip(sizes[:-1], sizes[1:])]


def write_policy(folder: Path, name: str, model: bytes, declaration: str | None) -> Path:
    """``folder/name.onnx`` and, unless None, ``folder/name.policy.yaml``; the model's path."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.onnx"
    path.write_bytes(model)
    if declaration is not None:
        (folder / f"{name}.policy.yaml").write_text(declaration)
    return path


# The declaration most tests use: 16 beams over 360 degrees, the target (polar), the velocity and the
# previous command (vx, vy, wz): 16 + 2 + 3 + 3 = 24 inputs, 3 outputs.
DECLARATION_24 = """\
navscenario-policy: 1
observation:
  - lidar: {beams: 16, fov: 360, clip: [0.0, 4.0], std: 4.0}
  - target: {form: polar, clip: [[0.0, 10.0], [-4.0, 4.0]]}
  - velocity: {components: [vx, vy, wz]}
  - previous_command: {components: [vx, vy, wz]}
action:
  components: [vx, vy, wz]
  clip: [-1.0, 1.0]
  scale: limits
"""
