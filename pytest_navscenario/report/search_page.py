"""The HTML report of a failure search (``pytest --navsearch NAME --nav-html=search.html``) and
its progress chart.

Plain data in, a self-contained page out (the same skeleton, CSS and time-slider viewer as the
run report, html.py): one section per search with what it found (each frozen failure with its
picture, outcome, clearance and the command that re-runs it) and how it went (distinct failures,
best fitness and discarded candidates over the simulations, as a chart; outcomes; discards by
reason). The plugin (plugin/search_report.py) turns a SearchReport into these dataclasses; this
module does not know the search package (report and search are sibling layers).

``FailureRow`` has optional fields for what a search may know about a failure beyond one run:
``probability`` and ``interval`` (the share of noisy re-runs that fail, with its 95 % interval);
the page shows their column only when a row has them.
"""
from __future__ import annotations

import datetime as _dt
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from ..core.files import atomic_write_text

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

OUTCOME_ORDER = ("success", "safety-stop", "requirement", "timeout", "collision", "subject-error", "harness-error")


@dataclass
class FailureRow:
    """One frozen failure of a search."""
    file: str                      # the frozen scenario file (rootdir-relative when inside it)
    new: bool                      # False: this failure was frozen by an earlier search (kept)
    outcome: str
    message: str
    culprit: str
    clearance: float               # m, the frozen (shrunk) layout's minimum clearance
    found_at: int                  # simulation number it was found at
    shrink_sims: int = 0
    note: str = ""                 # e.g. "not shrunk: ..."
    reproduce: str = ""            # the command that re-runs it
    plot_png: bytes | None = None
    picture: str | None = None     # the PNG file written for it, if any
    view: dict[str, Any] | None = None    # html.view_data of its re-run: the time-slider view
    rerun: str = ""                # what the re-run as a pytest item gave, when it differs
    probability: float | None = None               # share of noisy re-runs that fail (optional)
    interval: tuple[float, float] | None = None    # its 95 % interval (optional)

    @property
    def anchor(self) -> str:
        import hashlib
        return hashlib.sha1(self.file.encode()).hexdigest()[:12]


@dataclass
class Progress:
    """Per simulation of the search phase, in order: what the chart draws."""
    sims: list[int] = field(default_factory=list)
    outcomes: list[str] = field(default_factory=list)
    robustness: list[float] = field(default_factory=list)    # each candidate's (nan: harness error)
    best: list[float] = field(default_factory=list)          # lowest robustness so far
    failures: list[int] = field(default_factory=list)        # distinct failures found so far
    discarded: list[int] = field(default_factory=list)       # candidates discarded so far


@dataclass
class SearchSection:
    """One search: the facts of its summary, how it went, and its failures."""
    title: str                                   # "person-crossing vs dwa 1.1"
    facts: list[tuple[str, str]]                 # (label, value), in order
    progress: Progress
    failures: list[FailureRow]
    outcomes: dict[str, int] = field(default_factory=dict)         # search phase
    shrink_outcomes: dict[str, int] = field(default_factory=dict)  # shrink phase
    discarded: dict[str, int] = field(default_factory=dict)        # reason -> count
    skipped: int = 0
    notes: list[str] = field(default_factory=list)                 # cut short, unshrunk, errors
    discard_advice: list[str] = field(default_factory=list)        # why many were discarded, what to change
    chart_png: bytes | None = None

    @property
    def anchor(self) -> str:
        import hashlib
        return "s-" + hashlib.sha1(self.title.encode()).hexdigest()[:10]

    @property
    def has_probability(self) -> bool:
        return any(f.probability is not None for f in self.failures)


def progress_figure(progress: Progress, title: str = "") -> "Figure":
    """How the search went, over its simulations: distinct failures found so far (top); each
    candidate's robustness, coloured by outcome, and the lowest so far (middle; below 0 = it
    failed); candidates discarded before simulation so far (bottom). The title (the scenario's
    name) drawn as written."""
    from .plots import as_written

    return as_written(_progress_figure)(progress, title)


def _progress_figure(progress: Progress, title: str) -> "Figure":
    import numpy as np

    from .plots import OUTCOME_COLOURS, _figure

    fig = _figure(8.0, 6.4)
    top, mid, low = fig.subplots(3, 1, sharex=True, height_ratios=(1.0, 1.6, 0.8))
    sims = np.asarray(progress.sims, dtype=float)
    if len(sims):
        top.step(sims, progress.failures, where="post", color="#c62828", lw=1.6)
        rob = np.asarray(progress.robustness, dtype=float)
        colours = [OUTCOME_COLOURS.get(o, "#9e9e9e") for o in progress.outcomes]
        mid.scatter(sims, np.where(np.isfinite(rob), rob, np.nan), s=10, c=colours, zorder=3, lw=0)
        mid.step(sims, progress.best, where="post", color="#212121", lw=1.2, label="lowest so far")
        low.step(sims, progress.discarded, where="post", color="#616161", lw=1.4)
    else:
        mid.text(0.5, 0.5, "no simulation", transform=mid.transAxes, ha="center", va="center")
    mid.axhline(0.0, color="#c62828", lw=0.8, ls="--")
    top.set_ylabel("distinct\nfailures")
    mid.set_ylabel("robustness\n(< 0: failed)")
    low.set_ylabel("discarded\n(so far)")
    low.set_xlabel("simulation")
    for ax in (top, mid, low):
        ax.grid(True, color="#e0e0e0", lw=0.6)
        ax.set_axisbelow(True)
    for ax in (top, low):
        ax.yaxis.get_major_locator().set_params(integer=True)
        ax.set_ylim(bottom=0, top=max(1.0, ax.get_ylim()[1]))
    from matplotlib.lines import Line2D
    seen = [o for o in OUTCOME_ORDER if o in set(progress.outcomes)]
    handles = [Line2D([], [], marker="o", ls="none", color=OUTCOME_COLOURS.get(o, "#9e9e9e"), label=o) for o in seen]
    handles.append(Line2D([], [], color="#212121", lw=1.2, label="lowest so far"))
    mid.legend(handles=handles, fontsize=7, loc="best", ncol=3, framealpha=0.85)
    if title:
        top.set_title(title, fontsize=9)
    return fig


def build_search_html(sections: Sequence[SearchSection], *, title: str = "navsearch report",
                      info: Sequence[str] = ()) -> str:
    """The page as one HTML string (templates/search_report.html.j2)."""
    from .html import METRICS, _environment

    total = sum(len(s.failures) for s in sections)
    overview = (f"{len(sections)} search(es), {total} distinct failure(s) frozen" if sections
                else "no search finished")
    return _environment().get_template("search_report.html.j2").render(
        title=title, info=list(info), sections=list(sections), overview=overview, records=[],
        stamp=_dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"), metrics=METRICS,
        outcome_order=OUTCOME_ORDER, finite=lambda v: isinstance(v, (int, float)) and math.isfinite(v))


def write_search_html(path: str | os.PathLike, sections: Sequence[SearchSection], **kwargs: Any) -> Path:
    """Write the search report atomically; return its path."""
    path = Path(path)
    atomic_write_text(path, build_search_html(sections, **kwargs))
    return path
