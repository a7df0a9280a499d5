"""Ray test set-up shared by the Ray test modules: test planners on the workers' path, and a
suite of scenario files."""
from __future__ import annotations

import os
from pathlib import Path

from dispatch_helpers import KILLABLE_PLANNER, scenario_text

#: Why the Ray tests skip, and how to run them (shown in the summary: -rs is in addopts).
RAY_MISSING = ("Ray is not installed, so the --nav-ray tests cannot run: pip install -e '.[ray]' "
               "(the ray extra), then pytest tests/dispatch -n 2")

SUITE = [("a", 1.0), ("b", 1.1), ("victim", 1.2), ("c", 1.3), ("d", 1.4), ("e", 1.5)]


def planners_on_worker_path(folder: Path) -> str | None:
    """Write the test planner into ``folder`` and put it on PYTHONPATH for the Ray processes
    started afterwards (they inherit the environment). Returns the old PYTHONPATH."""
    (folder / "killable.py").write_text(KILLABLE_PLANNER.format(log_dir=str(folder)))
    old = os.environ.get("PYTHONPATH")
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(folder), old) if p)
    return old


def restore_pythonpath(old: str | None) -> None:
    if old is None:
        os.environ.pop("PYTHONPATH", None)
    else:
        os.environ["PYTHONPATH"] = old


def write_suite(folder: Path, short_timeout: str = "") -> None:
    """Six scenario files; with ``short_timeout`` the last one has that mission timeout (fails: 1.6 s can be
    driven at top speed, 1.52 s for the 1.7 m to the goal's tolerance, so it is a test, but dwa needs more)."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, x in SUITE:
        text = scenario_text(name, x)
        if short_timeout and name == SUITE[-1][0]:
            text = text.replace("timeout: 6", f"timeout: {short_timeout}")
        (folder / f"{name}.yaml").write_text(text)


def item_lines(output: list[str]) -> list[str]:
    """The -v lines of the items, in the order pytest reported them."""
    return [line.split(" ")[0] + " " + line.split()[1] for line in output
            if "::" in line and (" PASSED" in line or " FAILED" in line)]
