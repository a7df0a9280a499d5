"""Loading a subject under test: a built-in planner name (``dwa``), ``package.module:Attribute``
(a class or a zero-argument factory returning a fresh planner; the harness calls it once per
episode) or ``exec:PROGRAM [ARGS]`` (an external process). Each is checked against the planner
protocol (see protocol.py) before any episode runs."""
from __future__ import annotations

import importlib
from typing import Any

from ..core.errors import SubjectLoadError
from ..core.interrupts import from_the_user
from .protocol import PlannerFactory


BUILTIN_SUBJECTS = {
    "dwa": "pytest_navscenario.subjects.planners.dwa:DynamicWindowPlanner",
    "potential-field": "pytest_navscenario.subjects.planners.potential_field:PotentialFieldPlanner",
}
DEFAULT_SUBJECT = "dwa"


def load_subject(spec: str, *, cwd: str | None = None) -> PlannerFactory:
    """Resolve ``package.module:Attribute``, a built-in name such as ``dwa``, or
    ``exec:PROGRAM [ARGS]`` (an external planner, see external.py; resolved and started in
    ``cwd`` when given) to a planner factory.

    Raises SubjectLoadError with what is wrong and how to fix it.
    """
    spec = spec.strip()
    if spec.startswith("exec:"):
        from .external import exec_factory
        return exec_factory(spec[len("exec:"):].strip(), cwd=cwd)
    target = BUILTIN_SUBJECTS.get(spec, spec)
    if ":" not in target:
        raise SubjectLoadError(
            f"subject {spec!r} is not of the form 'package.module:Attribute' "
            f"(built-in subjects: {', '.join(sorted(BUILTIN_SUBJECTS))})")
    module_name, _, attr_path = target.partition(":")
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # ImportError, or an error raised by the module's own code
        raise SubjectLoadError(
            f"subject {spec!r}: cannot import module {module_name!r}: {type(exc).__name__}: {exc} "
            f"(is it installed, or on sys.path / the rootdir?)") from exc
    obj: Any = module
    for part in attr_path.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            public = sorted(n for n in dir(module) if not n.startswith("_"))
            raise SubjectLoadError(
                f"subject {spec!r}: module {module_name!r} has no attribute {attr_path!r} "
                f"(it has: {', '.join(public[:20])})") from None
    if not callable(obj):
        raise SubjectLoadError(
            f"subject {spec!r}: {attr_path!r} is a {type(obj).__name__}, not a class or factory")
    return obj


def subject_identity(planner: Any, spec: str) -> tuple[str, str | None]:
    """(name, version) of a planner for reports: its ``name``/``version`` attributes or the spec."""
    name = getattr(planner, "name", None) or spec
    version = getattr(planner, "version", None)
    return str(name), (str(version) if version is not None else None)


def make_planner(planner: Any = None) -> tuple[Any, str]:
    """(planner instance, spec) from None (built-in default), a spec string, a class or factory,
    or a ready planner object. Raises SubjectLoadError in plain words."""
    if planner is None:
        planner = DEFAULT_SUBJECT
    if isinstance(planner, str):
        spec = planner
        factory = load_subject(spec)
    elif hasattr(planner, "act") and not isinstance(planner, type):
        return planner, _spec_of(planner)
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
    missing = [m for m in ("reset", "act") if not callable(getattr(instance, m, None))]
    if missing:
        raise SubjectLoadError(
            f"subject {spec!r}: the object it makes ({type(instance).__name__}) has no "
            f"{' and no '.join(m + '()' for m in missing)} method; a planner needs reset(scenario) "
            f"and act(observation) -> (vx, vy, wz) (see pytest_navscenario/planner.py)")
    return instance, spec


def _spec_of(obj: Any) -> str:
    cls = obj if isinstance(obj, type) or callable(obj) and not hasattr(obj, "act") else type(obj)
    module = getattr(cls, "__module__", None) or "?"
    name = getattr(cls, "__qualname__", None) or getattr(cls, "__name__", None) or type(cls).__name__
    return f"{module}:{name}"
