"""What ``run_search`` asks of an evaluator beyond evaluating a generation, with the defaults.

``Evaluator`` is the base of the evaluators that do more than the serial default (parallel.py's on
worker processes, batched.py's in lockstep batches); ``as_evaluator`` wraps a plain function.
"""
from __future__ import annotations

from typing import Any, Callable, Iterable, Sequence

from .evaluation import EvalContext, Proposal, Simulator, serial_evaluator
from .report import Candidate
from .shrinker import shrink_all


class Evaluator:
    """What ``run_search`` asks of an evaluator, with the defaults: ``evaluator(ctx, proposals)``
    yields each proposal's candidate in proposal order (here: serially, ``serial_evaluator``).
    An evaluator may also shrink the failures itself (``shrink_failures``: e.g. all at once on
    worker processes, recording the results in a serial run's order), begin shrinking a failure
    the moment it is found (``shrinks_early`` and ``start_shrink``), give up what is in flight
    when the search ends early (``discard``) and say how its simulations ran in batches
    (``batching``), as parallel.py's and batched.py's do; the result never depends on it.
    A plain function ``(ctx, proposals) -> candidates`` is wrapped (``as_evaluator``)."""

    batching: Any = None          # a harness.batch.Batching, or None: nothing batched to tell
    shrinks_early = False         # whether start_shrink is offered

    def __call__(self, ctx: EvalContext, proposals: Sequence[Proposal]) -> Iterable[Candidate]:
        return serial_evaluator(ctx, proposals)

    def start_shrink(self, ctx: EvalContext, found: Candidate, cap: int, known: Sequence[Candidate] = (),
                     estimate: Any = None) -> None:
        raise NotImplementedError("this evaluator does not shrink early (shrinks_early is False)")

    def shrink_failures(self, sim: "Simulator", caps: Sequence[int], progress: Any) -> None:
        """Shrink each failure of ``sim.report`` with its cap (default: one after the other)."""
        shrink_all(sim.ctx.space, sim, caps, progress)

    def discard(self) -> None:
        """The search ended early: drop what is still in flight (default: nothing is)."""

    def worker_deaths(self) -> list[str]:
        """The worker processes that died during this search, each in words (default: none;
        parallel.py's: its pool was replaced and their jobs run again)."""
        return []


class _FunctionEvaluator(Evaluator):
    def __init__(self, function: Callable[[EvalContext, Sequence[Proposal]], Iterable[Candidate]]):
        self.function = function

    def __call__(self, ctx: EvalContext, proposals: Sequence[Proposal]) -> Iterable[Candidate]:
        return self.function(ctx, proposals)


def as_evaluator(evaluator: "Evaluator | Callable | None") -> Evaluator:
    """``evaluator`` as an ``Evaluator``: None is the serial one, a plain function is wrapped."""
    if evaluator is None:
        return Evaluator()
    return evaluator if isinstance(evaluator, Evaluator) else _FunctionEvaluator(evaluator)
