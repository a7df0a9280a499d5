"""A search's report as plain data and back: what crosses from an xdist worker to the controller on
the call report (``report.navsearch``), offsets kept as exact floats."""
from __future__ import annotations

import math
from typing import Any

def report_to_payload(report: Any) -> dict[str, Any]:
    """SearchReport as plain data (crosses from xdist workers); offsets kept as exact floats."""
    def cand(c):
        return {"sim": c.sim, "phase": c.phase, "origin": c.origin, "offsets": list(c.offsets),
                "outcome": c.outcome, "clearance": c.clearance if math.isfinite(c.clearance) else None,
                "culprit": c.culprit, "message": c.message,
                "metrics": {k: (v if not isinstance(v, float) or math.isfinite(v) else None)
                            for k, v in c.metrics.items()},
                "scenario_hash": c.scenario_hash, "wall_time": c.wall_time,
                "robustness": c.robustness if math.isfinite(c.robustness) else None,
                "signature": list(c.signature), "progress": c.progress, "run": c.run}
    index = {id(c): i for i, c in enumerate(report.candidates)}

    def failure(f):
        return {"found": index[id(f.found)], "shrunk": index[id(f.shrunk)], "shrink_sims": f.shrink_sims,
                "note": f.note, "status": f.status, "estimate": f.estimate.to_data()}
    return {
        "seed_name": report.seed_name, "seed_source": report.seed_source, "subject": report.subject,
        "subject_version": report.subject_version, "strategy": report.strategy,
        "seed_value": report.seed_value, "budget": report.budget, "shrink_budget": report.shrink_budget,
        "params": report.params, "sims_used": report.sims_used, "shrink_sims": report.shrink_sims,
        "shrink_total": report.shrink_total,
        "discarded": dict(report.discarded), "discard_log": [list(d) for d in report.discard_log],
        "skipped": report.skipped, "interrupted": report.interrupted,
        "stop_reason": report.stop_reason, "wall_time": report.wall_time,
        "episode_seed": report.episode_seed, "first_failure": report.first_failure,
        "batching": report.batching,
        "candidates": [cand(c) for c in report.candidates],
        "failures": [failure(f) for f in report.failures],
        "rejected": [failure(f) for f in report.rejected],
        "unconfirmed": [failure(f) for f in report.unconfirmed],
        "hold": report.hold, "randomness": list(report.randomness), "confirm_sims": report.confirm_sims,
    }


def payload_to_report(data: dict[str, Any], space: Any) -> Any:
    """Inverse of report_to_payload; candidate scenarios are rebuilt from the seed + offsets."""
    from ..search.engine import Candidate, Failure, SearchReport
    from ..search.holding import Estimate

    cands = []
    for c in data["candidates"]:
        offsets = tuple(float(v) for v in c["offsets"])
        metrics = {k: (math.nan if v is None else v) for k, v in c["metrics"].items()}
        cands.append(Candidate(c["sim"], c["phase"], c["origin"], offsets, c["outcome"],
                               math.nan if c["clearance"] is None else c["clearance"], c["culprit"],
                               c["message"], metrics, c["scenario_hash"], c["wall_time"], space.apply(offsets),
                               math.inf if c.get("robustness") is None else c["robustness"],
                               tuple(c.get("signature", ())), c.get("progress", 0.0), run=c.get("run", 0)))
    fields = {k: data[k] for k in ("seed_name", "seed_source", "subject", "subject_version", "strategy",
                                   "seed_value", "budget", "shrink_budget", "params", "sims_used",
                                   "shrink_sims", "discarded", "interrupted", "stop_reason", "wall_time",
                                   "episode_seed")}
    report = SearchReport(**fields)
    report.skipped = data.get("skipped", 0)
    report.discard_log = [(int(n), str(k)) for n, k in data.get("discard_log", [])]
    report.first_failure = data.get("first_failure", 0)
    report.shrink_total = data.get("shrink_total", 0)
    report.batching = data.get("batching", "")
    report.candidates = cands
    report.hold, report.randomness = data.get("hold", 0.0), tuple(data.get("randomness", ()))
    report.confirm_sims = data.get("confirm_sims", 0)

    def failures(key: str) -> list[Any]:
        return [Failure(cands[f["found"]], cands[f["shrunk"]], f["shrink_sims"], f["note"],
                        f.get("status", "found"), Estimate.from_data(f.get("estimate")))
                for f in data.get(key, [])]
    report.failures, report.rejected, report.unconfirmed = failures("failures"), failures("rejected"), \
        failures("unconfirmed")
    return report
