"""Formula text -> tokens, with the 1-based column of each; RTAMT's words and symbols.

Keywords and their RTAMT spellings (``always`` or ``G``, ``and`` or ``&``, ``implies`` or ``->``...)
map to one kind each; symbols other languages use (``&&``, ``||``, ``=>``, ``=``) are tokens of
kind ``mistake`` so that the parser can name the spelling to use instead.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from .errors import StlSyntaxError

#: Words of the language -> token kind (RTAMT's lexer: StlLexer.g4 of rtamt 0.4).
KEYWORDS = {
    "not": "not", "and": "and", "or": "or", "implies": "implies", "iff": "iff", "xor": "xor",
    "always": "always", "G": "always", "eventually": "eventually", "F": "eventually",
    "historically": "historically", "H": "historically", "once": "once", "O": "once",
    "until": "until", "U": "until", "since": "since", "S": "since",
    "unless": "unless", "W": "unless",
    "next": "next", "X": "next", "prev": "prev", "Y": "prev",
    "s_next": "s_next", "sX": "s_next", "s_prev": "s_prev", "sY": "s_prev",
    "rise": "rise", "fall": "fall",
    "abs": "abs", "sqrt": "sqrt", "exp": "exp", "pow": "pow",
}

#: Symbols, longest first -> token kind.
SYMBOLS = [
    ("<->", "iff"), ("!==", "!=="), ("->", "implies"), ("<=", "<="), (">=", ">="), ("==", "=="),
    ("!=", "!=="), ("&&", "mistake"), ("||", "mistake"), ("=>", "mistake"), ("<>", "mistake"),
    ("**", "mistake"),
    ("<", "<"), (">", ">"), ("=", "mistake"), ("!", "not"), ("&", "and"), ("|", "or"),
    ("+", "+"), ("-", "-"), ("*", "*"), ("/", "/"), ("(", "("), (")", ")"), ("[", "["), ("]", "]"),
    (":", ":"), (",", ","), ("~", "mistake"), ("^", "mistake"), ("%", "mistake"),
]

#: What to write instead of a symbol of another language.
MISTAKES = {
    "&&": "write 'and' (or '&')", "||": "write 'or' (or '|')", "=>": "write 'implies' (or '->')",
    "<>": "write '!=' (not equal)", "**": "write pow(x, y)", "=": "write '==' to compare",
    "~": "write 'not' (or '!')", "^": "write pow(x, y)", "%": "there is no remainder operator",
}

_NUMBER = re.compile(r"(\d+\.\d*|\.\d+|\d+)([eE][+-]?\d+)?")
_WORD = re.compile(r"[A-Za-z_$][A-Za-z0-9_$]*")


@dataclass(frozen=True)
class Token:
    kind: str        # "num", "id", "eof", a keyword kind or a symbol kind
    text: str        # as written
    column: int      # 1-based
    value: float = 0.0


def tokenize(text: str) -> list[Token]:
    """The tokens of ``text``, ending with an ``eof`` token; a character of no token is an error."""
    tokens: list[Token] = []
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch.isspace():
            i += 1
            continue
        m = _NUMBER.match(text, i)
        if m:
            tokens.append(Token("num", m.group(0), i + 1, float(m.group(0))))
            i = m.end()
            continue
        m = _WORD.match(text, i)
        if m:
            word = m.group(0)
            tokens.append(Token(KEYWORDS.get(word, "id"), word, i + 1))
            i = m.end()
            continue
        for symbol, kind in SYMBOLS:
            if text.startswith(symbol, i):
                tokens.append(Token(kind, symbol, i + 1))
                i += len(symbol)
                break
        else:
            hint = ("signal names are letters, digits and '_'" if ch == "." else
                    "remove it; see the operators in docs/reference/requirements-language.md")
            raise StlSyntaxError(f"unexpected character {ch!r}", i + 1, hint, text)
    tokens.append(Token("eof", "", n + 1))
    return tokens
