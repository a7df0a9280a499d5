"""--nav-ray's bad inputs are usage errors before any episode (with or without Ray installed)."""
from __future__ import annotations

import sys

import pytest

# Before pytester's in-process runs snapshot sys.modules (numpy cannot be loaded twice).
import pytest_navscenario.plugin.payload  # noqa: F401

SCENARIO = """version: 1
mission: {start: {x: 0, y: 0}, goal: {x: 0, y: 2}, timeout: 6}
"""


@pytest.fixture
def suite(pytester: pytest.Pytester) -> pytest.Pytester:
    pytester.makefile(".yaml", s1=SCENARIO)
    return pytester


def usage_error(result: pytest.RunResult) -> str:
    assert result.ret == pytest.ExitCode.USAGE_ERROR, result.stdout.str()[-2000:]
    assert "passed" not in result.stdout.str() and "failed" not in result.stdout.str()
    return result.stderr.str()


def test_without_ray_installed_the_error_says_how_to_install_it(suite: pytest.Pytester, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)        # `import ray` fails as if not installed
    err = usage_error(suite.runpytest("--nav-ray=auto", "-p", "no:cacheprovider"))
    assert "--nav-ray needs Ray, which is not installed here" in err
    assert 'pip install "pytest-navscenario[ray]"' in err


def test_collect_only_starts_no_ray(suite: pytest.Pytester, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)
    result = suite.runpytest("--nav-ray=auto", "--collect-only", "-q", "-p", "no:cacheprovider")
    assert result.ret == pytest.ExitCode.OK
    result.stdout.fnmatch_lines(["s1.yaml::s1"])


@pytest.mark.parametrize("args, expected", [
    (["--nav-ray=somewhere"], "--nav-ray: expected 'auto' (start a local Ray instance) or the address"),
    (["--nav-ray=10.0.0.5:6379", "-n", "2"], "runs the episodes on the cluster, which decides how many run at once; drop -n"),
    (["--nav-ray=auto", "-n", "0"], "would give the local Ray instance no CPU"),
    (["--nav-ray=auto", "-n", "-1"], "-n -1: the number of worker processes must be 0 or more"),
], ids=["not-an-address", "address-with-n", "auto-n0", "negative-n"])
def test_bad_values_are_usage_errors(suite: pytest.Pytester, args: list[str], expected: str):
    assert expected in usage_error(suite.runpytest(*args, "-p", "no:cacheprovider"))


def test_the_ini_twin_is_checked_too(suite: pytest.Pytester):
    suite.makeini("[pytest]\nnav_ray = not an address\n")
    assert "ini option nav_ray: expected 'auto'" in usage_error(suite.runpytest("-p", "no:cacheprovider"))


def test_help_describes_the_option_and_its_ini_twin(pytester: pytest.Pytester):
    out = " ".join(pytester.runpytest("--help").stdout.str().split())   # unwrap the help text
    assert "--nav-ray=ADDRESS" in out and "[ini: nav_ray]" in out
    assert "nav_ray (string)" in out
