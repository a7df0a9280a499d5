"""The paper's two-sided bar chart of a comparison (success up, failures by outcome down, A
beside B, per family). matplotlib is imported inside the functions."""
from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .figures import _figure, as_written, save_figure

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from .compare import Comparison

A_COLOUR, B_COLOUR = "#7f9fbf", "#1f4e79"


FAILURE_HATCHES = {"safety-stop": "///", "timeout": "..", "collision": "xx", "subject-error": "--", "requirement": "\\\\"}


@as_written
def bars_figure(cmp: "Comparison") -> "Figure":
    """The paper's two-sided bar chart, with every way of failing: per family, the success rate
    up and the failures down, stacked by outcome (safety stop, timeout, collision, subject error;
    each hatched its own way, its share written inside when there is room), A beside B. Error
    bars: 95 % Wilson intervals of the success rate (up) and of all failures together (down);
    n and McNemar's p under each family."""
    from matplotlib.patches import Patch

    rows = list(cmp.families) + ([cmp.overall] if len(cmp.families) > 1 else [])
    fig = _figure(max(6.0, 1.5 + 1.3 * len(rows)), 5.8)
    ax = fig.add_subplot()
    x = np.arange(len(rows), dtype=float)
    width = 0.38
    failing = [o for o in FAILURE_HATCHES
               if any(getattr(r, side)[o].count for r in rows for side in ("a", "b"))] or ["safety-stop"]
    halo = dict(boxstyle="square,pad=0.1", fc="white", ec="none", alpha=0.7)
    for side, offset, colour, name, subject in (("a", -width / 2, A_COLOUR, "A", cmp.a_subject),
                                                ("b", width / 2, B_COLOUR, "B", cmp.b_subject)):
        rates = [getattr(r, side) for r in rows]
        ok = np.array([0.0 if rt["success"].n == 0 else 100 * rt["success"].rate for rt in rates])
        err = np.maximum(np.array([[100 * (rt["success"].rate - rt["success"].low) if rt["success"].n else 0 for rt in rates],
                                   [100 * (rt["success"].high - rt["success"].rate) if rt["success"].n else 0 for rt in rates]]), 0.0)
        label = f"{name}: {subject}" if len(subject) < 40 else name
        ax.bar(x + offset, ok, width, color=colour, ec=colour, label=label, yerr=err, capsize=3,
               error_kw=dict(lw=0.8, ecolor="#424242"), zorder=3)
        for xi, v in zip(x + offset, ok):
            ax.annotate(f"{v:.0f}%", (xi, v), xytext=(0, 3), textcoords="offset points", ha="center",
                        va="bottom", fontsize=7, zorder=4, bbox=halo)
        bottom = np.zeros(len(rows))
        for outcome in failing:
            vals = np.array([0.0 if rt[outcome].n == 0 else 100 * rt[outcome].rate for rt in rates])
            ax.bar(x + offset, -vals, width, bottom=-bottom, color=colour, hatch=FAILURE_HATCHES[outcome],
                   ec="white", lw=0.5, zorder=3)
            total = np.array([sum(100 * rt[o].rate for o in failing if rt[o].n) for rt in rates])
            for xi, b0, v, t in zip(x + offset, bottom, vals, total):
                if v >= 9 and v < t - 0.5:   # room for the share inside, and not the whole stack
                    ax.annotate(f"{v:.0f}%", (xi, -(b0 + v / 2)), ha="center", va="center", fontsize=6.5,
                                zorder=4, bbox=halo)
            bottom += vals
        # all failures together: the interval of 1 - success, below the stack
        low = np.array([[100 * (rt["success"].high - rt["success"].rate) if rt["success"].n else 0 for rt in rates],
                        [100 * (rt["success"].rate - rt["success"].low) if rt["success"].n else 0 for rt in rates]])
        ax.errorbar(x + offset, -bottom, yerr=np.maximum(low, 0.0), fmt="none", ecolor="#424242",
                    elinewidth=0.8, capsize=3, zorder=4)
        for xi, v in zip(x + offset, bottom):
            ax.annotate(f"{v:.0f}%", (xi, -v), xytext=(0, -3), textcoords="offset points", ha="center",
                        va="top", fontsize=7, zorder=4, bbox=halo)
    if not rows or not cmp.pairs:
        ax.text(0.5, 0.5, "no comparable scenario pairs:\nsee the 'only in A / only in B / not comparable' lists",
                transform=ax.transAxes, ha="center", va="center", fontsize=10, color="#c62828")
    ax.axhline(0, color="black", lw=0.8)
    ax.set_xticks(x, [f"{r.family}\nn={r.n}" + (f"\np={r.mcnemar_p:.2g}" if r.n else "") for r in rows],
                  fontsize=8)
    ax.set_ylim(-118, 115)
    ticks = np.arange(-100, 101, 25)
    ax.set_yticks(ticks, [f"{abs(t)}" for t in ticks])
    ax.set_ylabel("failed %   |   success %")
    ax.grid(True, axis="y", color="#e0e0e0", zorder=0)
    ax.set_title(f"Success (up) and failures by outcome (down) per family, A vs B\n"
                 f"A = {cmp.a_subject}   B = {cmp.b_subject}   (error bars: 95 % Wilson; p: McNemar)",
                 fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    handles += [Patch(facecolor="white", edgecolor="#424242", hatch=FAILURE_HATCHES[o], label=o) for o in failing]
    labels += failing
    ax.legend(handles, labels, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.18),
              ncol=2 + len(failing), frameon=False)
    return fig


def save_bars(cmp: "Comparison", path: str | os.PathLike) -> Path:
    """Write the two-sided bar chart of a comparison as PNG."""
    return save_figure(bars_figure(cmp), path)
