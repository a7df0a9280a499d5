"""A pool child SIGKILLed in a ``-n 2`` search session does not end the session (issue 38, part 2):
the pool is replaced, what was lost runs again, what was found is kept, every search item ends as
it would have, and the end record of the search log says a worker died and what was run again."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from test_search import SEED_YAML
from test_search_kill import start_search, wait_for_progress

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def project(tmp_path: Path) -> Path:
    from test_search_parallel import SLOW
    (tmp_path / "straight_planner.py").write_text(SLOW)
    (tmp_path / "scenarios").mkdir()
    (tmp_path / "scenarios" / "crate.yaml").write_text(SEED_YAML.replace("name: crate\n", ""))
    (tmp_path / "scenarios" / "crate2.yaml").write_text(SEED_YAML.replace("name: crate\n", ""))
    (tmp_path / "pytest.ini").write_text("[pytest]\nnav_scenario_paths = scenarios\n")
    return tmp_path


def descendants(pid: int) -> list[int]:
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        for task in Path(f"/proc/{p}/task").iterdir() if Path(f"/proc/{p}/task").exists() else []:
            try:
                kids = [int(k) for k in (task / "children").read_text().split()]
            except OSError:
                continue
            out += kids
            todo += kids
    return out


def pool_workers(pid: int) -> list[int]:
    """The pool's worker processes: the children of the forkserver (itself a child of pytest)."""
    for child in descendants(pid):
        try:
            cmd = Path(f"/proc/{child}/cmdline").read_text()
            parent = int(Path(f"/proc/{child}/stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError):
            continue
        if parent == pid and "forkserver" in cmd:
            return [k for k in descendants(child)]
    return []


@pytest.mark.parametrize("delay", [0.5, 2.0])
def test_a_killed_pool_child_does_not_end_a_search_session(project: Path, delay: float):
    proc = start_search(project, "-n", "2", "--navsearch", "crate2", "--navsearch-out", "out")
    seen = wait_for_progress(proc)
    time.sleep(delay)
    workers = pool_workers(proc.pid)
    assert workers, "no pool worker found"
    os.kill(workers[0], signal.SIGKILL)
    seen += proc.communicate(timeout=300)[0]
    assert "BrokenProcessPool" not in seen and "process pool is not usable" not in seen, seen[-4000:]
    assert proc.returncode in (0, 1), seen[-4000:]
    for name in ("crate", "crate2"):
        log = [json.loads(line) for line in (project / "out" / name / "search-log.jsonl").read_text().splitlines()]
        end = log[-1]
        assert end["record"] == "end" and not end["interrupted"], end
        assert end["search_sims"] + end["shrink_sims"] >= 60 or end["stop_reason"], end
    ends = [json.loads((project / "out" / n / "search-log.jsonl").read_text().splitlines()[-1]) for n in ("crate", "crate2")]
    assert any(e.get("worker_deaths") for e in ends), ends       # the search in which it happened says so
    said = next(e["worker_deaths"] for e in ends if e.get("worker_deaths"))
    assert "killed by SIGKILL" in said[0] and "run again" in said[0]
