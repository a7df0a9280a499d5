"""An ONNX model as a planner: loaded with ONNX Runtime (the optional extra ``onnx``), checked
against its declaration (declaration.py), and run with one inference call per tick for every
episode of a batch (the batch protocol, subjects/protocol.py), or for the one episode run alone.

A model whose batch dimension is dynamic (``["batch", 72]``) takes the whole batch in one call.
One with a fixed batch of ``b`` is called on slices of ``b`` rows (the last padded with zeros,
their outputs dropped): with ``b`` = 1, once per episode per tick; a ``PolicyWarning`` says so
when the model is loaded. ONNX Runtime runs on one thread (intra- and inter-op), so a policy
uses the core its episode runs on and answers the same bits every time.
"""
from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from typing import Any, Iterable, Sequence

from ...core.errors import SubjectLoadError
from ...scenario.model import Scenario
from . import PolicyWarning
from .declaration import COMPONENTS, Declaration, declaration_path, find_declaration, model_digest

EXTRA_HINT = "pip install 'pytest-navscenario[onnx]' (or: pip install onnxruntime)"
_FLOAT_TYPES = {"tensor(float)": "float32", "tensor(double)": "float64", "tensor(float16)": "float16"}


def import_onnxruntime(spec: str) -> Any:
    """The onnxruntime module, or SubjectLoadError naming the extra to install."""
    try:
        import onnxruntime
    except ImportError as exc:
        raise SubjectLoadError(
            f"subject {spec!r} is an ONNX model, and running one needs ONNX Runtime, which is not "
            f"installed ({exc}): {EXTRA_HINT}") from None
    return onnxruntime


def locate_model(spec: str, *, cwd: str | None = None, project: Iterable[str | os.PathLike] = ()) -> str:
    """The absolute path of the model a spec names: an absolute path as it is, a relative one in
    ``cwd`` (the current folder when None), then in each ``project`` folder (pytest's rootdir, as
    for a ``package.module:Attribute`` subject's module). SubjectLoadError when it is in none."""
    places = model_places(spec, cwd=cwd, project=project)
    for place in places:
        if os.path.isdir(place):
            raise SubjectLoadError(f"subject {spec!r}: {place} is a folder, not an ONNX model file")
        if os.path.exists(place) and not os.path.isfile(place):   # reading a named pipe would wait forever
            raise SubjectLoadError(f"subject {spec!r}: {place} is not a regular file (a named pipe, socket or "
                                   f"device); name the ONNX model file itself")
        if os.path.exists(place):
            if not os.access(place, os.R_OK):
                raise SubjectLoadError(f"subject {spec!r}: cannot read the model file {place} "
                                       f"(permission denied: chmod +r it)")
            return os.path.abspath(place)
    looked = ", then ".join(dict.fromkeys(os.path.abspath(p) for p in places))
    raise SubjectLoadError(f"subject {spec!r}: no such model file (looked for {looked}); give its "
                           f"path relative to the folder you run in, or an absolute path")


def model_places(spec: str, *, cwd: str | None = None, project: Iterable[str | os.PathLike] = ()) -> list[str]:
    """Where a model spec is looked for, in order (see locate_model)."""
    path = os.path.expanduser(spec.strip())
    if os.path.isabs(path):
        return [path]
    return [os.path.join(cwd or os.getcwd(), path)] + [os.path.join(os.fspath(p), path) for p in project if p]


@dataclass
class LoadedModel:
    """A model ready to run: its session, the names fed and read, its declaration."""
    path: str
    session: Any
    input_name: str
    output_name: str
    decl: Declaration
    featurizer: Any
    fixed_batch: int | None           # None: a dynamic batch dimension
    batched_rank: bool                # the input has a batch dimension (rank 2), else rank 1
    name: str
    version: str
    notes: tuple[str, ...] = ()       # what the user should know (shown in pytest's header)

    def infer(self, rows: Any) -> Any:
        """The model's output rows for input rows (n, width): one call when the batch dimension is
        dynamic, else slices of the fixed batch (padded with zeros)."""
        import numpy as np

        run = self.session.run
        names = [self.output_name]
        n = len(rows)
        if self.fixed_batch is None:
            return run(names, {self.input_name: rows})[0]
        b = self.fixed_batch
        if not self.batched_rank:
            return np.stack([run(names, {self.input_name: rows[k]})[0] for k in range(n)])
        parts = []
        for start in range(0, n, b):
            part = rows[start:start + b]
            if len(part) < b:
                part = np.concatenate([part, np.zeros((b - len(part), rows.shape[1]), dtype=rows.dtype)])
            parts.append(run(names, {self.input_name: part})[0][:min(b, n - start)])
        return np.concatenate(parts)


