"""The options of the failure search (``--navsearch`` and friends, each with an ini twin), read and
checked into ``SearchSettings``, and how a seed name is found among the scenario folders."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from ..search.strategies import STRATEGIES as _REGISTERED, describe as describe_strategies, names as strategy_names
from .options import ini_value

DEFAULT_BUDGET = 100
DEFAULT_SHRINK_BUDGET = "25%"   # = search.engine.DEFAULT_SHRINK_BUDGET
DEFAULT_OUT = "scenarios/regressions"
DEFAULT_STUCK_AFTER = 15.0   # = search.engine.DEFAULT_STUCK_AFTER
DEFAULT_HOLD = 0.9           # = search.holding.DEFAULT_HOLD
STRATEGY_NAMES = strategy_names()   # the registry's (search/strategies/__init__.py; imports no strategy)
OLD_OUT_INI = "nav_regressions_dir"     # the old name of the ini option navsearch_out, still read

# (option, dest / ini name, metavar, help)
OPTIONS = (
    ("--navsearch", "navsearch", "NAME",
     "search for failures around the seed scenario NAME (a file NAME.yaml under the "
     "nav_scenario_paths folders, or a path to a scenario file); repeatable. Runs searches "
     "instead of the scenario items."),
    ("--budget", "navsearch_budget", "N",
     f"simulations per search (valid candidates only; default {DEFAULT_BUDGET})."),
    ("--navsearch-seed", "navsearch_seed", "N",
     "random seed of the search (integer >= 0, default 0); the same seed, subject and budget "
     "repeat a search exactly."),
    ("--navsearch-strategy", "navsearch_strategy", "{" + ",".join(STRATEGY_NAMES) + "}",
     describe_strategies() + "."),
    ("--navsearch-shrink-budget", "navsearch_shrink_budget", "SHARE",
     f"simulations for shrinking the distinct failures toward the seed, on top of the budget: "
     f"a share of the budget (default {DEFAULT_SHRINK_BUDGET}), shared out before shrinking "
     f"starts, most severe and earliest failure first (failures it does not reach are kept as "
     f"found); 0 = keep every failure as found; a whole number N = at most N simulations for "
     f"each failure (the old form)."),
    ("--navsearch-hold", "navsearch_hold", "P",
     f"a failure counts (is distinct, shrunk and frozen) only when it holds: when repeats under fresh "
     f"noise seeds (confirmation runs, simulations of the budget) decide, by a sequential test, that "
     f"it fails with probability at least P rather than at most the P whose odds are 9 times smaller "
     f"(default {DEFAULT_HOLD}: 0.9 against 0.5); 0 = every failure counts after one run. A seed "
     f"without randomness (no sensor noise, drift or perturbation) needs no confirmation."),
    ("--navsearch-stuck-after", "navsearch_stuck_after", "SECONDS",
     f"end a search episode early, as a timeout, when the robot has covered no new ground for "
     f"this long (default {DEFAULT_STUCK_AFTER:g}; 0 = run every episode to its timeout)."),
    ("--navsearch-out", "navsearch_out", "DIR",
     f"folder for frozen failures, one subfolder per seed, plus each search's log "
     f"(default {DEFAULT_OUT}; the ini option's old name {OLD_OUT_INI} is still read)."),
    ("--navsearch-junit", "navsearch_junit", "PATH",
     "also write the generated suite (every simulated candidate) as a JUnit XML file."),
    ("--navsearch-suite", "navsearch_suite", "DIR",
     "also keep the generated suite as scenario files: every candidate simulated in the search "
     "phase (failing or not; not the shrink phase) as DIR/<seed>/<seed>-sim<N>-<hash>.yaml, "
     "family = seed, replacing that seed's earlier suite there; written also when the run is cut "
     "short. Re-run it against any planner: pytest DIR --nav-subject=..."),
)


_INT_OPTIONS = ("navsearch_budget", "navsearch_seed")   # ini type int


# -- settings ------------------------------------------------------------------------------------
@dataclass
class SearchSettings:
    names: list[str]
    budget: int
    seed: int
    strategy: str
    shrink_budget: str
    out: Path
    junit: Path | None
    stuck_after: float | None = DEFAULT_STUCK_AFTER
    suite: Path | None = None
    hold: float = DEFAULT_HOLD



def _raw(config: pytest.Config, dest: str) -> tuple[Any, str, Path]:
    cli = config.getoption(dest)
    if cli is not None:
        return cli, f"--{dest.replace('_', '-')}" if dest != "navsearch_budget" else "--budget", \
            Path(config.invocation_params.dir)
    return ini_value(config, dest), f"ini option {dest}", Path(config.rootpath)


def _int(config: pytest.Config, dest: str, default: int, minimum: int, what: str) -> int:
    raw, where, _ = _raw(config, dest)
    if raw in ("", None):
        return default
    try:
        value = int(str(raw).strip())
    except ValueError:
        raise pytest.UsageError(f"{where}: {what} must be a whole number, got {raw!r}") from None
    if value < minimum:
        raise pytest.UsageError(f"{where}: {what} must be >= {minimum}, got {value}"
                                + (" (e.g. --budget 100)" if dest == "navsearch_budget" else ""))
    return value


def _out_raw(config: pytest.Config) -> tuple[Any, str, Path]:
    """--navsearch-out, else the ini option navsearch_out, else its old name nav_regressions_dir;
    the two ini names set to different folders is a usage error."""
    raw, where, base = _raw(config, "navsearch_out")
    if config.getoption("navsearch_out") is not None:
        return raw, where, base
    old = str(config.getini(OLD_OUT_INI)).strip()
    if old and str(raw).strip() and str(raw).strip() != old:
        raise pytest.UsageError(f"ini options navsearch_out = {str(raw).strip()!r} and {OLD_OUT_INI} = "
                                f"{old!r} disagree; {OLD_OUT_INI} is the old name of navsearch_out: "
                                f"keep only navsearch_out")
    if old and not str(raw).strip():
        return old, f"ini option {OLD_OUT_INI}", base
    return raw, where, base


def read_search_settings(config: pytest.Config) -> SearchSettings:
    """Every search option, checked (in every session, so a bad ini value is reported at once;
    the search package is imported only for a value that needs it)."""
    raw, _, _ = _raw(config, "navsearch")
    names = list(dict.fromkeys(n.strip() for n in (raw or []) if n and n.strip()))
    budget = _int(config, "navsearch_budget", DEFAULT_BUDGET, 1, "the budget (simulations per search)")
    seed = _int(config, "navsearch_seed", 0, 0, "the search seed")
    raw, where, _ = _raw(config, "navsearch_strategy")
    strategy = (str(raw).strip() or "evolve").lower()
    if strategy not in _REGISTERED:
        raise pytest.UsageError(f"{where}: unknown strategy {raw!r}; use one of {', '.join(strategy_names())}")
    shrink = _shrink_budget(config)
    raw, where, base = _out_raw(config)
    raw = str(raw).strip() or DEFAULT_OUT
    out = Path(os.path.expanduser(raw))
    out = out if out.is_absolute() else base / out
    if out.exists() and not out.is_dir():
        raise pytest.UsageError(f"{where}: {raw!r} exists and is not a folder; give a folder for the frozen failures")
    raw, where, base = _raw(config, "navsearch_junit")
    raw = str(raw or "").strip()
    junit = None
    if raw:
        junit = Path(os.path.expanduser(raw))
        junit = junit if junit.is_absolute() else base / junit
        if junit.is_dir():
            raise pytest.UsageError(f"{where}: {raw!r} is a folder; give a file name such as navsearch.xml")
    return SearchSettings(names, budget, seed, strategy, shrink, out, junit, _stuck_after(config),
                          _suite_dir(config, out), _hold(config))


def _hold(config: pytest.Config) -> float:
    """--navsearch-hold / navsearch_hold: a failure probability from 0 (off) to below 1."""
    raw, where, _ = _raw(config, "navsearch_hold")
    if raw in ("", None):
        return DEFAULT_HOLD
    try:
        value = float(str(raw).strip())
    except ValueError:
        value = math.nan
    if not 0.0 <= value < 1.0:
        raise pytest.UsageError(f"{where}: the hold threshold is a failure probability from 0 to below 1, "
                                f"got {raw!r} (e.g. 0.9, the default; 0 counts every failure after one run)")
    return value


def _suite_dir(config: pytest.Config, out: Path) -> Path | None:
    """--navsearch-suite DIR: a folder (made if missing), not the frozen failures' folder."""
    raw, where, base = _raw(config, "navsearch_suite")
    raw = str(raw or "").strip()
    if not raw:
        return None
    suite = Path(os.path.expanduser(raw))
    suite = suite if suite.is_absolute() else base / suite
    if suite.exists() and not suite.is_dir():
        raise pytest.UsageError(f"{where}: {raw!r} exists and is not a folder; give a folder for the "
                                f"generated suite, e.g. suites/dwa")
    if suite.resolve() == out.resolve():
        raise pytest.UsageError(f"{where}: {raw!r} is also the folder of the frozen failures "
                                f"(--navsearch-out); give the suite a folder of its own, e.g. suites/dwa, "
                                f"so that re-running it does not run the frozen failures too")
    return suite


