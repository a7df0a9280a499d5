"""What a search strategy is: the interface ``run_search`` drives (``Strategy``), and what the
strategies share (``GaveUp``; the validity and repeat filter
``Admission`` and ``uniform`` draws are in admission.py).

A strategy is an ask/tell object built as ``cls(space, report, budget, seed_value)``:
``ask(room)`` proposes at most ``room`` valid candidates (offset vectors with their origin),
``tell(results)`` receives them simulated, in proposal order, ``lag`` generations later (read
before each ask: it may change), and ``confirmed(candidate, estimate)`` hears when a failure's
confirmation runs decided (holding.py). ``BaseStrategy`` gives the defaults (lag 0, nothing to
hear). Like pytest-xdist's ``scheduler/protocol.py``: the one place that says what the engine
needs, so a new strategy is a new module plus one line in strategies/__init__.py's registry.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol, Sequence, runtime_checkable

if TYPE_CHECKING:
    from ..space import SearchSpace

GENERATION = 8                 # candidates per generation (evolve, random)

Offsets = tuple[float, ...]
Proposal = tuple[Offsets, str]   # (offsets, origin: the operator that proposed it)


@runtime_checkable
class Strategy(Protocol):
    """The interface ``engine.run_search`` drives (see the module docstring)."""

    lag: int

    def __init__(self, space: SearchSpace, report: Any, budget: int, seed_value: int) -> None: ...

    def ask(self, room: int) -> list[Proposal]:
        """At most ``room`` new valid candidates; [] (or GaveUp) when there is nothing left."""

    def tell(self, results: Sequence[Any]) -> None:
        """This strategy's candidates of one generation, simulated, in proposal order."""

    def confirmed(self, cand: Any, estimate: Any) -> None:
        """A failure this strategy proposed was decided (``estimate.decision``: held or rejected)."""


class BaseStrategy:
    """Defaults for a ``Strategy``: told each generation's results before the next ask (lag 0),
    and nothing to do when a failure is decided."""

    lag = 0

    def tell(self, results: Sequence[Any]) -> None:
        pass

    def confirmed(self, cand: Any, estimate: Any) -> None:
        pass


class GaveUp(Exception):
    """Too many invalid candidates in a row: the bounds leave almost nothing valid."""
