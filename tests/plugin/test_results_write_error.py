"""Issue 15 item 7: when the results file cannot be written at the end of the run, the error is
one clear line of its own (not glued to pytest's progress line), nothing claims it was written,
and the run fails (a CI job must not pass with its results lost). A real pytest run whose results
folder is replaced by a file while the tests run."""
from __future__ import annotations

import pytest

from pytest_navscenario.scenario.loader import load_scenario  # noqa: F401  (see test_ini_types.py)

PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none"]
SCENARIO = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1, y: 0}, timeout: 10}\n"

CONFTEST = """
import shutil
import pytest

@pytest.hookimpl(wrapper=True)
def pytest_runtestloop(session):
    out = yield
    shutil.rmtree("out")
    open("out", "w").write("a file where the results folder was")
    return out
"""


def test_unwritable_results_file_is_one_line_no_success_claim_and_fails(pytester: pytest.Pytester,
                                                                         monkeypatch: pytest.MonkeyPatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makeconftest(CONFTEST)
    pytester.makefile(".yaml", ok=SCENARIO)
    result = pytester.runpytest_subprocess(*PLUGIN, "--nav-results=out/r.jsonl", "--nav-subject=potential-field")
    out = result.stdout.str()
    lines = [line for line in out.splitlines() + result.stderr.str().splitlines() if "cannot write" in line]
    assert len(lines) == 1, out
    assert lines[0] in out.splitlines()   # through pytest's terminal, on a line of its own
    assert lines[0].startswith("navscenario: cannot write the results file ")
    assert "out/r.jsonl" in lines[0] and "no results were written" in lines[0]
    assert "wrote" not in out
    assert result.ret == pytest.ExitCode.INTERNAL_ERROR
    result.assert_outcomes(passed=1)
