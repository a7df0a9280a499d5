"""The tutorial and the README's examples run as written: their commands are run in order in a fresh
folder (the files the pages tell the reader to create, the package installed as it is) and every
output a page shows must be what the run printed, but for the masked values (docs_pages.MASKS).

``NAVSCENARIO_DOCS_UPDATE=1 pytest tests/docs -m heavy`` rewrites the pages' outputs from a run
(docs/contributing.md, "Executable pages")."""
from __future__ import annotations

import io
import os
import re
import shutil
from pathlib import Path

import pytest
from _pytest._io import TerminalWriter

from docs_pages import (MASKS, MarkupError, apply_rewrites, matches, read_blocks, read_steps, run_pages, shown,
                        unmarked_shell_blocks, updated)

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
TUTORIAL = [ROOT / "docs" / "tutorial" / name for name in
            ("first-scenario.md", "own-planner.md", "first-search.md", "compare-in-ci.md", "terrain.md",
             "requirements.md")]
UPDATE = os.environ.get("NAVSCENARIO_DOCS_UPDATE") == "1"


def _copy_scenarios(to: Path) -> None:
    """The shipped seeds as a fresh clone has them (no search output a developer left behind)."""
    shutil.copytree(ROOT / "scenarios", to, ignore=shutil.ignore_patterns("regressions", "suites", "__pycache__"))


def _finish(result, pages) -> None:
    if UPDATE and result.rewrites:
        changed = apply_rewrites(result.rewrites)
        print("rewrote the outputs at " + ", ".join(changed))
    for skipped in result.skipped:
        print(f"not run: {skipped}")
    print(f"{len(result.ran)} commands: {sum(r.wall for r in result.ran):.1f} s wall, "
          f"{sum(r.cpu for r in result.ran):.1f} s CPU; the slowest:")
    for r in sorted(result.ran, key=lambda r: r.cpu, reverse=True)[:5]:
        print(f"  {r.cpu:5.1f} s CPU {r.wall:5.1f} s wall  {r.command.block.where}  {r.command.text.splitlines()[0]}")
    assert not result.problems, f"{len(result.problems)} difference(s) between the pages and a run:\n\n" + \
        "\n\n".join(result.problems)


@pytest.mark.heavy
def test_tutorial_runs_as_written(tmp_path):
    """Tutorials 1-6 in order, in one project: the reader's folder beside a checkout of this project."""
    _copy_scenarios(tmp_path / "pytest-navscenario" / "scenarios")
    result = run_pages(TUTORIAL, home=tmp_path, cwd=tmp_path, update=UPDATE)
    assert result.ran, "no command ran: the tutorial pages lost their <!-- run --> markers"
    _finish(result, TUTORIAL)


@pytest.mark.heavy
def test_readme_examples_run_as_written(tmp_path):
    """The README's quick start, scenario, search and comparison, in a fresh clone's folder."""
    _copy_scenarios(tmp_path / "scenarios")
    result = run_pages([README], home=tmp_path, cwd=tmp_path, update=UPDATE)
    assert result.ran, "no command ran: the README lost its <!-- run --> markers"
    _finish(result, [README])


def _skipped_blocks():
    params = []
    for page in [README, *TUTORIAL]:
        try:
            steps = read_steps(page)
        except MarkupError:
            continue                    # test_pages_markup_is_valid says what is wrong
        params += [pytest.param(f"{step.block.where}: not run by the docs test: {step.reason}", id=step.block.where)
                   for step in steps if step.kind == "skip"]
    return params


@pytest.mark.heavy
@pytest.mark.parametrize("reason", _skipped_blocks())
def test_commands_the_docs_test_does_not_run(reason):
    """Each block marked <!-- skip: REASON --> shows up in the report with its reason."""
    pytest.skip(reason)


# --- fast checks of the markup and of the comparison (default run) ------------------------------


@pytest.mark.parametrize("page", [README, *TUTORIAL], ids=lambda p: p.name)
def test_pages_markup_is_valid_and_every_command_says_whether_it_runs(page):
    read_steps(page)
    assert not unmarked_shell_blocks(page), (
        f"command blocks without <!-- run --> or <!-- skip: REASON --> in {page.name}: "
        f"{unmarked_shell_blocks(page)}")


def test_the_tutorial_list_is_the_sites_tutorial_in_order():
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    listed = re.findall(r"^\s+- \d\. [^:]+: (tutorial/\S+\.md)$", nav, flags=re.M)
    assert listed == [str(p.relative_to(ROOT / "docs")) for p in TUTORIAL]