def _shrink_budget(config: pytest.Config) -> str:
    """--navsearch-shrink-budget / navsearch_shrink_budget, checked: "25%", "0" or "40"."""
    cli = config.getoption("navsearch_shrink_budget")
    if cli is not None:
        raw, where = cli, "--navsearch-shrink-budget"
    else:
        raw = ini_value(config, "navsearch_shrink_budget",
                        'a share of the budget such as "25%", or a whole number such as "40" (quoted in TOML)')
        where = "ini option navsearch_shrink_budget"
    if raw in ("", None):
        return DEFAULT_SHRINK_BUDGET
    from ..search.engine import ShrinkBudget
    try:
        ShrinkBudget.parse(raw)
    except ValueError as exc:
        raise pytest.UsageError(f"{where}: {exc}") from None
    return str(raw).strip()


def _stuck_after(config: pytest.Config) -> float | None:
    raw, where, _ = _raw(config, "navsearch_stuck_after")
    if raw in ("", None):
        return DEFAULT_STUCK_AFTER
    try:
        value = float(str(raw).strip())
    except ValueError:
        raise pytest.UsageError(f"{where}: the stuck time must be a number of seconds, got {raw!r} "
                                f"(e.g. 10; 0 turns the early stop off)") from None
    if not math.isfinite(value) or value < 0:
        raise pytest.UsageError(f"{where}: the stuck time must be >= 0 seconds, got {raw!r} "
                                f"(0 turns the early stop off)")
    return value or None


def _scenario_files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.glob("*.y*ml") if p.suffix in (".yaml", ".yml"))


def find_seed(name: str, scenario_paths: tuple[Path, ...], rootdir: Path) -> Path:
    """The seed file for ``name``: NAME.yaml / NAME.yml in a scenario folder, or a file path."""
    as_path = Path(os.path.expanduser(name))
    for candidate in (as_path, rootdir / as_path):
        if candidate.suffix in (".yaml", ".yml") and candidate.is_file():
            return candidate
    for folder in scenario_paths:
        for ext in (".yaml", ".yml"):
            if (folder / f"{name}{ext}").is_file():
                return folder / f"{name}{ext}"
    available = sorted({p.stem for folder in scenario_paths if folder.is_dir() for p in _scenario_files(folder)})
    where = ", ".join(str(p) for p in scenario_paths) or "(none configured)"
    raise pytest.UsageError(
        f"--navsearch {name}: no seed scenario named {name!r} in {where}. "
        + (f"Available: {', '.join(available)}. " if available else "No scenario files there. ")
        + "Give one of these names, a path to a scenario file, or add the folder to the ini option "
          "nav_scenario_paths.")
