"""Repeated runs (``--nav-repeat``): which scenarios are flaky, i.e. gave different outcomes
under different noise seeds. Pure functions of results-file records."""
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
