"""Learned policies as subjects: a model file (ONNX) plus a small declaration of the observation
it was trained on and the action it answers, run as a planner (and as a batch planner: one
inference call per tick for a whole batch of episodes).

How a subject spec names a model file (``is_model_spec``): it ends in ``.onnx`` and is neither of
the form ``package.module:Attribute`` nor an ``exec:`` command (``models/nav.onnx``, ``./nav.onnx``, ``nav.onnx``,
``/abs/nav.onnx``). A prefix such as ``onnx:`` was not used because ``onnx`` is a real package, so
``onnx:policy.onnx`` is also a valid ``package.module:Attribute`` (attribute ``policy.onnx`` of
the ``onnx`` package): which one was meant would depend on what is installed. A file suffix can
only collide with a Python spec whose last attribute is named ``onnx`` (``pkg:Obj.onnx``), and
such a spec stays a Python spec; a model file with that very name is reached as ``./pkg:Obj.onnx``.

Read first: ``declaration.py`` (the YAML beside the model: what each field means), then
``features.py`` (observations to the model's input rows, its output rows to commands) and
``onnx_policy.py`` (loading, shape checks, the planner). ``template.py`` writes a declaration to
start from for a given model (``navscenario policy-template``).
"""
from __future__ import annotations

import re

MODEL_SUFFIXES = (".onnx",)


class PolicyWarning(UserWarning):
    """Something about a learned policy the user should know (e.g. a fixed batch of one); pytest
    shows it as a note in its header instead."""

# `package.module:Attribute` exactly as core/user_code reads it: dotted identifiers on both sides
_PYTHON_SPEC = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*:[A-Za-z_]\w*(\.[A-Za-z_]\w*)*$")


def is_model_spec(spec: str) -> bool:
    """True if the subject spec ``spec`` names a model file (see the module docstring)."""
    text = spec.strip()
    return (text.lower().endswith(MODEL_SUFFIXES) and not _PYTHON_SPEC.match(text)
            and not text.startswith("exec:"))
