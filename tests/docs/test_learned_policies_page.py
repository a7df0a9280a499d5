"""docs/how-to/learned-policies.md runs as written: its complete example builds a model, writes its
declaration, checks, runs, tests and searches it (as the tutorial pages run, docs_pages.py), and
every output it shows is what the run printed. ``NAVSCENARIO_DOCS_UPDATE=1`` rewrites them."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from docs_pages import apply_rewrites, read_steps, run_pages, unmarked_shell_blocks

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "how-to" / "learned-policies.md"
UPDATE = os.environ.get("NAVSCENARIO_DOCS_UPDATE") == "1"


def test_the_pages_markup_is_valid_and_every_command_says_whether_it_runs():
    read_steps(PAGE)
    assert not unmarked_shell_blocks(PAGE)


@pytest.mark.heavy
def test_the_learned_policies_example_runs_as_written(tmp_path):
    pytest.importorskip("onnxruntime", reason="the page's example needs onnxruntime: pip install -e '.[onnx]'")
    pytest.importorskip("onnx", reason="the page's example builds its model with onnx: pip install -e '.[dev]'")
    shutil.copytree(ROOT / "scenarios", tmp_path / "scenarios",
                    ignore=shutil.ignore_patterns("regressions", "suites", "__pycache__"))
    result = run_pages([PAGE], home=tmp_path, cwd=tmp_path, update=UPDATE)
    assert result.ran, "no command ran: the page lost its <!-- run --> markers"
    if UPDATE and result.rewrites:
        print("rewrote the outputs at " + ", ".join(apply_rewrites(result.rewrites)))
    assert not result.problems, "\n\n".join(result.problems)