_MODELS: dict[tuple, LoadedModel] = {}


def _stamp(path: str) -> tuple:
    try:
        st = os.stat(path)
    except OSError:
        return (path, None)
    return (path, st.st_mtime_ns, st.st_size)


def load_model(spec: str, path: str) -> LoadedModel:
    """The model at ``path`` with its declaration, loaded once per process (again when the model
    or its declaration file changes). SubjectLoadError (DeclarationError for the declaration) with
    what is wrong, the shapes, and how to fix it."""
    key = (_stamp(path), _stamp(declaration_path(path)))
    model = _MODELS.get(key)
    if model is None:
        model = _MODELS[key] = _load(spec, path)
    return model


def _load(spec: str, path: str) -> LoadedModel:
    """Open the model, find its declaration, check its input and output against it, run it once."""
    import numpy as np

    session = _session(spec, path)
    try:
        metadata = dict(session.get_modelmeta().custom_metadata_map or {})
    except Exception:
        metadata = {}
    decl = find_declaration(path, metadata)
    where = f"{spec!r} ({path}, declared in {decl.source})"
    inp = _the_input(session, decl, where)
    out = _the_output(session, decl, where)
    if out.type not in _FLOAT_TYPES:
        raise SubjectLoadError(f"subject {where}: output {out.name!r} is of type {out.type}; navscenario reads the "
                               f"action as floats (tensor(float), tensor(double) or tensor(float16)): a "
                               f"velocity command, not a discrete action's index (export the continuous action, "
                               f"or name it with 'output: NAME' in the declaration)")
    if inp.type not in _FLOAT_TYPES:
        raise SubjectLoadError(f"subject {where}: input {inp.name!r} is of type {inp.type}; navscenario "
                               f"feeds floats (tensor(float), tensor(double) or tensor(float16))")
    dtype = np.dtype(_FLOAT_TYPES[inp.type])
    shape, batched_rank, fixed = _check_shapes(inp, out, decl, where)
    from .features import Featurizer
    model = LoadedModel(path=path, session=session, input_name=inp.name, output_name=out.name, decl=decl,
                        featurizer=Featurizer(decl, dtype), fixed_batch=fixed, batched_rank=batched_rank,
                        name=decl.name or os.path.splitext(os.path.basename(path))[0],
                        version=decl.version or model_digest(path))
    _trial(model, where, decl.width, decl.action.width)
    if fixed is not None:
        how = "once per episode per tick" if fixed == 1 else f"on slices of {fixed} episodes"
        what = "has a fixed batch dimension" if batched_rank else "has no batch dimension"
        note = (f"{spec}: the model's input {inp.name!r} {what} ({shape_text(shape)}), so it is called {how}, "
                f"not once per tick for a whole batch; export it with a dynamic batch dimension (e.g. "
                f"torch.onnx.export(..., dynamic_axes={{'{inp.name}': {{0: 'batch'}}, '{out.name}': "
                f"{{0: 'batch'}}}})) to run a batch in one call")
        model.notes = (note,)
        warnings.warn(PolicyWarning(note), stacklevel=2)
    return model


def _session(spec: str, path: str) -> Any:
    """An ONNX Runtime session on the CPU, one thread, sequential (the same answers every run)."""
    ort = import_onnxruntime(spec)
    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    options.inter_op_num_threads = 1
    options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    options.log_severity_level = 3          # errors only: ours say what is wrong
    try:
        return ort.InferenceSession(path, options, providers=["CPUExecutionProvider"])
    except Exception as exc:
        raise SubjectLoadError(f"subject {spec!r}: ONNX Runtime cannot load {path}: {type(exc).__name__}: "
                               f"{str(exc).strip()} (is it an ONNX model file, whole and not a Git LFS "
                               f"pointer? re-export it)") from None


