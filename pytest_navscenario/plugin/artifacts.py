"""Per failing item, a folder under ``--nav-artifacts`` with what is needed to look at the failure:

    <artifacts>/<item folder>/scenario.yaml     the scenario exactly as run (reload it with load_scenario)
    <artifacts>/<item folder>/trajectory.csv    t, x, y, yaw (rad), vx, vy, wz: every physics step
    <artifacts>/<item folder>/commands.csv      tick_t, vx, vy, wz: the commands after the drive's limits
    <artifacts>/<item folder>/result.json       the results-file record (outcome, metrics, seed, subject)
    <artifacts>/<item folder>/plots/, bags/     left for the plots and bags plugins (``item_dir``)

Written by the controller from ``report.nav`` (never by xdist workers). The item folder name is
the node id with every character outside ``[A-Za-z0-9._-]`` replaced, plus a short hash of the
node id, so two items never share a folder and no scenario name can write outside the folder.
"""
from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import pytest

from ..core.files import atomic_write_text, folder_name
from .state import get_state


def item_dir(config: pytest.Config, nodeid: str) -> Path | None:
    """The artifacts folder of one item (not created), or None when artifacts are off."""
    root = get_state(config).settings.artifacts
    if root is None:
        return None
    path = root / folder_name(nodeid)
    if path.parent != root:  # cannot happen with folder_name; guard against future edits
        raise ValueError(f"artifact folder {path} is outside {root}")
    return path


def _csv(header: list[str], rows: Any) -> str:
    buf = io.StringIO()
    buf.write(",".join(header) + "\n")
    for row in rows:
        buf.write(",".join(repr(float(v)) for v in row) + "\n")
    return buf.getvalue()


def write_item_artifacts(config: pytest.Config, payload: dict[str, Any]) -> Path | None:
    """Write the scenario, trajectory and record of one failed item; return its folder."""
    rec = payload["record"]
    folder = item_dir(config, rec["nodeid"])
    if folder is None:
        return None
    folder.mkdir(parents=True, exist_ok=True)
    try:
        from ..scenario.loader import scenario_from_dict
        from ..scenario.dump import dump_scenario
        text = dump_scenario(scenario_from_dict(payload["scenario"]))
    except Exception:  # the loader rejects what it wrote: still keep the data for a bug report
        import yaml
        text = yaml.safe_dump(payload["scenario"], sort_keys=False)
    atomic_write_text(folder / "scenario.yaml", text)
    atomic_write_text(folder / "result.json", json.dumps(rec, indent=2, sort_keys=True) + "\n")
    traj = payload.get("trajectory")
    if traj is not None:
        rows = ([t, *p, *v] for t, p, v in zip(traj["t"], traj["pose"], traj["velocity"]))
        atomic_write_text(folder / "trajectory.csv",
                          _csv(["t", "x", "y", "yaw", "vx", "vy", "wz"], rows))
        rows = ([t, *c] for t, c in zip(traj["tick_t"], traj["command"]))
        atomic_write_text(folder / "commands.csv", _csv(["tick_t", "vx", "vy", "wz"], rows))
    return folder
