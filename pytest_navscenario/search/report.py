"""What a search found: its candidates, its distinct failures and the report that holds them.

``Candidate`` (one simulated layout and what its episode showed), ``Failure`` (a distinct way of
failing, as found and as shrunk), ``SearchReport`` (the whole search) and the ``Recorder`` protocol
a search tells as it goes (search/freeze.py writes them). Plain data: the engine, the evaluators
(parallel.py, batched.py), freezing and the plugin all read them without importing the engine.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Protocol

from ..scenario.model import Scenario
from .holding import Estimate
from .space import SearchSpace


@dataclass
class Candidate:
    """One simulated candidate."""
    sim: int                      # 1-based simulation number within its phase
    phase: str                    # "search" or "shrink"
    origin: str                   # seed / explore / mutate / place / insert / random / climb / shrink
    offsets: tuple[float, ...]
    outcome: str                  # Outcome value, or "harness-error" if the simulation itself failed
    clearance: float              # metrics.min_clearance (nan on harness error)
    culprit: str                  # obstacle hit / stopped for / nearest
    message: str
    metrics: dict[str, Any]
    scenario_hash: str
    wall_time: float
    scenario: Scenario | None = field(default=None, repr=False, compare=False)
    robustness: float = math.inf  # fitness.py: < 0 failed, small = near a failure
    signature: tuple = ()         # fitness.py: the cause signature
    progress: float = 0.0         # 0..1 along the seed's route where the episode ended
    path: tuple = field(default=(), repr=False)      # robot centre samples (x, y)
    closest: tuple = field(default=(), repr=False)   # (t, x, y) of the closest approach
    run: int = 0                  # noise run: 0 the search's own, k >= 1 the k-th confirmation run

    @property
    def failed(self) -> bool:
        return self.outcome not in ("success", "harness-error")

    @property
    def fitness(self) -> tuple[int, float]:
        """Smaller is better: failures first, then lower robustness (closer to failing)."""
        r = self.robustness if math.isfinite(self.robustness) else math.inf
        return (0 if self.failed else 1, r)

    def to_dict(self, space: SearchSpace) -> dict[str, Any]:
        return {"sim": self.sim, "phase": self.phase, "origin": self.origin,
                "params": space.as_mapping(self.offsets), "outcome": self.outcome,
                "clearance": _finite(self.clearance), "culprit": self.culprit,
                "message": self.message, "metrics": {k: _finite(v) for k, v in self.metrics.items()},
                "scenario_hash": self.scenario_hash, "wall_time": round(self.wall_time, 6),
                "robustness": _finite(round(self.robustness, 6)), "signature": list(self.signature),
                "run": self.run}


@dataclass
class Failure:
    """A distinct failure: as found, and after shrinking toward the seed.

    ``status`` says how far the search got with it (and is written in its frozen file's
    provenance): "found" (failed once: not yet confirmed nor shrunk; the search was still running,
    or was cut short, before it was done with it), "confirmed" (it holds under the scenario's
    randomness, holding.py; not yet shrunk), "shrunk" (final: shrunk toward the seed, still
    holding), "unshrunk" (final: kept as found, ``note`` says why); or, not frozen, "rejected" (it
    does not hold: a knife-edge) and "unconfirmed" (the budget ran out before the test decided).
    ``estimate`` is what the confirmation runs of its current layout (``shrunk``) showed."""
    found: Candidate
    shrunk: Candidate
    shrink_sims: int = 0
    note: str = ""                # e.g. "shrink cap reached", "did not reproduce"
    status: str = "found"
    estimate: Estimate = field(default_factory=lambda: Estimate(decision="off", threshold=0.0))

    @property
    def key(self) -> int:
        """Names the failure for the whole search: the simulation that found it."""
        return self.found.sim


@dataclass
class SearchReport:
    seed_name: str
    seed_source: str | None
    subject: str
    subject_version: str | None
    strategy: str
    seed_value: int
    budget: int
    shrink_budget: "int | str"    # as given: "25%" (share of the budget) or N (per failure, the old form)
    params: list[str]
    sims_used: int = 0
    shrink_sims: int = 0
    shrink_total: int = 0         # simulations the shrink phase was allowed (shrink_plan's total)
    discarded: dict[str, int] = field(default_factory=dict)   # reason -> count
    # (simulations recorded by then, reason) of each discarded candidate: when the search spent
    # its draws on invalid layouts (the search report's chart)
    discard_log: list[tuple[int, str]] = field(default_factory=list)
    skipped: int = 0              # repeats of a simulated candidate, redrawn without simulating
    candidates: list[Candidate] = field(default_factory=list)  # search + shrink sims, in order
    failures: list[Failure] = field(default_factory=list)     # distinct failures that hold, in order confirmed
    hold: float = 0.0             # the failure probability a failure must show to count (0: one run counts)
    randomness: tuple[str, ...] = ()   # what varies between runs of the seed (scenario.model.randomness)
    confirm_sims: int = 0         # of sims_used: confirmation runs (holding.py)
    rejected: list[Failure] = field(default_factory=list)     # failed once, did not hold (knife-edges)
    unconfirmed: list[Failure] = field(default_factory=list)  # the test undecided when the search ended
    under_test: int = 0           # failures being confirmed now (the live progress line)
    interrupted: bool = False
    stop_reason: str = ""
    wall_time: float = 0.0
    episode_seed: int | None = None   # the run's base seed (--nav-seed) every episode used
    first_failure: int = 0            # simulation number of the first failing candidate (0: none)
    batching: str = ""                # how the simulations ran in batches (search/batched.py), or ""
    worker_deaths: list[str] = field(default_factory=list)   # workers that died, their jobs run again

    @property
    def discarded_total(self) -> int:
        return sum(self.discarded.values())

    def _scan(self) -> tuple:
        """(best, lowest clearance, lowest robustness) of the search phase, updated with the
        candidates added since the last call: the live progress line asks after every simulation,
        and a rescan would make a search quadratic in its budget."""
        cache = self.__dict__.get("_bests")
        if cache is None or cache[0] > len(self.candidates):
            cache = (0, None, math.nan, math.nan)
        n, best, clear, rob = cache
        for c in self.candidates[n:]:
            if c.phase != "search":
                continue
            if best is None or c.fitness < best.fitness:
                best = c
            if math.isfinite(c.clearance) and not c.clearance >= clear:
                clear = c.clearance
            if math.isfinite(c.robustness) and not c.robustness >= rob:
                rob = c.robustness
        self.__dict__["_bests"] = (len(self.candidates), best, clear, rob)
        return best, clear, rob

    @property
    def best(self) -> Candidate | None:
        return self._scan()[0]

    @property
    def best_clearance(self) -> float:
        return self._scan()[1]

    @property
    def best_robustness(self) -> float:
        return self._scan()[2]

    def failures_by_outcome(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for f in self.failures:
            out[f.found.outcome] = out.get(f.found.outcome, 0) + 1
        return out


def _finite(v: Any) -> Any:
    return None if isinstance(v, float) and not math.isfinite(v) else v



class Recorder(Protocol):
    """What ``run_search(..., recorder=...)`` tells while the search runs, so that what it found is
    on disk at every moment (search/freeze.py: ``SearchRecorder``). Each call is made whole: a
    Ctrl-C waits until it returns. The order: ``start``; per simulated candidate, first
    ``failure`` if it is a new failure (status "found"), then ``simulated``; ``failure`` again
    whenever a failure changes (Failure.status: confirmed, rejected, shrunk, ...); ``finish`` last,
    also when the search was cut short."""

    def start(self, report: SearchReport) -> None: ...
    def simulated(self, report: SearchReport, cand: Candidate) -> None: ...
    def failure(self, report: SearchReport, failure: Failure) -> None: ...
    def finish(self, report: SearchReport) -> None: ...
