"""The subject under test for a pytest session: where it came from, its factory, its check.

Resolution order: the ``pytest_navscenario_make_subject`` hook (a conftest.py), then
``--nav-subject`` / ini ``nav_subject``, then the built-in default (planner.DEFAULT_SUBJECT).
"""
from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable

import pytest

from .loading import BUILTIN_SUBJECTS, DEFAULT_SUBJECT, load_subject, locate_subject


@dataclass
class Subject:
    """What the session tests. ``spec`` is the string a user passes to ``--nav-subject`` to get
    the same subject again (None when a conftest hook provides it); ``origin`` says where it was set."""
    spec: str | None
    origin: str                        # "--nav-subject", "ini nav_subject", "built-in default", "hook"
    _factory: Callable[[], Any] | None = field(default=None, repr=False)
    # folders a 'package.module:Attribute' spec's module is also looked up in (the rootdir)
    project: tuple[str, ...] = ()
    # what loading it said the user should know (a planner's ``notes``), for pytest's header
    notes: tuple[str, ...] = ()
    _batches: bool | None = field(default=None, repr=False)   # answers the batch protocol (check())

    @property
    def label(self) -> str:
        if self.spec is None:
            return f"{getattr(self._factory, '__qualname__', repr(self._factory))} (from the " \
                   f"pytest_navscenario_make_subject hook)"
        if self.origin == "built-in default":
            return f"{self.spec} (built-in default; set --nav-subject or ini nav_subject)"
        kind = "built-in" if self.spec in BUILTIN_SUBJECTS else self.origin
        return f"{self.spec} ({kind})"

    @property
    def factory(self) -> Callable[[], Any]:
        """The zero-argument planner factory (loaded on first use). Raises SubjectLoadError."""
        if self._factory is None:
            self._factory = load_subject(self.spec or DEFAULT_SUBJECT, project=self.project)
        return self._factory

    @property
    def runner_arg(self) -> Any:
        """What to pass to run_scenario: the spec string when there is one (so results name the
        subject as the user wrote it, e.g. "dwa"), else the hook's factory."""
        return self.spec if self.spec is not None else self.factory

    def new(self) -> Any:
        """A fresh planner instance."""
        return self.factory()

    def locate(self) -> None:
        """Make the spec's module importable from the project folders when sys.path does not have
        it (nothing is imported): before any worker process starts, as workers copy sys.path."""
        locate_subject(self.spec, self.project)

    def check(self, keep_running: bool = True) -> None:
        """Load the subject and make one planner; SubjectLoadError if it breaks the protocol.
        An external (exec:) planner's program is started, so one that cannot start is found now;
        ``keep_running`` leaves it up for this process's episodes (False when workers run them)."""
        from .external import check_start
        from .loading import make_planner
        with warnings.catch_warnings():   # a PolicyWarning is kept as a note, shown in the header
            warnings.simplefilter("ignore", _policy_warning())
            planner, _ = make_planner(self.runner_arg, project=self.project)
        self.notes = tuple(str(n) for n in getattr(planner, "notes", None) or ())
        self._batches = _answers_batches(planner)
        check_start(planner, keep_running)

    def answers_batches(self) -> bool:
        """True if its planners answer the batch protocol (subjects/protocol.py): known from
        ``check``, or from the class a spec names (nothing is made); True for a model file (an
        ONNX policy answers it), False for an ``exec:`` program and for a subject this process
        cannot load (the nodes of a Ray cluster may)."""
        if self._batches is None:
            from .policies import is_model_spec
            if self.spec is not None and self.spec.strip().startswith("exec:"):
                self._batches = False
            elif self.spec is not None and is_model_spec(self.spec):
                self._batches = True           # an ONNX policy always answers it (policies/)
            else:
                try:
                    factory = self.factory
                except Exception:
                    return False
                self._batches = isinstance(factory, type) and _answers_batches(factory)
        return self._batches


def _policy_warning() -> type[Warning]:
    from .policies import PolicyWarning
    return PolicyWarning


def _answers_batches(planner: Any) -> bool:
    from .protocol import SingleFromBatch, is_batch_planner
    return is_batch_planner(planner.planner if isinstance(planner, SingleFromBatch) else planner)


def _model_path(spec: str, project: tuple[str, ...]) -> str:
    """A model spec found only in the rootdir becomes its absolute path, so that every process and
    every command that re-runs it (workers, reproduce lines) finds it; any other spec is kept."""
    from .policies import is_model_spec

    if not is_model_spec(spec):
        return spec
    from .policies.onnx_policy import model_places

    places = model_places(spec, project=project)
    if os.path.exists(places[0]):
        return spec
    return next((os.path.abspath(p) for p in places[1:] if os.path.exists(p)), spec)


def resolve_subject(config: pytest.Config, spec: str | None, origin: str) -> Subject:
    """Ask the hook first, then use ``spec`` (from option/ini), else the built-in default. A
    spec's module is looked up on sys.path, then in the rootdir (core/user_code.py)."""
    project = (str(config.rootpath),)
    try:
        provided = config.hook.pytest_navscenario_make_subject(config=config)
    except Exception as exc:
        raise pytest.UsageError(f"navscenario: the pytest_navscenario_make_subject hook raised "
                                f"{type(exc).__name__}: {exc}") from exc
    if provided is not None:
        if isinstance(provided, str):
            return Subject(spec=provided.strip(), origin="pytest_navscenario_make_subject hook", project=project)
        if not callable(provided):
            raise pytest.UsageError(
                f"pytest_navscenario_make_subject returned {type(provided).__name__} {provided!r}; "
                f"return a zero-argument factory or class, a 'package.module:Attribute' string, or None")
        return Subject(spec=None, origin="hook", _factory=provided)
    if spec:
        return Subject(spec=_model_path(spec.strip(), project), origin=origin, project=project)
    return Subject(spec=DEFAULT_SUBJECT, origin="built-in default", project=project)
