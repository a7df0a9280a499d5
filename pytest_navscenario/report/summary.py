"""The end-of-run table (like table I of the ANYmal/Surrealist paper), per scenario family:
count, each outcome's rate with a 95 % Wilson interval, and min / mean / max of the main metrics.

Pure functions of results-file records (results.make_record), so the same table can be printed
from a saved ``--nav-results`` file: ``print(format_summary(read_results(path)))``.
"""
from __future__ import annotations

from collections import defaultdict
from typing import Any, Iterable

from .stats import wilson_interval

RATE_OUTCOMES = ("success", "safety-stop", "timeout", "collision")
METRICS = (("min_clearance", "min clearance [m]"), ("path_efficiency", "path efficiency"),
           ("duration", "duration [s]"))
ALL = "all"


def group_by_family(records: Iterable[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
    groups: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for rec in records:
        groups[rec.get("family") or "(no family)"].append(rec)
    return dict(sorted(groups.items()))


def rate_cell(k: int, n: int) -> str:
    """'40.0% [23.4-59.3]': rate and 95 % Wilson interval, in percent."""
    lo, hi = wilson_interval(k, n)
    return f"{100 * k / n:5.1f}% [{100 * lo:4.1f}-{100 * hi:5.1f}]" if n else "n/a"


def metric_cell(values: list[float]) -> str:
    """'min / mean / max' of the finite values (null = not defined is skipped)."""
    vals = [float(v) for v in values if v is not None]
    if not vals:
        return "n/a"
    return f"{min(vals):.2f} / {sum(vals) / len(vals):.2f} / {max(vals):.2f}"


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    fmt = lambda row: "  ".join(c.ljust(w) if i == 0 else c.rjust(w)  # noqa: E731
                                for i, (c, w) in enumerate(zip(row, widths)))
    return [fmt(header), "  ".join("-" * w for w in widths), *(fmt(r) for r in rows)]


def format_summary(records: list[dict[str, Any]]) -> str:
    """Two aligned tables (rates, metrics) with one row per family and an 'all' row."""
    if not records:
        return "no scenario episodes ran"
    groups = group_by_family(records)
    if len(groups) > 1:
        groups[ALL] = list(records)
    outcomes = list(RATE_OUTCOMES)
    for extra in ("fall", "requirement", "subject-error"):          # a column only when some episode had it
        if any(r["outcome"] == extra for r in records):
            outcomes.append(extra)

    rate_rows, metric_rows = [], []
    for family, recs in groups.items():
        n = len(recs)
        rate_rows.append([family, str(n)] +
                         [rate_cell(sum(r["outcome"] == o for r in recs), n) for o in outcomes])
        metric_rows.append([family] + [metric_cell([(r.get("metrics") or {}).get(key) for r in recs])
                                       for key, _ in METRICS])
    lines = ["outcome rates with 95 % Wilson intervals:"]
    lines += _table(["family", "n", *outcomes], rate_rows)
    lines += ["", "metrics (min / mean / max):"]
    lines += _table(["family", *(label for _, label in METRICS)], metric_rows)
    return "\n".join(lines)
