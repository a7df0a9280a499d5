"""A declaration to start from, for a given model: ``navscenario policy-template nav.onnx`` writes
``nav.policy.yaml`` with every field explained, its input and output named, and a layout that adds
up to the model's input width (a guess that the user corrects to what the policy was trained on).
"""
from __future__ import annotations

import os
from typing import Any

from ...core.errors import SubjectLoadError
from .declaration import FORMAT_KEY, FORMAT_VERSION, declaration_path
from .onnx_policy import shape_text

ACTIONS = {3: "[vx, vy, wz]", 2: "[vx, wz]"}


def model_signature(path: str) -> tuple[Any, Any]:
    """(input, output) of the ONNX model at ``path`` as ONNX Runtime reads them (name, shape)."""
    from .onnx_policy import import_onnxruntime

    ort = import_onnxruntime(path)
    try:
        session = ort.InferenceSession(path, providers=["CPUExecutionProvider"])
    except Exception as exc:
        raise SubjectLoadError(f"ONNX Runtime cannot load {path}: {type(exc).__name__}: {str(exc).strip()}") from None
    inputs, outputs = session.get_inputs(), session.get_outputs()
    if len(inputs) != 1:
        names = ", ".join(f"{i.name!r} {shape_text(i.shape)}" for i in inputs)
        raise SubjectLoadError(f"{path}: the model has {len(inputs)} inputs ({names}); navscenario feeds one, "
                               f"the observation row: export the policy with a single input")
    return inputs[0], outputs[0]


def _layout(width: int | None, n_act: int) -> tuple[int, bool, bool]:
    """(lidar beams, with velocity, with previous command) adding up to ``width`` with a polar target."""
    if width is None:
        return 64, True, True
    rest = width - 2
    velocity = previous = False
    if rest - 2 * n_act >= 8:
        velocity = previous = True
        rest -= 2 * n_act
    elif rest - n_act >= 8:
        velocity = True
        rest -= n_act
    return rest, velocity, previous


def _c(code: str, comment: str) -> str:
    """A template line with its comment at column 32 (one space after longer code)."""
    return f"{code:<31} # {comment}" if len(code) < 31 else f"{code} # {comment}"


def template_text(path: str) -> str:
    """The declaration template for the model at ``path`` (see the module docstring)."""
    inp, out = model_signature(path)
    width = inp.shape[-1] if inp.shape and isinstance(inp.shape[-1], int) else None
    n_act = out.shape[-1] if out.shape and isinstance(out.shape[-1], int) else 3
    if n_act not in ACTIONS:
        raise SubjectLoadError(f"{path}: output {out.name!r} has shape {shape_text(out.shape)}: {n_act} values, but "
                               f"a command is 3 (vx, vy, wz) or 2 (vx, wz) values")
    comps = ACTIONS[n_act]
    beams, velocity, previous = _layout(width, n_act)
    if width is not None and beams < 1:
        raise SubjectLoadError(f"{path}: input {inp.name!r} has shape {shape_text(inp.shape)}: {width} values; write "
                               f"the declaration by hand (fields and widths: see docs/how-to/learned-policies.md)")
    name = os.path.splitext(os.path.basename(path))[0]
    total = f"{width}" if width is not None else "its"
    fields = [_c("  - lidar:", f"{beams} values: ranges (m), resampled from the scenario's lidar"),
              _c(f"      beams: {beams}", "beams the policy was trained on"),
              _c("      fov: 360", "degrees, centred on the heading (the scenario's lidar must cover it)"),
              _c("      resample: min", "min: the shortest range within each beam's sector; nearest: the nearest"),
              _c("      clip: [0.0, 5.0]", "m: ranges clipped to this (the training lidar's range)"),
              _c("      mean: 0.0", "then (value - mean) / std: a number, or one per value"),
              "      std: 5.0",
              _c("  - target:", "2 values: the next waypoint (else the goal) in the robot frame"),
              _c("      form: polar", "polar: distance (m), bearing (rad, left +); cartesian: x, y (m)"),
              _c("      clip: [[0.0, 10.0], [-3.1416, 3.1416]]", "one [low, high] per value, or one for all")]
    if velocity:
        fields += [_c("  - velocity:", f"{n_act} values: the measured velocity, robot frame (m/s, rad/s)"),
                   f"      components: {comps}"]
    if previous:
        fields += [_c("  - previous_command:", f"{n_act} values: what this policy answered last tick (zeros at "
                                                 f"the first)"),
                   f"      components: {comps}"]
    lines = [
        f"# What {os.path.basename(path)} was trained on: the observation it reads and the action it answers.",
        "# Written by `navscenario policy-template`: the layout below is a GUESS that adds up to the model's",
        f"# {total} inputs. Edit it to the fields, order and normalisation of your training environment",
        "# (docs/how-to/learned-policies.md), then run: navscenario check-planner " + path,
        f"{FORMAT_KEY}: {FORMAT_VERSION}",
        _c(f"name: {name}", "the subject's name in results (default: the model file's stem)"),
        _c("# version: ckpt-1200", "default: sha256 of the model file (its first 12 hex digits)"),
        _c(f"input: {inp.name}", f"the model's input {shape_text(inp.shape)}"),
        _c(f"output: {out.name}", f"the model's output {shape_text(out.shape)}: the action"),
        _c("observation:", "the input row: these fields, concatenated in this order"),
        *fields,
        _c("  # - goal: {form: polar}", "2 values: the final goal (not the next waypoint)"),
        "action:",
        _c(f"  components: {comps}", "the model's outputs, in order ([vx, wz] for a differential drive)"),
        _c("  clip: [-1.0, 1.0]", "the raw outputs clipped to this"),
        _c("  scale: limits", "then multiplied by the robot's limits (max_speed, max_lateral_speed,"),
        _c("", "max_yaw_rate in rad/s); or a number, or one number per component"),
    ]
    return "\n".join(lines) + "\n"


def write_template(path: str, *, force: bool = False) -> str:
    """Write the template beside the model; the path written. Refuses to overwrite unless ``force``."""
    from ...core.files import atomic_write_text

    target = declaration_path(path)
    if os.path.exists(target) and not force:
        raise SubjectLoadError(f"{target} exists already: not overwritten (--force overwrites it, or --print "
                               f"shows the template)")
    atomic_write_text(target, template_text(path))
    return target
