"""docs/reference/requirements-language.md says what the language does: its example runs as
written, every operator the parser knows is on the page, every message in its table of mistakes
is the one the parser gives."""
from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

from pytest_navscenario.stl import StlSyntaxError, parse
from pytest_navscenario.stl.lexer import KEYWORDS

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "reference" / "requirements-language.md"
sys.path.insert(0, str(ROOT / "tests" / "docs"))


def _table(heading: str) -> list[list[str]]:
    text = PAGE.read_text(encoding="utf-8").split(heading, 1)[1].split("\n## ", 1)[0]
    rows = [line for line in text.splitlines() if line.startswith("| ") and not line.startswith("|--")]
    return [[cell.strip() for cell in re.split(r"(?<!\\)\|", row)[1:-1]] for row in rows[1:]]


def test_every_operator_and_spelling_is_on_the_page():
    page = PAGE.read_text(encoding="utf-8")
    for word in KEYWORDS:
        assert f"`{word}" in page or f"`{word}(" in page or f"{word}[" in page or f" `{word}`" in page, word


@pytest.mark.parametrize("formula, message", [tuple(c.strip("`") for c in row)
                                              for row in _table("## Mistakes and their messages")])
def test_the_mistakes_table_shows_the_parsers_messages(formula, message):
    with pytest.raises(StlSyntaxError) as info:
        parse(formula)
    shown = message.split("...")[0]
    assert str(info.value).startswith(shown), str(info.value)


def test_the_pages_example_runs_as_written(tmp_path):
    from docs_pages import run_pages

    result = run_pages([PAGE], home=tmp_path, cwd=tmp_path, update=False)
    assert result.ran, "no command ran: the page lost its <!-- run --> marker"
    assert not result.problems, "\n\n".join(result.problems)
