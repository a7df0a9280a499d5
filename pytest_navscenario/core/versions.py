"""The MuJoCo release this process simulates with, named without importing MuJoCo (only ``sim/``
imports it; the CLI's ``--version`` and the pytest header stay cheap). Trajectories' bits are a
MuJoCo release's: a patch release moves them (issue 32: a fall 0.1 s later, a tip-over that became a
collision), so the version goes into pytest's header, ``navscenario --version``, results records and
frozen files' provenance, and a frozen file that no longer reproduces says when it was found under
another release."""
from __future__ import annotations

import sys
from importlib import metadata


def mujoco_version() -> str:
    """The loaded ``mujoco`` module's version, else the installed distribution's, else "unknown"."""
    module = sys.modules.get("mujoco")
    loaded = getattr(module, "__version__", None) if module is not None else None
    if loaded:
        return str(loaded)
    try:
        return metadata.version("mujoco")
    except metadata.PackageNotFoundError:
        return "unknown"


def other_mujoco(recorded: object) -> str:
    """A note when ``recorded`` (a provenance's or a record's ``mujoco_version``) names another
    release than this process's, else ""."""
    if not recorded:
        return ""
    now = mujoco_version()
    if str(recorded) == now:
        return ""
    return (f"it was recorded under MuJoCo {recorded}, this run simulates with MuJoCo {now}: "
            f"a MuJoCo release moves trajectories, so a different outcome may be the simulator's")
