"""Issue 34, the docs: the signals page lists every built-in signal, and every requirement written
in the tutorial and the reference pages parses (and its declared signals load)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from pytest_navscenario.scenario.requirements import BUILTIN_SIGNALS
from pytest_navscenario.stl import parse

DOCS = Path(__file__).resolve().parents[2] / "docs"
PAGES = [DOCS / "reference" / "signals.md", DOCS / "tutorial" / "requirements.md"]


def test_the_signals_page_lists_every_built_in_signal():
    text = (DOCS / "reference" / "signals.md").read_text()
    missing = [name for name in BUILTIN_SIGNALS if f"`{name}`" not in text]
    assert not missing


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_formula_on_the_page_parses(page):
    specs = re.findall(r'spec: "([^"]+)"', page.read_text())
    assert specs
    for spec in specs:
        parse(spec)