def _the_input(session: Any, decl: Any, where: str) -> Any:
    """The model's one input (the observation row), the declaration's if it names one."""
    inputs = {i.name: i for i in session.get_inputs()}
    if decl.input is not None and decl.input not in inputs:
        raise SubjectLoadError(f"subject {where}: the declaration's input {decl.input!r} is not an input of "
                               f"the model; its inputs: {_shapes(inputs.values())} (fix: input: in the "
                               f"declaration)")
    if len(inputs) != 1:
        raise SubjectLoadError(f"subject {where}: the model has {len(inputs)} inputs ({_shapes(inputs.values())}); "
                               f"navscenario feeds one, the observation row (export the policy with a single "
                               f"input; recurrent policies with a state input are not supported)")
    return next(iter(inputs.values()))


def _the_output(session: Any, decl: Any, where: str) -> Any:
    """The model's output that is the action: the declaration's, or its only one."""
    outputs = {o.name: o for o in session.get_outputs()}
    if decl.output is not None:
        if decl.output not in outputs:
            raise SubjectLoadError(f"subject {where}: the declaration's output {decl.output!r} is not an output "
                                   f"of the model; its outputs: {_shapes(outputs.values())} (fix: output: in "
                                   f"the declaration)")
        return outputs[decl.output]
    if len(outputs) != 1:
        raise SubjectLoadError(f"subject {where}: the model has {len(outputs)} outputs "
                               f"({_shapes(outputs.values())}); say which one is the action with "
                               f"'output: NAME' in the declaration")
    return next(iter(outputs.values()))


def _check_shapes(inp: Any, out: Any, decl: Any, where: str) -> tuple[list, bool, int | None]:
    """The input's and the output's shapes against the declaration's observation and action widths:
    (the input's shape, whether it has a batch dimension, its fixed batch size or None if dynamic)."""
    width = decl.width
    shape = list(inp.shape)
    if len(shape) not in (1, 2) or (isinstance(shape[-1], int) and shape[-1] != width):
        raise SubjectLoadError(
            f"subject {where}: input {inp.name!r} has shape {shape_text(shape)}, but the declaration's observation "
            f"has {width} values: {decl.layout()} (fix: declare the fields the policy was trained on, in "
            f"order, so that they add up to the model's input; the model should take [batch, {width}])")
    batched_rank = len(shape) == 2
    fixed = shape[0] if batched_rank and isinstance(shape[0], int) else (None if batched_rank else 1)
    if fixed is not None and fixed < 1:
        fixed = None
    n_out = decl.action.width
    out_shape = list(out.shape)
    if len(out_shape) != len(shape) or (isinstance(out_shape[-1], int) and out_shape[-1] != n_out):
        raise SubjectLoadError(
            f"subject {where}: output {out.name!r} has shape {shape_text(out_shape)}, but the declaration's action "
            f"has {n_out} values ({', '.join(COMPONENTS[c] for c in decl.action.components)}) (fix: "
            f"action.components in the declaration; the model should answer "
            f"{shape_text([shape[0], n_out] if batched_rank else [n_out])})")
    return shape, batched_rank, fixed


def _trial(model: LoadedModel, where: str, width: int, n_out: int) -> None:
    """Run the model once on zeros (two rows when the batch is dynamic), so that a model that
    fails or answers the wrong shape is found when it is loaded, not in every episode."""
    import numpy as np

    n = 2 if model.fixed_batch is None else 1
    rows = np.zeros((n, width), dtype=model.featurizer.dtype)
    try:
        if model.fixed_batch is None:
            got = model.session.run([model.output_name], {model.input_name: rows})[0]
        else:
            got = model.infer(rows)
    except Exception as exc:
        raise SubjectLoadError(f"subject {where}: running the model on a row of {width} zeros failed: "
                               f"{type(exc).__name__}: {str(exc).strip()}") from None
    got = np.asarray(got)
    if got.shape != (n, n_out):
        raise SubjectLoadError(
            f"subject {where}: for input rows of shape {shape_text([n, width])} the model answered shape "
            f"{shape_text(list(got.shape))}; the declaration's action needs {shape_text([n, n_out])}: one row of "
            f"{n_out} values per input row (fix: action.components, or export the model so that its "
            f"output follows the input's batch dimension)")


