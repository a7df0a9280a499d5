"""Per-session state of the core plugin, kept in ``config.stash`` (no module globals)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:  # kept out of plugin load: subject.py needs the planner module (numpy)
    from .options import Settings
    from ..subjects.resolve import Subject


@dataclass
class NavState:
    settings: Settings
    subject: Subject
    is_worker: bool
    records: list[dict[str, Any]] = field(default_factory=list)   # controller: results records
    failed_artifacts: list[str] = field(default_factory=list)      # controller: folders written
    bad_scenario_files: int = 0   # scenario files that failed to load (collection errors)
    results_error: str | None = None   # controller: why the results file could not be written
    results_kept: bool = False    # controller: no episode was recorded, the file was left as it was
    ended_left_running: list[str] = field(default_factory=list)   # processes planners left, ended at the end
    not_scenarios: list[tuple[str, str]] = field(default_factory=list)   # (path, why): skipped.py
    scenario_folders: set[str] = field(default_factory=set)   # folders holding collected scenarios
    executor: Any = None          # controller with --nav-ray: where episodes run (dispatch/)
    executor_notes: list[str] = field(default_factory=list)       # header lines about it
    # frozen failures of the search among the collected scenarios: (path, name) -> provenance
    frozen: dict[tuple[str, str], dict[str, Any]] = field(default_factory=dict)
    batching: Any = None          # controller with an executor: harness.batch.Batching of the items
    serial_items: int = 0         # scenario items run in this process, one at a time (no executor)


STATE_KEY = pytest.StashKey[NavState]()


def get_state(config: pytest.Config) -> NavState:
    try:
        return config.stash[STATE_KEY]
    except KeyError:
        raise RuntimeError("pytest-navscenario is not configured in this session "
                           "(is the plugin loaded? -p pytest_navscenario.plugin)") from None
