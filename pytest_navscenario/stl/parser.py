"""Tokens -> a typed formula tree, with RTAMT's operator precedence (a Pratt parser).

RTAMT's grammar is one left-recursive ANTLR rule whose alternatives bind in the order written;
from tightest: ``*``, ``/``, ``+``, ``-``, comparisons; the prefix operators (``not`` then
``always``, ``eventually``, ``historically``, ``once``, ``prev``, ``next``...) take the operand
that follows up to the next logical or temporal binary operator; then ``until``, ``since``,
``and``, ``or``, ``implies``, ``iff``, ``xor``. Binary operators group to the left. The levels
below are RTAMT's own, so ``always (a > 0) and (b > 0)`` is ``(always (a > 0)) and (b > 0)``
there and here. Two of RTAMT's groupings surprise arithmetic readers (``a - b + c`` is
``a - (b + c)``, ``a / b * c`` is ``a / (b * c)``): those are errors asking for parentheses.
"""
from __future__ import annotations

from .tree import (BINARY_TEMPORAL, COMPARISONS, EDGE_UNARY, FUTURE_UNARY, PAST_UNARY,
                  Node, number, render)
from .errors import StlSyntaxError
from .lexer import MISTAKES, Token, tokenize

#: Infix operators -> RTAMT's precedence level (higher binds tighter).
INFIX = {"*": 26, "/": 25, "+": 24, "-": 23, **{c: 22 for c in COMPARISONS},
         "until": 12, "unless": 11, "since": 10, "and": 9, "or": 8, "implies": 7, "iff": 6,
         "xor": 5}
#: Prefix operators -> the level their operand is parsed at.
PREFIX = {"not": 21, "always": 20, "eventually": 19, "historically": 18, "once": 17,
          "prev": 16, "next": 15, "s_prev": 14, "s_next": 13}
UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
_NEG_LEVEL = 27          # unary minus binds tighter than any infix operator
_FUNCTIONS = ("abs", "sqrt", "exp", "pow", "rise", "fall")
_EXAMPLE = "e.g. 'always (d_walker >= 0.8)'"


