"""Loading a subject under test: a built-in planner name (``dwa``), ``package.module:Attribute``
(a class or a zero-argument factory returning a fresh planner; the harness calls it once per
episode), ``exec:PROGRAM [ARGS]`` (an external process) or a model file ``path/to/policy.onnx``
(a learned policy, see policies/). Each is checked against the planner protocol (see
protocol.py) before any episode runs."""
from __future__ import annotations

import os
from typing import Any, Iterable

from ..core.errors import SubjectLoadError
from ..core.user_code import load_object, look_in_project, spec_module
from ..core.interrupts import from_the_user
from .policies import is_model_spec
from .protocol import PlannerFactory, SingleFromBatch, is_batch_planner


BUILTIN_SUBJECTS = {
    "dwa": "pytest_navscenario.subjects.planners.dwa:DynamicWindowPlanner",
    "potential-field": "pytest_navscenario.subjects.planners.potential_field:PotentialFieldPlanner",
}
DEFAULT_SUBJECT = "dwa"


def load_subject(spec: str, *, cwd: str | None = None, project: Iterable[str | os.PathLike] = ()) -> PlannerFactory:
    """Resolve ``package.module:Attribute``, a built-in name such as ``dwa``,
    ``exec:PROGRAM [ARGS]`` (an external planner, see external.py; resolved and started in
    ``cwd`` when given) or a model file such as ``models/nav.onnx`` (policies/: found in ``cwd``,
    then in the ``project`` folders) to a planner factory. A module that is not on sys.path is
    also looked up in the ``project`` folders (pytest's rootdir, the CLI's current folder): see
    core/user_code.py for the order and which one wins.

    Raises SubjectLoadError with what is wrong and how to fix it.
    """
    spec = spec.strip()
    if spec.startswith("exec:"):
        from .external import exec_factory
        return exec_factory(spec[len("exec:"):].strip(), cwd=cwd)
    if is_model_spec(spec):
        from .policies.onnx_policy import onnx_factory
        return onnx_factory(spec, cwd=cwd, project=project)
    target = BUILTIN_SUBJECTS.get(spec, spec)
    if ":" not in target:
        raise SubjectLoadError(
            f"subject {spec!r} is not of the form 'package.module:Attribute' "
            f"(built-in subjects: {', '.join(sorted(BUILTIN_SUBJECTS))}; an external program: exec:PROGRAM; "
            f"a learned policy: the path of its .onnx file)")
    obj = load_object(target, what="subject", project=project)
    if not callable(obj):
        raise SubjectLoadError(
            f"subject {spec!r}: {target.partition(':')[2]!r} is a {type(obj).__name__}, not a class or factory")
    return obj


def locate_subject(spec: str | None, project: Iterable[str | os.PathLike]) -> None:
    """Make a ``package.module:Attribute`` subject importable from the ``project`` folders when
    sys.path does not have its module (core/user_code.look_in_project); nothing is imported.
    Called before worker processes start, so that they find it too."""
    if not spec:
        return
    module = spec_module(BUILTIN_SUBJECTS.get(spec.strip(), spec))
    if module is not None and not spec.strip().startswith("exec:") and not is_model_spec(spec):
        look_in_project(module, project)


def subject_identity(planner: Any, spec: str) -> tuple[str, str | None]:
    """(name, version) of a planner for reports: its ``name``/``version`` attributes or the spec."""
    name = getattr(planner, "name", None) or spec
    version = getattr(planner, "version", None)
    return str(name), (str(version) if version is not None else None)


def make_planner(planner: Any = None, *, project: Iterable[str | os.PathLike] = ()) -> tuple[Any, str]:
    """(planner instance, spec) from None (built-in default), a spec string, a class or factory,
    or a ready planner object (a spec's module also looked up in the ``project`` folders, see
    load_subject). Raises SubjectLoadError in plain words."""
    if planner is None:
        planner = DEFAULT_SUBJECT
    if isinstance(planner, str):
        spec = planner
        factory = load_subject(spec, project=project)
    elif (hasattr(planner, "act") or is_batch_planner(planner)) and not isinstance(planner, type):
        return _single(planner), _spec_of(planner)
    elif callable(planner):
        spec, factory = _spec_of(planner), planner
    else:
        raise SubjectLoadError(
            f"planner must be None, a 'package.module:Attribute' string, a class/factory or an object "
            f"with reset() and act(); got {type(planner).__name__} {planner!r:.60}")
    try:
        instance = factory()
    except (Exception, SystemExit, KeyboardInterrupt) as exc:
        if not isinstance(exc, Exception) and from_the_user(exc):   # a real Ctrl-C stops the run
            raise
        raise SubjectLoadError(f"subject {spec!r}: calling it to make a planner raised "
                               f"{type(exc).__name__}: {exc}") from exc
    instance = _single(instance)
    missing = [m for m in ("reset", "act") if not callable(getattr(instance, m, None))]
    if missing:
        raise SubjectLoadError(
            f"subject {spec!r}: the object it makes ({type(instance).__name__}) has no "
            f"{' and no '.join(m + '()' for m in missing)} method; a planner needs reset(scenario) "
            f"and act(observation) -> (vx, vy, wz), or the batch protocol's reset_batch(scenarios) "
            f"and act_batch(ids, observations) (see docs/reference/planner-protocol.md)")
    return instance, spec


def _single(planner: Any) -> Any:
    """``planner`` itself, or, for one with only the batch methods, the adapter that runs it alone."""
    if is_batch_planner(planner) and not (callable(getattr(planner, "reset", None))
                                          and callable(getattr(planner, "act", None))):
        return SingleFromBatch(planner)
    return planner


def _spec_of(obj: Any) -> str:
    cls = obj if isinstance(obj, type) or callable(obj) and not hasattr(obj, "act") else type(obj)
    module = getattr(cls, "__module__", None) or "?"
    name = getattr(cls, "__qualname__", None) or getattr(cls, "__name__", None) or type(cls).__name__
    return f"{module}:{name}"
