"""Feature plugin: regression gate against a baseline, trajectory plots, the HTML report.

Options (each with an ini twin)::

    --nav-baseline=A.jsonl        compare this run with a results file of an earlier run; the
                                  comparison goes into the terminal summary
    --nav-baseline-mode=fail|warn fail (default): the session fails when this run broke a scenario
                                  the baseline passed, or when none of its scenario runs could be
                                  compared with the baseline; warn: only report it
    --nav-baseline-subject=SPEC   re-run the baseline's subject on each regression for a side-by-side
                                  plot (default: the subject its records name)
    --nav-plots=failed|all|none   trajectory plots of failing items (default), of every item, or none
    --nav-plots-max=N             at most N plots per session (default 20, 0 = no limit; not for
                                  failing items when --nav-html is given)
    --nav-plots-dir=DIR           where plots go; default: the item's artifacts folder
                                  (<artifacts>/<item>/plots/trajectory.png), or nav-plots/ under the
                                  rootdir when artifacts are off
    --nav-html=report.html        one self-contained HTML report (summary, comparison, failures' plots)

Everything runs on the controller (never on an xdist worker) from ``report.nav``, and matplotlib
is imported only when a plot is actually made: a default run in which everything passes never
imports it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from .options import ini_type, option_value as _value, resolve_path

PLOT_CHOICES = ("failed", "all", "none")
MODE_CHOICES = ("fail", "warn")
DEFAULT_PLOTS_DIR = "nav-plots"

OPTIONS = (
    ("--nav-baseline", "nav_baseline", "",
     "compare this run with the results file of an earlier run (pytest --nav-results=A.jsonl); "
     "the comparison is added to the terminal summary"),
    ("--nav-baseline-mode", "nav_baseline_mode", "fail",
     "what a regression against --nav-baseline does: fail (default: the session fails when a scenario "
     "the baseline passed fails now, or when no scenario run could be compared with the baseline) or "
     "warn (report only)"),
    ("--nav-baseline-subject", "nav_baseline_subject", "",
     "the baseline's subject spec, to re-run it for side-by-side plots of regressions (default: the "
     "--nav-subject spec the baseline's records carry; needed when its subject came from a conftest "
     "hook)"),
    ("--nav-plots", "nav_plots", "failed",
     "trajectory plots: failed (default: for failing items), all, or none; given with --navsearch "
     "(failed or all), a picture of each frozen failure beside its file"),
    ("--nav-plots-max", "nav_plots_max", "20",
     "make at most N trajectory plots per session (default 20; 0 = no limit): a plot costs ~0.25 s of "
     "CPU on the controller; --nav-html lifts the limit for failing items (the report shows them all)"),
    ("--nav-plots-dir", "nav_plots_dir", "",
     "folder for trajectory plots; default: each item's artifacts folder (plots/trajectory.png), or "
     f"{DEFAULT_PLOTS_DIR}/ under the rootdir when artifacts are off"),
    ("--nav-html", "nav_html", "",
     "write one self-contained HTML report (summary, comparison, every failure's plot) to this file; "
     "with --navsearch the search's report (its failures with their pictures, how it went)"),
)

# accepted values in braces, or a unit (N, PATH, DIR, SPEC), as every option of the plugin shows it
METAVARS = {"nav_baseline": "PATH", "nav_baseline_mode": "{" + ",".join(MODE_CHOICES) + "}",
            "nav_baseline_subject": "SPEC", "nav_plots": "{" + ",".join(PLOT_CHOICES) + "}",
            "nav_plots_max": "N", "nav_plots_dir": "DIR", "nav_html": "PATH"}


@dataclass
class ReportSettings:
    baseline: Path | None
    mode: str
    plots: str
    plots_dir: Path | None
    html: Path | None
    plots_max: int = 20
    baseline_subject: str | None = None


@dataclass
class ReportState:
    settings: ReportSettings
    baseline_records: list[dict[str, Any]] = field(default_factory=list)
    records: list[dict[str, Any]] = field(default_factory=list)
    plots: dict[tuple[str, int], Path | bytes] = field(default_factory=dict)  # (nodeid, repeat) -> file or PNG
    views: dict[tuple[str, int], dict[str, Any]] = field(default_factory=dict)  # for the HTML's viewer
    xfailed: dict[tuple[str, int], str] = field(default_factory=dict)  # expected failures: xfail reason
    side_by_side: dict[tuple[str, int], Path | bytes] = field(default_factory=dict)  # regressions: A | B
    signal_plots: dict[tuple[str, int], Path | bytes] = field(default_factory=dict)  # requirements over time
    baseline_index: dict[tuple[str, int], dict[str, Any]] = field(default_factory=dict)
    bad_baseline_subjects: set[str] = field(default_factory=set)
    notes: list[str] = field(default_factory=list)
    plot_errors: list[str] = field(default_factory=list)
    not_plotted: int = 0                      # items left without a plot by --nav-plots-max
    comparison: Any = None
    html_written: Path | None = None
    gate_failed: bool = False
    nothing_compared: str | None = None       # why no scenario run was compared with the baseline


REPORT_KEY = pytest.StashKey[ReportState]()


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("navscenario", "navigation scenarios (pytest-navscenario)")
    for opt, ini, default, text in OPTIONS:
        group.addoption(opt, dest=ini, default=None, metavar=METAVARS[ini], help=f"{text} [ini: {ini}]")
        kind = ini_type("int") if ini == "nav_plots_max" else "string"   # its real type (issue 15)
        parser.addini(ini, text, type=kind, default=default)


def _choice(config: pytest.Config, name: str, choices: tuple[str, ...]) -> str:
    raw, where, _ = _value(config, name)
    value = raw.lower()
    if value not in choices:
        raise pytest.UsageError(f"{where}: expected one of {', '.join(choices)}, got {raw!r}")
    return value


def read_report_settings(config: pytest.Config, check_files: bool = True) -> ReportSettings:
    """Parse and check this plugin's options; pytest.UsageError on a bad value.

    ``check_files`` is off on xdist workers (a remote worker need not see the controller's files).
    """
    raw, where, base = _value(config, "nav_baseline")
    baseline = resolve_path(raw, base) if raw else None
    if check_files and baseline is not None and not baseline.is_file():
        raise pytest.UsageError(f"{where}: no results file {str(baseline)!r}; write one first with "
                                f"pytest --nav-results={raw} (with the baseline planner)")
    mode = _choice(config, "nav_baseline_mode", MODE_CHOICES)
    plots = _choice(config, "nav_plots", PLOT_CHOICES)
    raw, where, base = _value(config, "nav_plots_dir")
    plots_dir = resolve_path(raw, base) if raw else None
    if plots_dir is not None and plots_dir.exists() and not plots_dir.is_dir():
        raise pytest.UsageError(f"{where}: {raw!r} exists and is not a folder")
    raw, where, base = _value(config, "nav_html")
    html = resolve_path(raw, base) if raw else None
    if html is not None and html.is_dir():
        raise pytest.UsageError(f"{where}: {raw!r} is a folder; give a file name such as report.html")
    raw, where, _ = _value(config, "nav_plots_max")
    try:
        plots_max = int(raw)
        if plots_max < 0:
            raise ValueError
    except ValueError:
        raise pytest.UsageError(f"{where}: expected a whole number >= 0 (0 = no limit), got {raw!r}") from None
    raw, _, _ = _value(config, "nav_baseline_subject")
    return ReportSettings(baseline=baseline, mode=mode, plots=plots, plots_dir=plots_dir, html=html,
                          plots_max=plots_max, baseline_subject=raw or None)


def _is_worker(config: pytest.Config) -> bool:
    return hasattr(config, "workerinput")


def _is_search(config: pytest.Config) -> bool:
    """A --navsearch session: it runs searches, not scenario items."""
    try:
        return bool(config.getoption("navsearch") or config.getini("navsearch"))
    except (ValueError, pytest.UsageError):   # the search plugin is not loaded
        return False


def pytest_configure(config: pytest.Config) -> None:
    settings = read_report_settings(config, check_files=not _is_worker(config))
    state = ReportState(settings=settings)
    if settings.baseline is not None and not _is_worker(config):
        from ..report.results_file import ResultsFileError, read_results
        try:
            state.baseline_records = read_results(settings.baseline)
        except ResultsFileError as exc:
            raise pytest.UsageError(f"--nav-baseline: {exc}") from None
        state.baseline_index = {(r["nodeid"], int(r.get("repeat") or 0)): r for r in state.baseline_records}
    config.stash[REPORT_KEY] = state


def pytest_collection_modifyitems(session: pytest.Session, config: pytest.Config, items: list[pytest.Item]) -> None:
    """Ask the core plugin for trajectories, once scenario items exist (in every process that
    collects, i.e. each xdist worker). Done here rather than at configure time so that a pytest run
    without scenarios never imports payload.py and numpy (~0.4 s)."""
    state = config.stash.get(REPORT_KEY, None)
    if state is None or not any(hasattr(item, "nav_result") for item in items):
        return
    from .payload import request_trajectories

    if state.settings.plots == "all":
        request_trajectories(config, "all")
    elif state.settings.plots == "failed" or state.settings.html is not None:
        request_trajectories(config, "failed")


def _wants_plot(settings: ReportSettings, failed: bool) -> tuple[bool, bool]:
    """(make a plot, write it to a file)."""
    to_file = settings.plots == "all" or (settings.plots == "failed" and failed)
    in_html = settings.html is not None and failed
    return to_file or in_html, to_file


def _plot_path(config: pytest.Config, settings: ReportSettings, rec: dict[str, Any],
               artifact_dir: Path | None) -> Path:
    from ..core.files import folder_name

    repeat = int(rec.get("repeat") or 0)
    stem = "trajectory" if not repeat else f"trajectory-r{repeat}"
    if settings.plots_dir is not None:
        return settings.plots_dir / f"{folder_name(rec['nodeid'])}{'' if not repeat else f'-r{repeat}'}.png"
    if artifact_dir is None:
        from .artifacts import item_dir
        try:
            artifact_dir = item_dir(config, rec["nodeid"])
        except RuntimeError:  # the core plugin is not configured (should not happen)
            artifact_dir = None
    if artifact_dir is not None:
        return Path(artifact_dir) / "plots" / f"{stem}.png"
    return Path(config.rootpath) / DEFAULT_PLOTS_DIR / f"{folder_name(rec['nodeid'])}{'' if not repeat else f'-r{repeat}'}.png"


@pytest.hookimpl(optionalhook=True)
def pytest_navscenario_episode_report(config: pytest.Config, report: pytest.TestReport,
                                      payload: dict[str, Any], artifact_dir: Any) -> None:
    """Controller: keep the record; plot the episode if asked (or it failed)."""
    state = config.stash.get(REPORT_KEY, None)
    if state is None or _is_worker(config):
        return
    rec = payload["record"]
    state.records.append(rec)
    failed = rec["outcome"] != "success"
    if report.skipped and getattr(report, "wasxfail", None) is not None:  # xfailed: an expected failure
        state.xfailed[(rec["nodeid"], int(rec.get("repeat") or 0))] = str(report.wasxfail)
    make, to_file = _wants_plot(state.settings, failed)
    if not make:  # (without a trajectory in the payload the plot still shows layout and markers)
        return
    limit = state.settings.plots_max
    if limit and len(state.plots) >= limit and not (failed and state.settings.html is not None):
        state.not_plotted += 1
        return
    key = (rec["nodeid"], int(rec.get("repeat") or 0))
    try:
        from .payload import episode_from_payload
        from ..report.plots import png_bytes, save_figure, trajectory_figure

        episode = episode_from_payload(payload)
        fig = trajectory_figure(episode)
        if state.settings.html is not None and failed:
            from ..report.html import view_data
            view = view_data(episode)
            if view is not None:
                state.views[key] = view
        path = _plot_path(config, state.settings, rec, artifact_dir)
        if to_file:
            state.plots[key] = save_figure(fig, path)
        else:
            state.plots[key] = png_bytes(fig)
        if rec.get("requirements") and (failed or state.settings.html is not None):
            from ..report.requirement_plot import requirements_figure
            signals = requirements_figure(episode)
            if signals is not None:
                state.signal_plots[key] = (save_figure(signals, path.with_name(f"{path.stem}-requirements.png"))
                                           if to_file else png_bytes(signals))
        base = state.baseline_index.get(key)
        if (failed and base is not None and base["outcome"] == "success"
                and base["scenario_hash"] == rec["scenario_hash"]):
            side = _side_by_side(config, state, episode, base, rec)
            if side is not None:
                state.side_by_side[key] = (save_figure(side, path.with_name(f"{path.stem}-vs-baseline.png"))
                                           if to_file else png_bytes(side))
    except Exception as exc:  # a plotting bug must not hide the test results; say so at the end
        state.plot_errors.append(f"{rec['nodeid']}: {type(exc).__name__}: {exc}")


def _side_by_side(config: pytest.Config, state: ReportState, episode: Any, base: dict[str, Any],
                  rec: dict[str, Any]) -> Any:
    """A regression: re-run the baseline's subject on the same scenario with the baseline's episode
    seed and return the side-by-side figure (A = baseline | B = this run), or None with a note."""
    import dataclasses

    from ..core.errors import NavScenarioError
    from ..report.plots import comparison_figure
    from ..harness.runner import run_scenario

    from ..report.rerun import rerun_spec
    from ..subjects.loading import locate_subject

    try:   # the spec the baseline's records carry, never the planner's display name
        spec = rerun_spec(base, state.settings.baseline_subject, "the baseline", "--nav-baseline-subject")
    except NavScenarioError as exc:
        if not state.bad_baseline_subjects:
            state.notes.append(f"no side-by-side plots: {exc}")
        state.bad_baseline_subjects.add("")
        return None
    if spec in state.bad_baseline_subjects:
        return None
    locate_subject(spec, [str(config.rootpath)])
    sim = dataclasses.replace(episode.scenario.simulation, seed=int(base.get("seed") or 0))
    try:
        res_a = run_scenario(dataclasses.replace(episode.scenario, simulation=sim), spec)
    except NavScenarioError as exc:
        state.bad_baseline_subjects.add(spec)
        state.notes.append(f"no side-by-side plots: cannot re-run the baseline's subject {spec!r} ({exc}); "
                           f"give its spec with --nav-baseline-subject=SPEC")
        return None
    if res_a.outcome.value != base["outcome"]:
        state.notes.append(f"{rec['nodeid']}: the baseline's subject {spec!r} re-run gave "
                           f"{res_a.outcome.value}, the baseline file says {base['outcome']} (another "
                           f"version of it, or --nav-baseline-subject names another planner?)")
    return comparison_figure(res_a, episode, labels=(f"A (baseline: {spec})", "B (this run)"))


def _subject_and_seed(config: pytest.Config) -> tuple[str | None, int | None]:
    """This session's --nav-subject spec (None: built-in default or a conftest hook) and base seed."""
    from .state import STATE_KEY
    state = config.stash.get(STATE_KEY, None)
    if state is None:
        return None, None
    spec = state.subject.spec if state.subject.origin != "built-in default" else None
    return spec, state.settings.seed


def _cd_rootdir(config: pytest.Config) -> str:
    """'cd ROOTDIR && ' when pytest was started elsewhere (node ids are relative to the rootdir)."""
    import shlex
    if Path(config.invocation_params.dir) != Path(config.rootpath):
        return f"cd {shlex.quote(str(config.rootpath))} && "
    return ""


def _reproduce(config: pytest.Config, rec: dict[str, Any]) -> str:
    import shlex
    spec, seed = _subject_and_seed(config)
    cmd = f"{_cd_rootdir(config)}pytest {shlex.quote(rec['nodeid'])}"
    if spec:
        cmd += f" {shlex.quote(f'--nav-subject={spec}')}"
    if seed is not None:
        cmd += f" --nav-seed={seed}"
    return cmd


@pytest.hookimpl(trylast=True)
def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Controller: compare with the baseline (and gate), write the HTML report."""
    config = session.config
    state = config.stash.get(REPORT_KEY, None)
    if state is None or _is_worker(config):
        return
    s = state.settings
    if s.baseline is not None:
        from ..report.compare import compare_records
        state.comparison = compare_records(state.baseline_records, state.records,
                                           a_name=str(s.baseline), b_name="this run")
        spec, seed = _subject_and_seed(config)
        if spec is not None:
            state.comparison.subject_specs["b"] = spec
        if seed is not None:
            state.comparison.extra_args = f"--nav-seed={seed}"
        state.comparison.command_prefix = _cd_rootdir(config)
        if not config.option.collectonly:
            state.nothing_compared = _nothing_compared(state.comparison)
        if (state.comparison.has_regressions or state.nothing_compared) and s.mode == "fail":
            state.gate_failed = True
            if session.exitstatus == pytest.ExitCode.OK:
                session.exitstatus = pytest.ExitCode.TESTS_FAILED
    if s.html is not None and not _is_search(config):   # a search writes its own (search_report.py)
        try:
            _write_html(config, state)
        except Exception as exc:
            state.plot_errors.append(f"HTML report {s.html}: {type(exc).__name__}: {exc}")


def _nothing_compared(cmp: Any) -> str | None:
    """Why no scenario run of this session could be compared with the baseline (None when one
    was): a run of another suite, or one that missed the baseline's scenarios, must not pass the
    regression gate as "no regression"."""
    if cmp.pairs:
        return None
    shared = len(cmp.not_comparable)
    n_base = len(cmp.only_a) + shared
    if not n_base:
        return f"the baseline {cmp.a_name} has no records"
    if shared:
        why = (f"the {shared} scenario run(s) this run shares with it changed since it was written "
               f"(another scenario_hash)")
    else:
        why = f"this run ran none of its {n_base} scenario run(s)"
    return why + (f" ({len(cmp.only_b)} run now, not in it)" if cmp.only_b else "")


def _write_html(config: pytest.Config, state: ReportState) -> None:
    from ..report.html import Entry, write_html

    entries = []
    for rec in state.records:
        plot = state.plots.get((rec["nodeid"], int(rec.get("repeat") or 0)))
        png = plot.read_bytes() if isinstance(plot, Path) and plot.is_file() else (
            plot if isinstance(plot, bytes) else None)
        key = (rec["nodeid"], int(rec.get("repeat") or 0))
        side = state.side_by_side.get(key)
        side_png = side.read_bytes() if isinstance(side, Path) and side.is_file() else (
            side if isinstance(side, bytes) else None)
        signals = state.signal_plots.get(key)
        signals_png = signals.read_bytes() if isinstance(signals, Path) and signals.is_file() else (
            signals if isinstance(signals, bytes) else None)
        entries.append(Entry(record=rec, plot_png=png, reproduce=_reproduce(config, rec),
                             view=state.views.get(key), compare_png=side_png,
                             xfail_reason=state.xfailed.get(key), requirements_png=signals_png))
    bars = None
    if state.comparison is not None and state.comparison.pairs:
        from ..report.plots import bars_figure, png_bytes
        bars = png_bytes(bars_figure(state.comparison))
    subjects = sorted({r.get("subject") or "?" for r in state.records})
    info = [f"subject: {', '.join(subjects) or '-'}",
            f"command: pytest {' '.join(config.invocation_params.args)}"]
    write_html(state.settings.html, entries, comparison=state.comparison, bars_png=bars, info=info)
    state.html_written = state.settings.html


def _gate_line(tr: Any, mode: str, failed: str, warned: str) -> None:
    """One line for a regression-gate finding: FAILED in red under mode ``fail``, else a warning."""
    if mode == "fail":
        tr.write_line(f"navscenario: FAILED the regression gate: {failed} (--nav-baseline-mode=warn to only "
                      f"report this)", red=True, bold=True)
    else:
        tr.write_line(f"navscenario: warning: {warned} (--nav-baseline-mode=warn)", yellow=True, bold=True)


def pytest_terminal_summary(terminalreporter: Any, exitstatus: int, config: pytest.Config) -> None:
    state = config.stash.get(REPORT_KEY, None)
    if state is None or _is_worker(config):
        return
    tr = terminalreporter
    if state.comparison is not None:
        from ..report.compare import format_comparison
        tr.write_sep("=", f"navscenario comparison with the baseline {state.settings.baseline}")
        text = format_comparison(state.comparison, max_listed=20, max_unpaired=5,
                                 only_a_note="not run now (a subset selected?), not compared")
        for line in text.splitlines():
            tr.write_line(line)
        n = len(state.comparison.broke)
        why = state.nothing_compared
        if why:
            _gate_line(tr, state.settings.mode, f"nothing was compared with the baseline: {why}",
                       f"nothing was compared with the baseline: {why}")
        if n:
            _gate_line(tr, state.settings.mode, f"{n} scenario(s) the baseline passed fail now",
                       f"{n} regression(s) against the baseline")
        kept = state.comparison.broke_requirements
        if kept:
            what = ", ".join(f"{label}: {name}" for label, name in kept[:5]) + (" ..." if len(kept) > 5 else "")
            _gate_line(tr, state.settings.mode, f"{len(kept)} requirement(s) the baseline kept are violated now ({what})",
                       f"{len(kept)} requirement(s) the baseline kept are violated now ({what})")
    files = [p for p in state.plots.values() if isinstance(p, Path)]
    if files:
        folders = sorted({str(p.parent) for p in files})
        where = folders[0] if len(folders) == 1 else (
            str(state.settings.plots_dir) if state.settings.plots_dir else f"{len(folders)} folders")
        tr.write_line(f"navscenario: {len(files)} trajectory plot(s) in {where}")
    if state.not_plotted:
        tr.write_line(f"navscenario: {state.not_plotted} more item(s) not plotted: at most "
                      f"{state.settings.plots_max} plots per session (--nav-plots-max=N, 0 = no limit)")
    if state.html_written is not None:
        tr.write_line(f"navscenario: HTML report written to {state.html_written}")
    sides = [p for p in state.side_by_side.values() if isinstance(p, Path)]
    if sides:
        tr.write_line(f"navscenario: {len(sides)} side-by-side plot(s) of regressions (baseline | this run), "
                      f"e.g. {sides[0]}")
    for note in state.notes:
        tr.write_line(f"navscenario: {note}", yellow=True)
    for err in state.plot_errors:
        tr.write_line(f"navscenario: could not draw {err}", red=True)