class Parser:
    def __init__(self, text: str):
        self.text = text
        self.tokens = tokenize(text)
        self.pos = 0
        self.parenthesised: set[int] = set()

    # -- helpers ---------------------------------------------------------------------------
    @property
    def tok(self) -> Token:
        return self.tokens[self.pos]

    def advance(self) -> Token:
        tok = self.tokens[self.pos]
        self.pos += 1
        return tok

    def error(self, message: str, tok: Token | int, hint: str | None = None) -> StlSyntaxError:
        column = tok if isinstance(tok, int) else tok.column
        return StlSyntaxError(message, column, hint, self.text)

    def expect(self, kind: str, what: str, hint: str | None = None) -> Token:
        if self.tok.kind != kind:
            raise self.error(f"expected {what}, found {describe(self.tok)}", self.tok, hint)
        return self.advance()

    # -- the grammar -----------------------------------------------------------------------
    def parse(self) -> Node:
        if self.tok.kind == "eof":
            raise self.error("the formula is empty", self.tok, f"write a condition, {_EXAMPLE}")
        node = self.expression(0)
        if self.tok.kind == ")":
            raise self.error("')' without a matching '('", self.tok, "remove it or add the '(' it closes")
        if self.tok.kind != "eof":
            raise self.error(f"unexpected {describe(self.tok)} after a complete formula", self.tok,
                             "join the two parts with an operator such as 'and', or add the missing one")
        formula(node, self.text, "the whole text")
        return node

    def expression(self, level: int) -> Node:
        left = self.prefix()
        while True:
            tok = self.tok
            if tok.kind == "mistake":
                raise self.error(f"unknown operator {tok.text!r}", tok, MISTAKES[tok.text])
            op_level = INFIX.get(tok.kind)
            if op_level is None or op_level < level:
                return left
            self.advance()
            left = self.infix(tok, left, op_level)

    def infix(self, tok: Token, left: Node, level: int) -> Node:
        op = tok.kind
        if op == "unless":
            raise self.error("'unless' is not supported (RTAMT's offline evaluator has none)", tok,
                             "write '(a until b) or (always a)', its meaning")
        interval = self.interval() if op in BINARY_TEMPORAL else None
        right = self.expression(level + 1)
        if op in ("-", "/") and right.op == {"-": "+", "/": "*"}[op] and id(right) not in self.parenthesised:
            raise self.error(
                f"ambiguous without parentheses: RTAMT reads it as '{render(left)} {op} ({render(right)})'",
                tok, "add the parentheses you mean, e.g. '(a - b) + c' or 'a - (b + c)'")
        if op in INFIX and INFIX[op] >= 22:          # arithmetic and comparisons read terms
            term(left, self.text, f"the left side of '{tok.text}'", tok)
            term(right, self.text, f"the right side of '{tok.text}'", tok)
        else:
            formula(left, self.text, f"the left side of '{tok.text}'", tok)
            formula(right, self.text, f"the right side of '{tok.text}'", tok)
        return Node(op, (left, right), interval=interval, column=tok.column)

    def prefix(self) -> Node:
        tok = self.tok
        kind = tok.kind
        if kind == "(":
            return self.parenthesis()
        if kind == "num":
            self.advance()
            return Node("const", value=tok.value, column=tok.column)
        if kind == "id":
            self.advance()
            if self.tok.kind == "(":
                raise self.error(f"unknown function {tok.text!r}", tok,
                                 "the functions are abs, sqrt, exp, pow (and rise, fall of a condition)")
            return Node("var", name=tok.text, column=tok.column)
        if kind == "-":
            self.advance()
            operand = self.expression(_NEG_LEVEL)
            term(operand, self.text, "the operand of '-'", tok)
            if operand.op == "const" and id(operand) not in self.parenthesised:
                return Node("const", value=-operand.value, column=tok.column)
            return Node("neg", (operand,), column=tok.column)
        if kind in PREFIX:
            self.advance()
            interval = self.interval() if kind in FUTURE_UNARY or kind in PAST_UNARY else None
            operand = self.expression(PREFIX[kind])
            formula(operand, self.text, f"the operand of '{tok.text}'", tok)
            return Node(kind, (operand,), interval=interval, column=tok.column)
        if kind in _FUNCTIONS:
            return self.function()
        if kind == "mistake":
            raise self.error(f"unknown operator {tok.text!r}", tok, MISTAKES[tok.text])
        if kind == "eof":
            raise self.error("the formula ends too early", tok, "complete the condition after the last operator")
        if kind in INFIX or kind in ("and", "or"):
            raise self.error(f"{describe(tok)} needs something on its left", tok,
                             "write the condition before it, or remove it")
        raise self.error(f"unexpected {describe(tok)}", tok, f"write a signal, a number or an operator, {_EXAMPLE}")

    def parenthesis(self) -> Node:
        open_tok = self.advance()
        if self.tok.kind == ")":
            raise self.error("empty parentheses", self.tok, "put a condition or a signal between them")
        node = self.expression(0)
        if self.tok.kind != ")":
            if self.tok.kind == "eof":
                raise self.error("'(' is never closed", open_tok, "add the ')' it needs")
            raise self.error(f"expected ')' to close the '(' at column {open_tok.column}, found "
                             f"{describe(self.tok)}", self.tok, "add the missing ')' or an operator")
        self.advance()
        self.parenthesised.add(id(node))
        return node

    def function(self) -> Node:
        tok = self.advance()
        self.expect("(", f"'(' after '{tok.text}'", f"write {tok.text}(...)")
        first = self.expression(0)
        args = [first]
        if tok.kind == "pow":
            self.expect(",", "',' between pow's two arguments", "write pow(x, y)")
            args.append(self.expression(0))
        if self.tok.kind != ")":
            raise self.error(f"expected ')' to close '{tok.text}(', found {describe(self.tok)}",
                             self.tok, "add the missing ')'")
        self.advance()
        check = formula if tok.kind in EDGE_UNARY else term
        for arg in args:
            check(arg, self.text, f"the argument of '{tok.text}'", tok)
        return Node(tok.kind, tuple(args), column=tok.column)

    def interval(self) -> tuple[float, float] | None:
        """An optional ``[begin:end]`` (or ``[begin,end]``) in seconds, units s/ms/us/ns allowed."""
        if self.tok.kind != "[":
            return None
        open_tok = self.advance()
        begin, begin_unit = self.bound("begin")
        if self.tok.kind not in (":", ","):
            raise self.error(f"expected ':' in the interval, found {describe(self.tok)}", self.tok,
                             "write [begin:end] in seconds, e.g. [0:5]")
        self.advance()
        end, end_unit = self.bound("end")
        self.expect("]", "']' to close the interval", "write [begin:end] in seconds, e.g. [0:5]")
        begin *= UNITS[begin_unit or end_unit or "s"]
        end *= UNITS[end_unit or "s"]
        if end < begin:
            raise self.error(f"the interval [{number(begin)}:{number(end)}] ends before it begins", open_tok,
                             f"write [{number(end)}:{number(begin)}]")
        return (begin, end)

    def bound(self, which: str) -> tuple[float, str | None]:
        tok = self.tok
        if tok.kind == "-":
            raise self.error(f"the interval's {which} is negative", tok,
                             "intervals look ahead (always, eventually, until) or back (historically, "
                             "once, since) from now: write 0 or more seconds")
        if tok.kind != "num":
            hint = ("intervals are numbers of seconds: for no bound, leave the interval out"
                    if tok.text in ("inf", "oo") else "write a number of seconds, e.g. [0:5]")
            raise self.error(f"expected the interval's {which} (seconds), found {describe(tok)}", tok, hint)
        self.advance()
        unit = None
        if self.tok.kind == "id" and self.tok.text in UNITS:
            unit = self.advance().text
        elif self.tok.kind == "id" and self.tokens[self.pos + 1].kind in (":", ",", "]"):
            raise self.error(f"unknown time unit {self.tok.text!r}", self.tok, "use s, ms, us or ns (default: s)")
        return tok.value, unit


def describe(tok: Token) -> str:
    if tok.kind == "eof":
        return "the end of the formula"
    if tok.kind == "num":
        return f"the number {tok.text}"
    if tok.kind == "id":
        return f"the signal {tok.text!r}"
    return f"{tok.text!r}"


def term(node: Node, text: str, where: str, tok: Token | None = None) -> None:
    """``node`` must be a real-valued expression (a signal, a number, arithmetic)."""
    if not node.is_term:
        column = tok.column if tok else node.column
        raise StlSyntaxError(f"{where} is a condition, where a number or signal is needed", column,
                             "arithmetic and comparisons read signals and numbers; combine conditions "
                             "with and/or/not", text)


def formula(node: Node, text: str, where: str, tok: Token | None = None) -> None:
    """``node`` must be a condition (a comparison, or operators of comparisons)."""
    if node.is_term:
        what = f"the signal {node.name!r}" if node.op == "var" else "a number" if node.op == "const" \
            else "an arithmetic expression"
        example = f"'{node.name} >= 0.5'" if node.op == "var" else "'speed <= 0.3'"
        raise StlSyntaxError(f"{where} is {what}, where a condition is needed", node.column,
                             f"compare it with a threshold, e.g. {example}", text)
