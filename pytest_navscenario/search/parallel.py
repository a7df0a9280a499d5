"""A search's generations evaluated on an executor (``dispatch/``: local worker processes or Ray).

``executor_evaluator(executor)`` is an evaluator for ``run_search(..., evaluator=...)``: each
generation the strategy proposes becomes one ``CandidateJob`` per candidate, all submitted at
once, and the candidates come back in proposal order. A candidate is a pure function of the
evaluation context and its offsets (``engine.evaluate_candidate``), and the strategy only sees
the generation once it is complete, so the search takes the same path, finds the same failures
and writes the same files as a serial run with the same search seed; only the measured wall
times differ, as they do between two serial runs.
"""
from __future__ import annotations

import uuid
from dataclasses import dataclass
from typing import Any, Iterator, Sequence

from .engine import Candidate, EvalContext, evaluate_candidate

_CONTEXTS: dict[str, EvalContext] = {}   # worker side: the first copy of each context received
_MAX_CONTEXTS = 4


@dataclass(frozen=True)
class CandidateJob:
    """One candidate to simulate in a worker (a dispatch job: ``run`` there, ``restore`` here)."""
    ctx: EvalContext
    offsets: tuple[float, ...]
    origin: str
    token: str          # names ``ctx``: a worker reuses its first copy, so per-space caches survive

    def run(self) -> Candidate:
        ctx = _CONTEXTS.get(self.token)
        if ctx is None:
            if len(_CONTEXTS) >= _MAX_CONTEXTS:
                _CONTEXTS.clear()
            ctx = _CONTEXTS[self.token] = self.ctx
        cand = evaluate_candidate(ctx, self.offsets, self.origin)
        cand.scenario = None    # rebuilt from the offsets here: no need to send it back
        return cand

    def restore(self, cand: Candidate) -> Candidate:
        cand.scenario = self.ctx.space.apply(self.offsets)
        return cand


class executor_evaluator:   # noqa: N801  (used like a function: evaluator=executor_evaluator(ex))
    """An evaluator that runs each generation on ``executor`` (see the module docstring)."""

    def __init__(self, executor: Any):
        self.executor = executor
        self._ctx: EvalContext | None = None
        self._token = ""

    def __call__(self, ctx: EvalContext, proposals: Sequence[tuple[tuple[float, ...], str]]) -> Iterator[Candidate]:
        if ctx is not self._ctx:
            self._ctx, self._token = ctx, uuid.uuid4().hex
        pending = self.executor.submit([CandidateJob(ctx, tuple(offsets), origin, self._token)
                                        for offsets, origin in proposals])
        for p in pending:
            yield p.result()
