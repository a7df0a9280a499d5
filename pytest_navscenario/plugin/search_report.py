"""Pictures and the HTML report of a search: ``pytest --navsearch NAME`` with ``--nav-plots`` and
``--nav-html`` (the options of the run report, reports.py, read the same way).

* ``--nav-plots=failed|all`` (given on the command line or in the ini file; the default makes no
  search pictures: a search is not slowed by what it was not asked for): a picture of each frozen
  failure, beside its file (``<seed>-<hash>.png`` next to ``<seed>-<hash>.yaml``), or in
  ``--nav-plots-dir``; at most ``--nav-plots-max`` files per session, as for scenario items.
* ``--nav-html=FILE``: the search report (report/search_page.py) instead of the run report: per
  search its failures with their pictures, outcome, clearance and reproduce command, and how it
  went (distinct failures, best fitness and discards over the simulations, outcomes, discards by
  reason).

A failure's picture is of the frozen file run as a pytest item runs it (same subject, --nav-seed
and tick limit, no early stop of a stuck robot): what ``pytest <file>`` shows. When that run ends
otherwise than the search saw, the report says so.
"""
from __future__ import annotations

import math
import shlex
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from .options import ini_is_set
from .reports import REPORT_KEY


def _plots_asked(config: pytest.Config) -> bool:
    """--nav-plots / nav_plots set by the user (not its default, which is for scenario items)."""
    return config.getoption("nav_plots") is not None or ini_is_set(config, "nav_plots")


def wanted(config: pytest.Config) -> tuple[bool, bool]:
    """(make a picture of each failure, write it to a file)."""
    state = config.stash.get(REPORT_KEY, None)
    if state is None:
        return False, False
    to_file = _plots_asked(config) and state.settings.plots != "none"
    return to_file or state.settings.html is not None, to_file


def lowest_clearance(report: Any) -> Any:
    """The search-phase candidate that came closest to an obstacle (the first of equals), or None."""
    best = None
    for c in report.candidates:
        if c.phase == "search" and math.isfinite(c.clearance) and (best is None or c.clearance < best.clearance):
            best = c
    return best


def lowest_clearance_text(report: Any) -> str:
    """"lowest clearance of any run 0.029 m (sim 57, a run that passed)": the closest any simulated
    candidate came, and the run it came from, so that it is not read as a frozen failure's."""
    c = lowest_clearance(report)
    if c is None:
        return "lowest clearance of any run n/a"
    what = "a run that passed" if c.outcome == "success" else f"a {c.outcome}"
    return f"lowest clearance of any run {c.clearance:.3f} m (sim {c.sim}, {what})"


def _rel(config: pytest.Config, path: Path) -> str:
    try:
        return Path(path).resolve().relative_to(Path(config.rootpath).resolve()).as_posix()
    except ValueError:
        return str(path)


def _reproduce(config: pytest.Config, path: Path) -> str:
    from .reports import _cd_rootdir
    from .state import get_state

    core = get_state(config)
    cmd = f"{_cd_rootdir(config)}pytest {shlex.quote(_rel(config, path))}"
    if core.subject.spec is not None and core.subject.origin != "built-in default":
        cmd += f" {shlex.quote(f'--nav-subject={core.subject.spec}')}"
    if core.settings.seed:
        cmd += f" --nav-seed={core.settings.seed}"
    return cmd


def _picture_path(config: pytest.Config, frozen: Path) -> Path:
    state = config.stash[REPORT_KEY]
    if state.settings.plots_dir is not None:
        return state.settings.plots_dir / f"{frozen.stem}.png"
    return frozen.with_suffix(".png")


def failure_rows(config: pytest.Config, entry: dict[str, Any]) -> list[Any]:
    """One FailureRow per frozen file of a finished search (``entry`` of plugin/search.py), each
    with its picture when asked for (written beside the file, or kept for the HTML page)."""
    from ..report.search_page import FailureRow
    from ..scenario.model import content_hash
    from ..search.freeze import candidate_scenario

    make, to_file = wanted(config)
    report, space = entry["report"], entry["job"].space
    by_name = {}
    for failure in report.failures:
        name = f"{space.seed.name}-{content_hash(candidate_scenario(failure.shrunk, space))}"
        by_name.setdefault(name, failure)
    rows = []
    for frozen in entry["files"]:
        failure = by_name.get(Path(frozen.path).stem)
        shrunk = failure.shrunk if failure is not None else None
        row = FailureRow(
            file=_rel(config, frozen.path), new=frozen.new, outcome=frozen.outcome,
            message=shrunk.message if shrunk is not None else "", culprit=shrunk.culprit if shrunk else "",
            clearance=frozen.clearance, found_at=failure.found.sim if failure else 0,
            shrink_sims=failure.shrink_sims if failure else 0, note=failure.note if failure else "",
            reproduce=_reproduce(config, Path(frozen.path)))
        estimate = failure.estimate if failure is not None else None
        if estimate is not None and estimate.runs:   # confirmed under the seed's randomness (search/holding.py)
            row.probability, row.interval = estimate.probability, estimate.interval
        if make:
            try:
                _picture(config, row, Path(frozen.path), to_file)
            except Exception as exc:   # a picture must not lose the search's results
                entry["error"] += ("; " if entry["error"] else "") + (
                    f"could not draw {row.file}: {type(exc).__name__}: {exc}")
        rows.append(row)
    return rows


