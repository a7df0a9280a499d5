"""Texts that describe the project and drifted from it (issue 32): the README's manual table names
every page of the site, tutorial 4 counts the seeds there are, tutorial 3 says what the two-search
run does, and ``navscenario import --help`` names what the import page documents."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from pytest_navscenario.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
NUMBERS = "zero one two three four five six seven eight nine ten eleven twelve thirteen fourteen fifteen " \
          "sixteen seventeen eighteen nineteen twenty".split()


def _nav_pages(node) -> list[str]:
    if isinstance(node, str):
        return [node]
    if isinstance(node, dict):
        return [p for v in node.values() for p in _nav_pages(v)]
    return [p for v in node for p in _nav_pages(v)]


def test_the_readme_manual_table_links_every_page_of_the_site():
    nav = yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))["nav"]
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    table = readme[readme.index("## The manual"):]
    table = table[:table.index("\n\n", table.index("| tutorial |"))]
    linked = set(re.findall(r"\]\(docs/([^)#]+)\)", table))
    missing = [p for p in _nav_pages(nav) if p != "index.md" and p not in linked]
    assert not missing, f"README.md's manual table leaves out {missing}: add them to its rows"


def test_tutorial_4_counts_the_shipped_seeds():
    seeds = len(list((ROOT / "scenarios").glob("*.yaml")))
    text = (ROOT / "docs" / "tutorial" / "compare-in-ci.md").read_text(encoding="utf-8")
    said = re.search(r"`scenarios/` now holds the (\w+) seeds", text)
    assert said and said.group(1) == NUMBERS[seeds], f"compare-in-ci.md says {said and said.group(1)!r}, " \
                                                     f"scenarios/ holds {seeds} seeds"


def test_tutorial_3_says_two_searches_in_one_run_go_one_after_the_other():
    text = (ROOT / "docs" / "tutorial" / "first-search.md").read_text(encoding="utf-8")
    before = text[:text.index("pytest -n 2 --navsearch boxes1 --navsearch corridor")]
    sentence = before[before.rindex("compares the two)"):]
    assert "at once" not in sentence and "one after the other" in sentence   # what the run's header prints


def test_import_help_names_what_the_import_page_documents(capsys):
    with pytest.raises(SystemExit):
        main(["import", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for kind in ("boxes", "cylinders", "polylines", "meshes", "heightmaps"):
        assert kind in text, f"navscenario import --help does not name {kind}"
