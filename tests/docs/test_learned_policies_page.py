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


def test_the_onnx_extra_installs_what_the_pages_scripts_import():
    """`pip install "pytest-navscenario[onnx]"`, as the page says, then its scripts run: every module
    they import is the standard library's, or a distribution of the package's own dependencies or
    of the onnx extra (issue 32: make_policy.py failed with No module named 'onnx')."""
    import ast
    import sys
    import tomllib
    from importlib.metadata import packages_distributions

    from packaging.requirements import Requirement

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    given = {Requirement(r).name.lower() for r in project["dependencies"] + project["optional-dependencies"]["onnx"]}
    dists = packages_distributions()
    scripts = [s for s in read_steps(PAGE) if s.kind == "file" and s.path.endswith(".py")]
    assert scripts, "the page writes no Python script any more: this test has nothing to check"
    for step in scripts:
        tree = ast.parse("\n".join(step.block.lines))
        names = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        names |= {n.module.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module}
        for name in sorted(names - set(sys.stdlib_module_names) - {"pytest_navscenario"}):
            owners = {d.lower() for d in dists.get(name, [name])}
            assert owners & given, (f"{step.block.where}: {step.path} imports {name}, which neither the "
                                    f"package's dependencies nor its onnx extra install (pyproject.toml)")


@pytest.mark.heavy
def test_the_learned_policies_example_runs_as_written(tmp_path):
    pytest.importorskip("onnxruntime", reason="the page's example needs onnxruntime: pip install -e '.[onnx]'")
    pytest.importorskip("onnx", reason="the page's example builds its model with onnx: pip install -e '.[onnx]'")
    shutil.copytree(ROOT / "scenarios", tmp_path / "scenarios",
                    ignore=shutil.ignore_patterns("regressions", "suites", "__pycache__"))
    result = run_pages([PAGE], home=tmp_path, cwd=tmp_path, update=UPDATE)
    assert result.ran, "no command ran: the page lost its <!-- run --> markers"
    if UPDATE and result.rewrites:
        print("rewrote the outputs at " + ", ".join(apply_rewrites(result.rewrites)))
    assert not result.problems, "\n\n".join(result.problems)
