"""CI (.ci/run) tests a fresh machine: a new virtual environment made from nothing on every run, the
project and every extra installed into it, and the README's own commands run with that environment's
executables. Issue 32: CI installed into a Python that already had MuJoCo 4.0.0 and stayed green while
a fresh install (4.0.1) failed 3 tests. These read the script as text (running it installs from the
registries for minutes); `bash -n` checks that it parses."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

from docs_pages import read_blocks

ROOT = Path(__file__).resolve().parents[2]
CI = ROOT / ".ci" / "run"


def _lines() -> list[str]:
    """The script's commands: comments and blank lines left out."""
    return [ln.strip() for ln in CI.read_text().splitlines() if ln.strip() and not ln.lstrip().startswith("#")]


def _first(lines: list[str], pattern: str) -> int:
    hits = [i for i, ln in enumerate(lines) if re.search(pattern, ln)]
    assert hits, f".ci/run has no line matching {pattern!r}"
    return hits[0]


def test_ci_parses_and_keeps_bytecode_caching_on():
    subprocess.run(["bash", "-n", str(CI)], check=True)
    assert "unset PYTHONDONTWRITEBYTECODE" in _lines()


def test_ci_makes_a_new_environment_and_installs_every_extra_into_it_before_any_test():
    lines = _lines()
    venv = _first(lines, r"-m venv \"?\$")                           # into a fresh temporary folder
    assert re.search(r"mktemp -d", "\n".join(lines[:venv])), "the new environment's folder is a new temp dir"
    install = _first(lines, r"pip install .*-e \"?\.\[dev,ray,onnx,gpu\]")
    assert install > venv and "$venv/bin/python -m pip" in lines[install].replace('"', "")
    path = _first(lines, r'^export PATH="\$venv/bin:\$PATH"')
    first_test = _first(lines, r"^(python -m )?pytest ")
    assert venv < path < first_test and install < first_test
    assert _first(lines, r"command -v") < first_test                  # and checks whose pytest it runs


def test_ci_runs_exactly_the_readme_test_command_then_heavy_lint_and_docs():
    readme = [b for b in read_blocks(ROOT / "README.md") if b.marker == "skip" and "CI" in b.argument]
    assert readme, "the README's test command block (marked skip: ... CI (.ci/run) runs exactly this command)"
    command = readme[0].lines[0].split("#")[0].strip()
    lines = _lines()
    order = [lines.index(command), lines.index("pytest -n 2 -m heavy"), lines.index("lint-imports"),
             _first(lines, r"^NO_MKDOCS_2_WARNING=1 mkdocs build --strict")]
    assert order == sorted(order)


def test_the_readme_says_how_long_the_fresh_install_takes():
    text = (ROOT / "README.md").read_text()
    assert re.search(r"fresh virtual environment.{0,200}?install.{0,120}?\d+ (s|min)", text, re.S), \
        "the README states the time of CI's fresh install"