def test_an_ellipsis_stands_for_any_lines_and_masks_hide_only_wall_times():
    page = ["collected 9 items", "...", "===== 9 passed in 0.76s =====",]
    assert matches(page, ["collected 9 items", "a", "b", "========== 9 passed in 12.10s =========="])
    assert matches(page, ["collected 9 items", "=== 9 passed in 3.2s ==="])
    assert not matches(page, ["collected 8 items", "=== 9 passed in 3.2s ==="])
    assert not matches(page, ["collected 9 items", "=== 8 passed in 3.2s ==="])
    assert not matches(["x", "..."], ["y", "x"])                     # no ellipsis before: anchored
    # a simulated time is not a wall time: it must match exactly
    assert not matches(["safety stop at t=2.80 s"], ["safety stop at t=2.90 s"])
    assert matches(["best clearance 0.029 m, 50 sims, 1.2 s"], ["best clearance 0.029 m, 50 sims, 14.0 s"])
    assert not matches(["best clearance 0.029 m, 50 sims, 1.2 s"], ["best clearance 0.038 m, 50 sims, 1.2 s"])
    assert matches(["<object at 0x7f12ab34cd56>"], ["<object at 0x55aa00ff1234>"])
    # a rule whose title held the temporary folder is centred again once the folder shows as ~
    long = "= comparison with the baseline /tmp/pytest-of-me/pytest-7/test_tutorial0/my-project/a.jsonl ="
    out = io.StringIO()
    writer = TerminalWriter(out)
    writer.fullwidth = 80
    writer.sep("=", "comparison with the baseline ~/my-project/a.jsonl")
    assert shown(long, Path("/tmp/pytest-of-me/pytest-7/test_tutorial0")) == [out.getvalue().rstrip("\n")]


def test_update_keeps_the_pages_elisions_and_takes_the_lines_most_like_them():
    page = ["header", "...", "boxes1 vs dwa: 11 distinct failure(s), best clearance 0.029 m",
            "  new  a.yaml  safety-stop", "...", "=== 1 passed in 1.0s ==="]
    run = ["header", "progress 1", "progress 2", "boxes1 vs dwa: 13 distinct failure(s), best clearance 0.038 m",
           "  new  b.yaml  timeout", "  new  c.yaml  safety-stop", "  log  x", "=== 1 passed in 2.5s ==="]
    new = updated(page, run)
    assert new == ["header", "...", "boxes1 vs dwa: 13 distinct failure(s), best clearance 0.038 m",
                   "  new  b.yaml  timeout", "...", "=== 1 passed in 2.5s ==="]
    assert matches(new, run)
    assert updated(["a", "b"], ["c"]) == ["c"]                       # no ellipsis: the whole output
    # a shown list that grew shows whole: from the line most like its first to the one most like its last
    page = ["...", "=== navsearch summary ===", "  new  a.yaml", "  log  x", "=== 1 passed in 1.0s ==="]
    run = ["progress", "=== navsearch summary ===", "  new  a.yaml", "  new  b.yaml", "  log  x",
           "=== 1 passed in 2.0s ==="]
    assert updated(page, run) == ["...", *run[1:]]


def test_markup_errors_say_where_and_how_to_fix(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("<!-- run: exit 1 0 -->\n```sh\ntrue\nfalse\ntrue\n```\n")
    with pytest.raises(MarkupError, match=r"page.md:2: .* 2 exit status\(es\) for 3 command\(s\)"):
        read_steps(page)
    page.write_text("<!-- run: exit 1 -->\n```sh\ntrue\nfalse\n```\n")
    assert [c.exit for c in read_steps(page)[0].commands] == [0, 1]
    page.write_text("<!-- output -->\n```text\nhello\n```\n")
    with pytest.raises(MarkupError, match="must follow a run block"):
        read_steps(page)
    page.write_text("<!-- run -->\nsome text\n```sh\ntrue\n```\n")
    with pytest.raises(MarkupError, match=r"page.md:1: .* right before a code block"):
        read_blocks(page)
    page.write_text("```sh\npytest\n```\n<!-- skip: needs ray -->\n```sh\npytest --nav-ray\n```\n")
    assert unmarked_shell_blocks(page) == ["page.md:1"]
    assert [s.reason for s in read_steps(page)] == ["needs ray"]


def test_every_mask_is_documented_for_page_writers():
    """docs/contributing.md lists each placeholder a page's output may differ by."""
    text = (ROOT / "docs" / "contributing.md").read_text(encoding="utf-8")
    for name, _, replacement in MASKS:
        placeholder = re.sub(r"\\\d", "", replacement).strip() or "rule line"   # the rule mask keeps the title
        assert placeholder in text, f"mask {name!r} ({placeholder}) is not in docs/contributing.md"
