"""New pytest hooks of pytest-navscenario (registered by plugin.py via ``pytest_addhooks``).

Implement them in a ``conftest.py`` or a plugin. Example: provide the subject from code::

    # conftest.py
    def pytest_navscenario_make_subject(config):
        from mypkg.nav import Planner
        return lambda: Planner(gain=config.getoption("--my-gain"))

Feature plugins (plots, bags, comparison) read each episode on the controller either from
``report.nav`` in their own ``pytest_runtest_logreport`` (not ``trylast``: after every other
plugin has seen it, the core trims the payload to its record to keep memory flat in long runs) or
through ``pytest_navscenario_episode_report`` below; the payload format is documented in payload.py.
Call ``payload.request_trajectories(config, "failed" | "all")`` in ``pytest_configure`` to have
the trajectory included (it is left out by default: it is the bulk of the payload).
"""
from __future__ import annotations

from typing import Any

import pytest


@pytest.hookspec(firstresult=True)
def pytest_navscenario_make_subject(config: pytest.Config) -> Any:
    """Return the subject under test, or None to fall back to ``--nav-subject`` / ini ``nav_subject``.

    The return value may be a zero-argument factory or class (called once per episode, so each
    episode starts from a fresh planner) or a ``"package.module:Attribute"`` / built-in name string.
    Called once per process (controller and each xdist worker) at session start, from the
    conftest.py files pytest has loaded by then (the rootdir's and those of the given paths).
    """


def pytest_navscenario_episode_report(config: pytest.Config, report: pytest.TestReport,
                                      payload: dict[str, Any], artifact_dir: Any) -> None:
    """Called on the controller (never on an xdist worker) for each scenario episode's call report.

    ``payload`` is ``report.nav`` (see payload.py; ``payload.episode_from_payload`` rebuilds the
    EpisodeResult). ``artifact_dir`` is the item's artifacts folder (a ``pathlib.Path`` that exists)
    when the item failed and artifacts are on, else None; write plots/bags into subfolders of it.
    """
