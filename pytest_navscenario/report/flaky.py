"""Repeated runs (``--nav-repeat``): which scenarios are flaky, i.e. gave different outcomes
under different noise seeds, and which frozen failures of the search no longer hold. Pure
functions of results-file records (and, for the frozen failures, their provenance)."""
from __future__ import annotations

from collections import Counter, defaultdict
from typing import Any, Iterable


def scenario_key(record: dict[str, Any]) -> tuple[str, str]:
    """Records of the same scenario file and name are repeats of one scenario."""
    return record.get("path", ""), record.get("scenario", "")


def outcome_counts(records: Iterable[dict[str, Any]]) -> dict[tuple[str, str], Counter]:
    counts: dict[tuple[str, str], Counter] = defaultdict(Counter)
    for rec in records:
        counts[scenario_key(rec)][rec["outcome"]] += 1
    return counts


def annotate_repeats(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Copies of the records with ``runs``, ``outcome_counts`` and ``flaky`` of their scenario."""
    counts: dict[tuple[str, str], dict[str, int]] = {}   # plain dicts: 500 Counters cost ~25 ms
    for rec in records:
        c = counts.setdefault(scenario_key(rec), {})
        c[rec["outcome"]] = c.get(rec["outcome"], 0) + 1
    out = []
    for rec in records:
        c = counts[scenario_key(rec)]
        out.append({**rec, "runs": sum(c.values()), "outcome_counts": dict(sorted(c.items())),
                    "flaky": len(c) > 1})
    return out


def format_flaky(records: list[dict[str, Any]]) -> str:
    """One line per flaky scenario with its per-outcome counts, or a line saying there are none."""
    counts = outcome_counts(records)
    flaky = {key: c for key, c in sorted(counts.items()) if len(c) > 1}
    if not flaky:
        return f"no flaky scenarios: each of {len(counts)} scenario(s) had the same outcome in every run"
    lines = [f"{len(flaky)} of {len(counts)} scenario(s) gave different outcomes under different noise seeds:"]
    for (path, name), c in flaky.items():
        runs = sum(c.values())
        detail = ", ".join(f"{outcome} {n}/{runs}" for outcome, n in c.most_common())
        lines.append(f"  {path}::{name}: {detail}")
    return "\n".join(lines)


def holding_rows(records: list[dict[str, Any]], measured: dict[tuple[str, str], dict[str, Any]]
                 ) -> list[dict[str, Any]]:
    """Per frozen failure of the search (``measured``: scenario key -> its provenance, with the
    ``failure_probability`` the search measured) that ran here: how often it failed now, its 95 %
    interval, and whether it still holds. It no longer holds when the whole interval lies below
    the threshold it was confirmed against (``hold_threshold``): the planner now passes it too
    often for a failure that held (one that passes every run is fixed)."""
    from ..core.rates import clopper_pearson

    runs: dict[tuple[str, str], list[bool]] = {}
    for rec in records:
        key = scenario_key(rec)
        if key in measured:
            runs.setdefault(key, []).append(rec["outcome"] not in ("success", "skipped"))
    rows = []
    for key, fails in sorted(runs.items()):
        prov = measured[key]
        k, n = sum(fails), len(fails)
        lo, hi = clopper_pearson(k, n)
        threshold = float(prov.get("hold_threshold") or 0.0)
        rows.append({"path": key[0], "scenario": key[1], "failed": k, "runs": n, "interval": (lo, hi),
                     "measured": prov.get("failure_probability"), "measured_interval":
                     prov.get("failure_probability_interval"), "measured_runs": prov.get("confirmation_runs"),
                     "threshold": threshold, "holds": not (threshold and hi < threshold) and k > 0,
                     "mujoco_version": prov.get("mujoco_version")})
    return rows


def format_holding(rows: list[dict[str, Any]]) -> str:
    """One line per frozen failure run with repeats: does it still hold? (One that does not and was
    found under another MuJoCo release says so.)"""
    from ..core.versions import other_mujoco

    lost = [r for r in rows if not r["holds"]]
    lines = [f"{len(rows) - len(lost)} of {len(rows)} frozen failure(s) still hold"
             + (f"; {len(lost)} no longer hold:" if lost else ":")]
    for r in sorted(rows, key=lambda r: r["holds"]):
        lo, hi = r["interval"]
        was = ""
        if r["measured"] is not None:
            mlo, mhi = r["measured_interval"] or (0.0, 1.0)
            was = (f"; the search measured {r['measured']:.2f} ({mlo:.2f}-{mhi:.2f}) over "
                   f"{r['measured_runs'] or 1} run(s)")
        verdict = ("holds" if r["holds"] else "FIXED (passes every run)" if not r["failed"]
                   else f"NO LONGER HOLDS (below the threshold {r['threshold']:g})")
        lines.append(f"  {r['path']}::{r['scenario']}: fails in {r['failed']}/{r['runs']} runs "
                     f"(95 % {lo:.2f}-{hi:.2f}){was}: {verdict}")
        note = "" if r["holds"] else other_mujoco(r.get("mujoco_version"))
        if note:
            lines.append(f"    {note}")
    return "\n".join(lines)