def _picture(config: pytest.Config, row: Any, frozen: Path, to_file: bool) -> None:
    """Run the frozen file as a pytest item would, plot it, keep the PNG (and write it)."""
    from ..harness.runner import run_scenario
    from ..report.plots import png_bytes, save_figure, trajectory_figure
    from ..scenario.loader import load_scenario
    from .state import get_state

    core = get_state(config)
    reports = config.stash[REPORT_KEY]
    result = run_scenario(load_scenario(frozen), core.subject.runner_arg, seed=core.settings.seed,
                          tick_limit=core.settings.tick_limit, reset_timeout=core.settings.reset_timeout)
    if result.outcome.value != row.outcome:
        row.rerun = (f"run as a pytest item it ends {result.outcome.value}; the search saw {row.outcome}: "
                     f"{row.message} (a search ends an episode early when the robot is stuck, "
                     f"--navsearch-stuck-after)")
    row.message = result.message   # what the picture shows: the file run as a pytest item
    fig = trajectory_figure(result)
    limit = reports.settings.plots_max
    files = sum(1 for p in reports.plots.values() if isinstance(p, Path))
    if to_file and (not limit or files < limit):
        path = save_figure(fig, _picture_path(config, frozen))
        reports.plots[(row.file, 0)] = path
        row.picture = _rel(config, path)
        row.plot_png = path.read_bytes() if reports.settings.html is not None else None
    elif to_file:
        reports.not_plotted += 1
    if reports.settings.html is not None:
        from ..report.html import view_data
        row.plot_png = row.plot_png or png_bytes(fig)
        row.view = view_data(result)


def section(config: pytest.Config, entry: dict[str, Any]) -> Any:
    """The search as a SearchSection of the HTML report (its chart included)."""
    from ..report.plots import png_bytes
    from ..report.search_page import SearchSection, progress_figure

    r = entry["report"]
    version = f" {r.subject_version}" if r.subject_version else ""
    title = f"{r.seed_name} vs {r.subject}{version}"
    progress = _progress(r)
    facts = [("seed file", _rel(config, Path(entry["job"].path))),
             ("strategy, search seed", f"{r.strategy}, {r.seed_value}"),
             ("simulations", f"{r.sims_used} of a budget of {r.budget} searching, {r.shrink_sims} shrinking"
                             + (f" (shrink budget {r.shrink_total})" if r.shrink_total else "")),
             ("distinct failures", ", ".join(f"{k} {v}" for k, v in sorted(r.failures_by_outcome().items()))
              or "none"),
             ("first failure", f"sim {r.first_failure}" if r.first_failure else "none"),
             ("clearance", lowest_clearance_text(r)),
             ("episode seed (--nav-seed)", str(r.episode_seed or 0)),
             ("wall time", f"{r.wall_time:.1f} s")]
    if entry.get("log") is not None:
        facts.append(("search log", _rel(config, entry["log"])))
    notes = []
    if r.interrupted:
        notes.append(f"CUT SHORT: {r.stop_reason or 'interrupted'}; the failures found so far are kept")
    elif r.stop_reason:
        notes.append(f"stopped early: {r.stop_reason}")
    if entry.get("error"):
        notes.append(f"ERROR {entry['error']}")
    from ..search.discards import discard_advice
    advice = [a.line() for a in discard_advice(r.discarded, r.sims_used, getattr(entry.get("job"), "space", None))]
    rows = entry.get("rows") or []
    sec = SearchSection(
        title=title, facts=facts, progress=progress, failures=rows,
        outcomes=dict(Counter(c.outcome for c in r.candidates if c.phase == "search")),
        shrink_outcomes=dict(Counter(c.outcome for c in r.candidates if c.phase == "shrink")),
        discarded=dict(r.discarded), skipped=r.skipped, notes=notes, discard_advice=advice)
    sec.chart_png = png_bytes(progress_figure(progress, title=f"{title}: how the search went"))
    return sec


def _progress(r: Any) -> Any:
    """Per search simulation: outcome, robustness, lowest so far, distinct failures and discards
    so far (from the report's candidates, failures and discard log)."""
    from ..report.search_page import Progress

    found = sorted(f.found.sim for f in r.failures if f.found.phase == "search")
    discards = sorted(n for n, _ in getattr(r, "discard_log", []))
    p = Progress()
    best = math.inf
    k = d = 0
    for c in r.candidates:
        if c.phase != "search":
            continue
        rob = c.robustness if math.isfinite(c.robustness) else math.nan
        if math.isfinite(rob):
            best = min(best, rob)
        while k < len(found) and found[k] <= c.sim:
            k += 1
        while d < len(discards) and discards[d] < c.sim:
            d += 1
        p.sims.append(c.sim)
        p.outcomes.append(c.outcome)
        p.robustness.append(rob)
        p.best.append(best if math.isfinite(best) else math.nan)
        p.failures.append(k)
        p.discarded.append(d)
    return p


def write_html(config: pytest.Config, entries: list[dict[str, Any]]) -> Path | None:
    """The search report at --nav-html (None when it was not asked for)."""
    from ..report.search_page import write_search_html

    state = config.stash.get(REPORT_KEY, None)
    if state is None or state.settings.html is None:
        return None
    sections = [section(config, e) for e in entries]
    info = [f"command: pytest {' '.join(config.invocation_params.args)}"]
    path = write_search_html(state.settings.html, sections, info=info,
                             title="navsearch report: " + ", ".join(e["report"].seed_name for e in entries))
    state.html_written = path
    return path