def shape_text(shape: Sequence[Any]) -> str:
    return "[" + ", ".join(str(d) if d is not None else "?" for d in shape) + "]"


def _shapes(infos: Iterable[Any]) -> str:
    return ", ".join(f"{i.name!r} {shape_text(i.shape)}" for i in infos)


class ModelOutputError(ValueError):
    """The model's output does not fit its batch (each episode of the batch gets it as its answer)."""


class OnnxPolicy:
    """A planner (and batch planner) running a loaded model: each tick, the observations become
    input rows (features.py), one inference call answers all of them, and the outputs become
    commands. ``name`` and ``version`` come from the declaration, else the model's file name and
    the digest of its bytes."""

    def __init__(self, model: LoadedModel):
        self.model = model
        self.name = model.name
        self.version = model.version
        self.notes = model.notes
        self._episodes: list[Any] = []

    def reset(self, scenario: Scenario) -> None:
        self.reset_batch([scenario])

    def act(self, obs: Any) -> tuple[float, float, float]:
        answer = self.act_batch((0,), (obs,))[0]
        if isinstance(answer, Exception):
            raise answer
        return answer

    def reset_batch(self, scenarios: Sequence[Scenario]) -> None:
        """Each episode's state; a scenario that cannot feed the policy (a narrower lidar) fails
        its own episode at its first tick, never the others of the batch."""
        from .features import ObservationMismatch

        start = self.model.featurizer.start
        episodes: list[Any] = []
        for scenario in scenarios:
            try:
                episodes.append(start(scenario))
            except ObservationMismatch as exc:
                episodes.append(exc)
        self._episodes = episodes

    def act_batch(self, ids: Sequence[int], observations: Sequence[Any]) -> list[Any]:
        """One command per id (a tuple), or for an episode whose scenario cannot feed the policy
        the exception saying why (the harness fails that episode alone)."""
        episodes = [self._episodes[i] for i in ids]
        bad = [k for k, ep in enumerate(episodes) if isinstance(ep, Exception)]
        if bad:
            answers: list[Any] = list(episodes)
            good = [k for k in range(len(episodes)) if k not in set(bad)]
            if good:
                done = self._commands([episodes[k] for k in good], [observations[k] for k in good])
                for k, command in zip(good, done):
                    answers[k] = command
            return answers
        return self._commands(episodes, observations)

    def _commands(self, episodes: Sequence[Any], observations: Sequence[Any]) -> list[tuple[float, float, float]]:
        """One inference call (or the fixed batch's slices) for these episodes' observations."""
        import numpy as np

        model = self.model
        rows = model.featurizer.rows(episodes, observations)
        outputs = np.asarray(model.infer(rows))
        wanted = (len(rows), model.decl.action.width)
        if outputs.shape != wanted:      # the load's trial (2 rows) cannot see every batch size
            wrong = ModelOutputError(
                f"the model answered shape {shape_text(list(outputs.shape))} for {len(rows)} input rows of "
                f"{rows.shape[1]} values: one row of {wanted[1]} values per input row is needed (fix: export "
                f"the model so that its output follows the input's batch dimension)")
            return [wrong] * len(episodes)
        return list(map(tuple, model.featurizer.commands(episodes, outputs).tolist()))


def onnx_factory(spec: str, *, cwd: str | None = None, project: Iterable[str | os.PathLike] = ()):
    """A planner factory for a model spec (``models/nav.onnx``): the model is found, loaded and
    checked now; every planner the factory makes shares it."""
    path = locate_model(spec, cwd=cwd, project=project)
    model = load_model(spec, path)

    def factory() -> OnnxPolicy:
        return OnnxPolicy(model)

    factory.__name__ = os.path.basename(path)
    factory.__qualname__ = spec.strip()
    return factory
