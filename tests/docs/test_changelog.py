"""docs/changelog.md is a changelog a user reads (issue 33; the 2100-line measurement log it was is
docs/measurement-log.md): Keep a Changelog's shape, per version Added / Changed / Fixed (and the
format's other kinds), newest first, and its newest version is the package's."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

import pytest_navscenario

tomllib = pytest.importorskip("tomllib", reason="reading pyproject.toml needs Python 3.11 (tomllib)")

ROOT = Path(__file__).resolve().parents[2]
CHANGELOG = ROOT / "docs" / "changelog.md"
KINDS = ("Added", "Changed", "Deprecated", "Removed", "Fixed", "Security")


def _versions(text: str) -> list[tuple[str, str]]:
    return re.findall(r"^## \[(\d+\.\d+\.\d+)\] - (\d{4}-\d{2}-\d{2})$", text, re.M)


def test_the_changelog_is_keep_a_changelog_and_short():
    text = CHANGELOG.read_text(encoding="utf-8")
    versions = _versions(text)
    assert versions, "no '## [X.Y.Z] - YYYY-MM-DD' version headings"
    numbers = [tuple(map(int, v.split("."))) for v, _ in versions]
    assert numbers == sorted(numbers, reverse=True) and len(set(numbers)) == len(numbers), "newest first, once each"
    kinds = re.findall(r"^### (.+)$", text, re.M)
    assert kinds and set(kinds) <= set(KINDS), f"subsections other than {KINDS}: {sorted(set(kinds) - set(KINDS))}"
    assert len(text.splitlines()) < 400, "a changelog is a line per change; measurements go to measurement-log.md"
    assert (ROOT / "docs" / "measurement-log.md").read_text(encoding="utf-8").startswith("# Measurement log")


def test_its_newest_version_is_the_packages():
    newest = _versions(CHANGELOG.read_text(encoding="utf-8"))[0][0]
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert newest == project == pytest_navscenario.__version__, (
        f"changelog {newest}, pyproject.toml {project}, __version__ {pytest_navscenario.__version__}: a change of "
        f"behaviour gets its line under a new version, and both version strings follow")


def test_benchmark_rows_hold_a_figure_not_a_story():
    """docs/benchmarks.md had rows of 900 characters; the story of a figure goes to the measurement
    log, which the row links (docs/contributing.md)."""
    rows = [(i + 1, line) for i, line in enumerate((ROOT / "docs" / "benchmarks.md").read_text(
        encoding="utf-8").splitlines()) if line.startswith("|")]
    long = [f"benchmarks.md:{n}: {len(line)} characters" for n, line in rows if len(line) > 700]
    assert not long, "rows longer than 700 characters (one figure per row, the story in measurement-log.md):\n  " \
        + "\n  ".join(long)
