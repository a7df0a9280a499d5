"""The formula tree: one ``Node`` class, a term (a real-valued signal expression) or a formula
(a condition with a robustness), and its canonical text.

The canonical text is RTAMT syntax with every operand of a logical or temporal operator in
parentheses, so it reads the same to RTAMT and to a person: ``always((d < 1.5) implies (v <= 0.3))``.
"""
from __future__ import annotations

from dataclasses import dataclass

#: Real-valued operators (terms); everything else is a formula.
TERM_OPS = frozenset({"var", "const", "neg", "+", "-", "*", "/", "abs", "sqrt", "exp", "pow"})
COMPARISONS = frozenset({"<", "<=", ">", ">=", "==", "!=="})
#: Prefix temporal operators that may take an interval, future and past.
FUTURE_UNARY = frozenset({"always", "eventually"})
PAST_UNARY = frozenset({"historically", "once"})
BINARY_LOGIC = frozenset({"and", "or", "implies", "iff", "xor"})
BINARY_TEMPORAL = frozenset({"until", "since"})
#: Prefix operators of one step (a sample) and of change.
STEP_UNARY = frozenset({"next", "prev", "s_next", "s_prev"})
EDGE_UNARY = frozenset({"rise", "fall"})


@dataclass(frozen=True, eq=False)
class Node:
    """One operator of a formula. ``interval`` is ``(begin, end)`` in seconds or ``None``
    (unbounded); ``column`` (1-based) is where the operator is written."""

    op: str
    args: tuple["Node", ...] = ()
    name: str = ""
    value: float = 0.0
    interval: tuple[float, float] | None = None
    column: int = 0

    @property
    def is_term(self) -> bool:
        return self.op in TERM_OPS

    def walk(self):
        """This node and every node below it, parents first."""
        yield self
        for arg in self.args:
            yield from arg.walk()


def number(x: float) -> str:
    """A constant as RTAMT reads it back: ``5`` not ``5.0``; the shortest exact repr otherwise."""
    if x == int(x) and abs(x) < 1e15:
        return str(int(x))
    return repr(float(x))


def interval_text(interval: tuple[float, float] | None) -> str:
    return "" if interval is None else f"[{number(interval[0])}:{number(interval[1])}]"


def render(node: Node) -> str:
    """The canonical text of ``node`` (see the module docstring)."""
    op, args = node.op, node.args
    if op == "var":
        return node.name
    if op == "const":
        return number(node.value)
    if op == "neg":
        return f"-{_operand(args[0])}"
    if op in ("+", "-", "*", "/"):
        return f"{_operand(args[0])} {op} {_operand(args[1])}"
    if op in ("abs", "sqrt", "exp", "rise", "fall"):
        return f"{op}({render(args[0])})"
    if op == "pow":
        return f"pow({render(args[0])}, {render(args[1])})"
    if op in COMPARISONS:
        return f"{_operand(args[0])} {op} {_operand(args[1])}"
    if op in BINARY_LOGIC or op in BINARY_TEMPORAL:
        return f"{_condition(args[0])} {op}{interval_text(node.interval)} {_condition(args[1])}"
    # not, always, eventually, historically, once, next, prev, s_next, s_prev
    return f"{op}{interval_text(node.interval)}({render(args[0])})"


def _operand(node: Node) -> str:
    """A term inside a larger term or comparison: parenthesised unless it is atomic."""
    text = render(node)
    return f"({text})" if node.op in ("+", "-", "*", "/", "neg") else text


def _condition(node: Node) -> str:
    """An operand of a binary logical or temporal operator: parenthesised unless it is a prefix
    operator, whose own parentheses delimit it (``always(a > 0) and (b > 0)``)."""
    text = render(node)
    return text if node.op in PREFIX_FORMS else f"({text})"


PREFIX_FORMS = FUTURE_UNARY | PAST_UNARY | STEP_UNARY | EDGE_UNARY | {"not"}
