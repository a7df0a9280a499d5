"""The formula language: RTAMT's syntax and precedence, the canonical text, and errors that name
the column and the fix."""
from __future__ import annotations

import pickle

import pytest

from pytest_navscenario.core.errors import NavScenarioError
from pytest_navscenario.stl import Formula, StlSyntaxError, parse


@pytest.mark.parametrize("text, canonical", [
    ("always ((d_walker < 1.5) implies (speed <= 0.3))", "always((d_walker < 1.5) implies (speed <= 0.3))"),
    ("always (d_walker >= 0.8)", "always(d_walker >= 0.8)"),
    ("eventually[0:50](d < 0.3)", "eventually[0:50](d < 0.3)"),
    # RTAMT's spellings: G F U H O S, & | ! -> <->, [a,b], units
    ("G[0,5] (a > 0) & !(b < 1)", "always[0:5](a > 0) and not(b < 1)"),
    ("F[1s:1500ms] x == 1 | y !== 2", "eventually[1:1.5](x == 1) or (y !== 2)"),
    ("(a > 0) -> (b > 0) <-> (c > 0)", "((a > 0) implies (b > 0)) iff (c > 0)"),
    ("y != 2", "y !== 2"),
    ("(a > 0) U[0:2] (b > 0)", "(a > 0) until[0:2] (b > 0)"),
    ("H[0:1] a > 0 and O b > 0 and (a > 0) S (b > 0)",
     "(historically[0:1](a > 0) and once(b > 0)) and ((a > 0) since (b > 0))"),
    ("next a > 0 or prev a > 0 or s_next a > 0 or sY a > 0",
     "((next(a > 0) or prev(a > 0)) or s_next(a > 0)) or s_prev(a > 0)"),
    ("rise(a > 0) xor fall(b > 0)", "rise(a > 0) xor fall(b > 0)"),
    ("abs(a - b) + sqrt(c) * exp(d) <= pow(e, 2)", "(abs(a - b) + (sqrt(c) * exp(d))) <= pow(e, 2)"),
    ("a > -0.5 and b < 1e-3 and c > .5", "((a > -0.5) and (b < 0.001)) and (c > 0.5)"),
    ("-a > 0", "(-a) > 0"),
])
def test_rtamt_syntax_reads_to_its_canonical_text(text, canonical):
    f = parse(text)
    assert f.text == canonical
    assert parse(f.text).text == canonical          # the canonical text reads back the same


@pytest.mark.parametrize("text, grouping", [
    # prefix temporal operators take the operand up to the next logical operator (RTAMT)
    ("always (a > 0) and (b > 0)", "always(a > 0) and (b > 0)"),
    ("always (a > 0) implies (b > 0)", "always(a > 0) implies (b > 0)"),
    ("not a > 0 and b > 0", "not(a > 0) and (b > 0)"),
    # and binds tighter than or, or than implies, implies than iff, iff than xor
    ("a > 0 or b > 0 and c > 0", "(a > 0) or ((b > 0) and (c > 0))"),
    ("a > 0 implies b > 0 or c > 0", "(a > 0) implies ((b > 0) or (c > 0))"),
    ("a > 0 xor b > 0 iff c > 0", "(a > 0) xor ((b > 0) iff (c > 0))"),
    # until binds tighter than and; binary operators group to the left
    ("a > 0 and b > 0 until c > 0", "(a > 0) and ((b > 0) until (c > 0))"),
    ("a > 0 until b > 0 until c > 0", "((a > 0) until (b > 0)) until (c > 0)"),
    ("a > 0 implies b > 0 implies c > 0", "((a > 0) implies (b > 0)) implies (c > 0)"),
    # arithmetic as usual where RTAMT agrees with it
    ("a + b * c > d - e - f", "(a + (b * c)) > ((d - e) - f)"),
    ("a * b / c + d > 0", "(((a * b) / c) + d) > 0"),
])
def test_precedence_is_rtamts(text, grouping):
    assert parse(text).text == grouping


def test_a_formula_knows_its_signals_compares_by_text_and_pickles():
    f = parse("always ((d_walker < 1.5) implies (speed <= 0.3))")
    assert f.signals == frozenset({"d_walker", "speed"})
    assert f == parse("always((d_walker<1.5)implies(speed<=0.3))") and hash(f) == hash(parse(f.text))
    assert isinstance(f, Formula) and "always" in repr(f)
    assert pickle.loads(pickle.dumps(f)) == f


@pytest.mark.parametrize("text, column, message, fix", [
    ("", 1, "empty", "write a condition"),
    ("a > 0 && b > 0", 7, "unknown operator '&&'", "'and'"),
    ("a > 0 || b > 0", 7, "unknown operator '||'", "'or'"),
    ("(a > 0) => (b > 0)", 9, "unknown operator '=>'", "'implies'"),
    ("a = 1", 3, "unknown operator '='", "'=='"),
    ("always ((a > 0) and (b > 0)", 8, "'(' is never closed", "add the ')'"),
    ("always (a > 0))", 15, "')' without a matching '('", "remove it"),
    ("always[5:2] (a > 0)", 7, "the interval [5:2] ends before it begins", "[2:5]"),
    ("always[-1:2] (a > 0)", 8, "negative", "0 or more seconds"),
    ("always[0:inf] (a > 0)", 10, "interval's end", "leave the interval out"),
    ("always[0:2min] (a > 0)", 11, "unknown time unit 'min'", "s, ms, us or ns"),
    ("always[0:2 (a > 0)", 12, "expected ']'", "[begin:end]"),
    ("always speed", 8, "the signal 'speed', where a condition is needed", "speed >= 0.5"),
    ("speed", 1, "the signal 'speed', where a condition is needed", "compare it"),
    ("(a > 0) + 1 > 0", 9, "the left side of '+' is a condition", "and/or/not"),
    ("a > b > c", 7, "the left side of '>' is a condition", None),
    ("a - b + c > 0", 3, "RTAMT reads it as 'a - (b + c)'", "parentheses you mean"),
    ("a / b * c > 0", 3, "RTAMT reads it as 'a / (b * c)'", "parentheses you mean"),
    ("min(a, b) > 0", 1, "unknown function 'min'", "abs, sqrt, exp, pow"),
    ("a > 0 b > 0", 7, "unexpected the signal 'b' after a complete formula", "'and'"),
    ("robot.speed > 0", 6, "unexpected character '.'", "letters, digits and '_'"),
    ("and a > 0", 1, "needs something on its left", None),
    ("a >", 4, "ends too early", None),
    ("()", 2, "empty parentheses", None),
    ("(a > 0) unless (b > 0)", 9, "'unless' is not supported", "until"),
    ("pow(a) > 0", 6, "expected ','", "pow(x, y)"),
])
def test_a_mistake_names_its_column_and_the_fix(text, column, message, fix):
    with pytest.raises(StlSyntaxError) as info:
        parse(text)
    err = info.value
    assert err.column == column, str(err)
    assert message in err.message
    if fix is not None:
        assert fix in err.hint
    assert str(err).startswith(f"column {column}: ")
    assert err.pointer().splitlines()[1] == " " * (column - 1) + "^"
    assert isinstance(err, NavScenarioError)
