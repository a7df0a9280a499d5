"""``parse(text) -> Formula``: a parsed, checked requirement, ready to evaluate.

A ``Formula`` is immutable and cheap to keep: its canonical ``text``, the ``source`` as written,
the tree (``root``), the ``signals`` it reads. Its evaluation plan is compiled once per sampling
period on first use (``compile.plan``) and cached on the formula. It pickles as its text (worker
processes re-parse it).
"""
from __future__ import annotations

from .tree import Node, render
from .parser import Parser
from .plan import plan_for


class Formula:
    """A requirement in STL. Compare by ``text``; see ``robustness``/``evaluate`` to check one."""

    __slots__ = ("root", "text", "source", "signals", "_plans")

    def __init__(self, root: Node, source: str):
        self.root = root
        self.source = source
        self.text = render(root)
        self.signals = frozenset(n.name for n in root.walk() if n.op == "var")
        self._plans: dict[float, object] = {}

    def __repr__(self) -> str:
        return f"Formula({self.text!r})"

    def __str__(self) -> str:
        return self.text

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Formula) and other.text == self.text

    def __hash__(self) -> int:
        return hash(self.text)

    def __reduce__(self):
        return (parse, (self.source,))

    def check_period(self, dt: float) -> None:
        """Raise ``StlEvaluationError`` unless every interval bound is a whole number of sampling
        periods ``dt`` (seconds): the check ``robustness`` makes, for a scenario to make at load."""
        plan_for(self, dt)


def parse(text: str) -> Formula:
    """The formula ``text`` in RTAMT's discrete-time STL syntax, checked.

    Raises ``StlSyntaxError(message, column, hint)`` on a mistake: an unknown operator, an
    unbalanced parenthesis, an interval that ends before it begins, a signal where a condition is
    needed (``always speed``), a condition where a number is needed.
    """
    if not isinstance(text, str):
        raise TypeError(f"parse() takes the formula's text, got {type(text).__name__}")
    return Formula(Parser(text).parse(), text)
