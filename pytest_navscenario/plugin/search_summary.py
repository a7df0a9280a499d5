"""The terminal summary of the searches of a session: per search what it found, how its failures
held, where the files went."""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

def _rel(config: pytest.Config, path: Path) -> str:
    try:
        return Path(path).resolve().relative_to(Path(config.rootpath).resolve()).as_posix()
    except ValueError:
        return str(path)


def _one_way_everywhere(r: Any) -> str:
    """"outcome: message" when every simulation of the search phase (two at least) was a subject or
    harness error with the same message (its tick aside): a broken subject, not the layouts; else ""."""
    import re

    ran = [c for c in r.candidates if c.phase == "search"]
    if len(ran) < 2 or any(c.outcome not in ("subject-error", "harness-error") for c in ran):
        return ""
    said = {(c.outcome, re.sub(r"^planner error at tick \d+ \(t=[^)]*\): ", "", c.message)) for c in ran}
    return "" if len(said) != 1 else "{}: {}".format(*said.pop())


def _holding_lines(r: Any) -> list[str]:
    """What the confirmation of failures under the seed's randomness did (search/holding.py)."""
    if not r.randomness:
        return ["  the seed has no randomness (no sensor noise, drift or perturbation): one run decides each "
                "failure; search under noise with --nav-sensor-model realistic"] if r.failures else []
    noise = ", ".join(r.randomness)
    if not r.hold:
        return [f"  confirmation off (--navsearch-hold 0): each failure counted after one run, though {noise} "
                f"may make it pass the next time"]
    out = [f"  failures that hold (fail with probability >= {r.hold:g} under {noise}, decided by a "
           f"sequential test): {len(r.failures)}; {r.confirm_sims} confirmation run(s)"
           + (f", {r.confirm_sims / len(r.failures):.1f} per failure that holds" if r.failures else "")]
    if r.rejected:
        out.append(f"  {len(r.rejected)} failure(s) did not hold (failed once, then passed under fresh noise: "
                   f"knife-edges, not frozen)")
    if r.unconfirmed:
        cut = r.interrupted and any(f.status == "found" for f in r.unconfirmed)
        out.append(f"  {len(r.unconfirmed)} failure(s) still under test when the search "
                   + ("was cut short (frozen as found, unconfirmed)" if cut else
                      "ran out of budget (not frozen; a larger --budget confirms them)"))
    return out


def format_entry(entry: dict[str, Any], config: pytest.Config) -> list[str]:
    from .search_report import lowest_clearance_text

    r = entry["report"]
    by = ", ".join(f"{k} {v}" for k, v in sorted(r.failures_by_outcome().items())) or "none"
    disc = ", ".join(f"{k} {v}" for k, v in sorted(r.discarded.items()))
    version = f" {r.subject_version}" if r.subject_version else ""
    lines = [f"{r.seed_name} vs {r.subject}{version} ({r.strategy}, search seed {r.seed_value}): "
             f"{r.sims_used}/{r.budget} sims, {r.discarded_total} discarded" + (f" ({disc})" if disc else "")
             + f", {len(r.failures)} distinct failure(s) ({by}), " + lowest_clearance_text(r)
             + (f", first at sim {r.first_failure}" if r.first_failure else "")
             + f", {r.sims_used} sims searching" + (f" ({r.confirm_sims} of them confirming)" if r.confirm_sims else "")
             + f" + {r.shrink_sims} shrinking"
             + (f" (shrink budget {r.shrink_total})" if r.shrink_total else "") + f", {r.wall_time:.1f} s"]
    lines += _holding_lines(r)
    from ..search.discards import discard_advice    # why many were discarded, what to change (issue 32)
    lines += [f"  {a.line()}" for a in discard_advice(r.discarded, r.sims_used, getattr(entry["job"], "space", None))]
    unshrunk = sum(1 for f in r.failures if f.note.startswith("not shrunk: the shrink budget"))
    if unshrunk:
        lines.append(f"  {unshrunk} of {len(r.failures)} failure(s) frozen as found: the shrink budget "
                     f"({r.shrink_total} simulations) went to the most severe and earliest ones (raise "
                     f"--navsearch-shrink-budget, e.g. 50%, to shrink more)")
    same = _one_way_everywhere(r)
    if same:
        lines.append(f"  every one of the {r.sims_used} simulations ended the same way: {same}; the subject fails "
                     f"whatever the layout: fix it (navscenario check-planner SPEC) before searching")
    if r.batching:
        lines.append(f"  batches (--nav-batch): {r.batching}")
    if r.skipped:
        lines.append(f"  {r.skipped} candidate(s) repeating a simulated one or next to a known failure were "
                     f"redrawn without simulating them")
    if r.interrupted:
        lines.append(f"  CUT SHORT: {r.stop_reason or 'interrupted'}; the failures found so far are kept "
                     f"(unshrunk ones are frozen as found)")
    elif r.stop_reason:
        lines.append(f"  stopped early: {r.stop_reason}")
    for f in entry["files"]:
        state = "new " if f.new else "kept"
        c = f.clearance
        held = f", {f.estimate.describe()}" if f.estimate is not None and f.estimate.runs else ""
        lines.append(f"  {state} {_rel(config, f.path)}  {f.what}, clearance "
                     + (f"{c:.3f} m" if math.isfinite(c) else "n/a") + held + ("" if f.new else " (already frozen)"))
    pictures = [row.picture for row in entry.get("rows") or [] if row.picture]
    if pictures:
        folders = sorted({str(Path(p).parent) for p in pictures})
        lines.append(f"  pictures of {len(pictures)} failure(s) in {folders[0] if len(folders) == 1 else ', '.join(folders)}/ "
                     f"(the frozen file's name, .png)")
    if entry["log"] is not None:
        lines.append(f"  log  {_rel(config, entry['log'])}")
    suite = entry.get("suite")
    if suite is not None:
        lines.append(f"  suite {_rel(config, suite.folder)}/: {len(suite.files)} scenario file(s), "
                     f"{suite.failing} failing for {r.subject}"
                     + (f", {suite.replaced} of an earlier suite removed" if suite.replaced else "")
                     + f" (re-run: pytest {_rel(config, suite.folder.parent)} --nav-subject=...)")
    if entry["error"]:
        lines.append(f"  ERROR {entry['error']}")
    return lines
