"""The failures of a search under confirmation: which confirmation runs to ask for next, and what
their results decide (the state machine beside holding.py's sequential test).
"""
from __future__ import annotations

import math
from typing import Callable

from .evaluation import EvalContext, Proposal
from .holding import Estimate, decide
from .report import Candidate, Failure, SearchReport


class Confirming:
    """The failures of the search phase under confirmation (holding.py), oldest first: which
    confirmation runs to ask for next, and what their results decide.

    A candidate that fails in a way no failure holds yet becomes a failure "found"; with a test
    (the seed has randomness and the threshold is not 0) it waits for its confirmation runs, else
    it holds at once. While one failure of a way of failing is under test, the first other
    candidate failing that way is kept aside and tried next if the first is rejected; a way of
    failing rejected MAX_REJECTIONS times is not tried again. ``on_decided(failure)`` is called
    when a failure holds or is rejected."""

    def __init__(self, ctx: EvalContext, report: SearchReport, exact: str, on_decided: Callable[[Failure], None]):
        from .holding import MAX_REJECTIONS

        self.test, self.exact, self.report = ctx.hold, exact, report
        self.threshold = ctx.hold_threshold
        self.on_decided = on_decided
        self.pending: list[Failure] = []
        self.flight: dict[int, int] = {}            # failure key -> runs asked for, results not yet in
        self.by_offsets: dict[tuple, Failure] = {}  # the layout under test -> its failure
        self.aside: dict[tuple, Candidate] = {}     # signature -> a later candidate failing that way
        self.held: set[tuple] = set()
        self.rejections: dict[tuple, int] = {}
        self.max_rejections = MAX_REJECTIONS
        self.seen = self.begun = 0    # the strategy's candidates read, failures begun (reserve's rate)

    def counted(self, cand: Candidate) -> None:
        """A strategy's candidate came back (the rate of new failures, for ``reserve``)."""
        self.seen += 1

    def failed(self, cand: Candidate) -> Failure | None:
        """A search candidate failed: the new failure it starts (None: a way of failing known)."""
        sig = cand.signature
        if sig in self.held or self.rejections.get(sig, 0) >= self.max_rejections:
            return None
        if any(f.found.signature == sig for f in self.pending):
            self.aside.setdefault(sig, cand)
            return None
        return self._begin(cand)

    def _begin(self, cand: Candidate) -> Failure:
        self.begun += 1
        failure = Failure(found=cand, shrunk=cand, estimate=Estimate(threshold=self.threshold))
        if self.test is None:
            failure.estimate.decision = self.exact
            failure.status = "confirmed"
            self.held.add(cand.signature)
        else:
            self.pending.append(failure)
            self.by_offsets[tuple(cand.offsets)] = failure
        return failure

    def requests(self, room: int) -> list[Proposal]:
        """The confirmation runs to start now, oldest failure first: for each failure with no run
        in flight, the fewest runs that could decide its test (Sprt.runs_to_decide)."""
        out: list[Proposal] = []
        for failure in self.pending:
            if self.flight.get(failure.key) or len(out) >= room:
                continue
            est = failure.estimate
            n = min(self.test.runs_to_decide(est.outcomes), room - len(out))
            out += [(tuple(failure.found.offsets), "confirm", est.runs + 1 + k) for k in range(n)]
            self.flight[failure.key] = n
        return out

    def reserve(self, new_in_flight: int = 0) -> int:
        """Runs kept out of the strategy's room so that the failures found can be decided before
        the budget ends: what the failures under test still need beyond the runs in flight if
        each keeps failing (the runs a failure that holds takes), and what the new failures
        expected among the ``new_in_flight`` candidates not yet read would need (at the rate new
        failures have come so far)."""
        need = 0
        for failure in self.pending:
            est = failure.estimate
            need += max(self._to_accept(est.outcomes) - self.flight.get(failure.key, 0), 0)
        if self.seen and new_in_flight:
            need += math.ceil(new_in_flight * self.begun / self.seen * self._to_accept([]) - 1e-9)
        return need

    def _to_accept(self, outcomes: list[bool]) -> int:
        """Runs to accept after ``outcomes`` if every one fails (at most the test's last run)."""
        runs = math.ceil((self.test.accept_at - self.test.llr(outcomes)) / self.test.up - 1e-9)
        return max(0, min(runs, self.test.max_runs - len(outcomes)))

    def result(self, cand: Candidate) -> None:
        """A confirmation run came back: note it; decide when the runs asked for are all in."""
        failure = self.by_offsets[tuple(cand.offsets)]
        failure.estimate.outcomes.append(cand.failed)
        self.flight[failure.key] -= 1
        if self.flight[failure.key]:
            return
        del self.flight[failure.key]
        decide(self.test, failure.estimate)
        if failure.estimate.decision == "pending":
            return
        self.pending.remove(failure)
        del self.by_offsets[tuple(failure.found.offsets)]
        sig = failure.found.signature
        if failure.estimate.decision == "held":
            failure.status = "confirmed"
            self.held.add(sig)
            self.aside.pop(sig, None)
        else:
            failure.status = "rejected"
            self.rejections[sig] = self.rejections.get(sig, 0) + 1
        self.on_decided(failure)

    def next_aside(self, failure: Failure) -> Failure | None:
        """After ``failure`` was rejected: the candidate kept aside for its way of failing, begun."""
        sig = failure.found.signature
        cand = self.aside.pop(sig, None)
        if cand is None or self.rejections.get(sig, 0) >= self.max_rejections:
            return None
        return self._begin(cand)

    def close(self, interrupted: bool) -> list[Failure]:
        """The search phase is over: the failures still under test (marked unconfirmed unless the
        search was cut short, when they stay as found)."""
        left, self.pending = self.pending, []
        for failure in left:
            failure.estimate.decision = "pending" if interrupted else "unconfirmed"
            failure.status = "found" if interrupted else "unconfirmed"
        return left

