"""Fixtures for Python tests: ``nav_run`` (run a scenario, get the EpisodeResult) and ``nav_subject``.

Example::

    import pytest

    @pytest.mark.parametrize("gap", [1.2, 1.0, 0.8])
    def test_doorway(nav_run, gap):
        result = nav_run("scenarios/corridor.yaml",
                         obstacles=lambda obs: shift_walls(obs, gap),      # callable: old -> new
                         simulation=lambda s: dataclasses.replace(s, seed=3))
        assert result.outcome.value == "success"
        assert result.metrics.min_clearance > 0.05
"""
from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import pytest

from .state import get_state

if TYPE_CHECKING:
    from ..subjects.resolve import Subject


@pytest.fixture
def nav_subject(request: pytest.FixtureRequest) -> "Subject":
    """The session's subject under test (``.spec``, ``.label``, ``.factory``, ``.new()``)."""
    return get_state(request.config).subject


def _find(path: Path, request: pytest.FixtureRequest) -> Path:
    if path.is_absolute() or path.exists():
        return path
    for base in (Path(request.path).parent, Path(request.config.rootpath)):
        if (base / path).exists():
            return base / path
    raise FileNotFoundError(
        f"nav_run: no scenario file {str(path)!r} (looked in the current folder, "
        f"{Path(request.path).parent} and the rootdir {request.config.rootpath})")


def apply_overrides(scenario: Any, overrides: dict[str, Any]) -> Any:
    """dataclasses.replace on top-level Scenario fields; a callable value maps old -> new."""
    if not overrides:
        return scenario
    names = {f.name for f in dataclasses.fields(scenario)}
    unknown = sorted(set(overrides) - names)
    if unknown:
        raise TypeError(f"nav_run: Scenario has no field(s) {', '.join(unknown)} "
                        f"(top-level fields: {', '.join(sorted(names))})")
    changes = {k: (v(getattr(scenario, k)) if callable(v) else v) for k, v in overrides.items()}
    return dataclasses.replace(scenario, **changes)


@pytest.fixture
def nav_run(request: pytest.FixtureRequest) -> Callable[..., Any]:
    """``nav_run(scenario_or_path, planner=None, *, seed=None, **overrides) -> EpisodeResult``.

    ``scenario_or_path``: a Scenario or a YAML file (relative paths: the current folder, then
    the test file's folder, then the rootdir). ``planner``: None for the session's subject
    (``--nav-subject``), or a spec string, class/factory or planner instance. ``seed``: the base
    seed (default: the session's ``--nav-seed``); the per-tick limit is ``--nav-tick-limit``. ``overrides``: top-level Scenario fields to
    replace, e.g. ``obstacles=()``, or callables mapping the old value to the new one.
    Returns the EpisodeResult whatever the outcome: the test makes its own assertions.
    """
    state = get_state(request.config)

    def run(scenario_or_path: Any, planner: Any = None, *, seed: int | None = None,
            **overrides: Any) -> Any:
        from ..harness.runner import run_scenario

        scenario = scenario_or_path
        if isinstance(scenario, (str, os.PathLike)):
            from ..scenario.loader import load_scenario
            scenario = load_scenario(_find(Path(scenario), request))
        scenario = apply_overrides(scenario, overrides)
        subject = state.subject.runner_arg if planner is None else planner
        if isinstance(planner, str):   # looked up like --nav-subject: sys.path, then the rootdir
            from ..subjects.loading import locate_subject
            locate_subject(planner, state.subject.project)
        return run_scenario(scenario, subject, seed=state.settings.seed if seed is None else seed,
                            tick_limit=state.settings.tick_limit,
                            reset_timeout=state.settings.reset_timeout)

    return run
