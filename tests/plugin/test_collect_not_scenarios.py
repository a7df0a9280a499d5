"""Issue 15 item 8: a file named on the command line gets the loader's real message (not pytest's
"not found"); a UTF-16/32 scenario with a byte-order mark loads; empty, binary and scalar-root
YAML files beside scenarios are counted in the summary and listed with -v. Real pytest runs."""
from __future__ import annotations

import pytest

import pytest_navscenario.plugin.payload  # noqa: F401  (numpy: in-process runs cannot import it afresh)

from pytest_navscenario.scenario.loader import load_scenario

PLUGIN = ["-p", "pytest_navscenario.plugin", "--nav-plots=none"]
OK = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 1, y: 0}, timeout: 10}\n"


@pytest.fixture
def project(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> pytest.Pytester:
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    (pytester.path / "s").mkdir()
    (pytester.path / "s" / "ok.yaml").write_text(OK)
    return pytester


@pytest.mark.parametrize("content, message", [
    (b"", "the scenario is empty"),
    (b"just a sentence\n", "the top level must be a mapping of scenario fields"),
    (b"name: x\nrobot: {}\n", "missing required field 'version'"),
    (b"\x00\x01\xff\xfe\x00binary", "not UTF-8 text"),
])
def test_a_named_file_gets_the_loaders_message(project, content, message):
    (project.path / "s" / "named.yaml").write_bytes(content)
    result = project.runpytest(*PLUGIN, "--collect-only", "s/named.yaml")
    out = result.stdout.str()
    assert "not found" not in out + result.stderr.str()
    assert message in out
    assert "named.yaml" in out


@pytest.mark.parametrize("codec", ["utf-16", "utf-16-le", "utf-16-be", "utf-32", "utf-32-le", "utf-32-be"])
def test_utf16_and_utf32_with_a_byte_order_mark_load(project, tmp_path, codec):
    bom = {"utf-16-le": b"\xff\xfe", "utf-16-be": b"\xfe\xff", "utf-32-le": b"\xff\xfe\x00\x00",
           "utf-32-be": b"\x00\x00\xfe\xff"}.get(codec, b"")
    (project.path / "s" / "wide.yaml").write_bytes(bom + OK.encode(codec))
    assert load_scenario(project.path / "s" / "wide.yaml").mission.goal.x == 1
    result = project.runpytest(*PLUGIN, "--collect-only", "-q", "s")
    result.stdout.fnmatch_lines(["s/ok.yaml::ok", "s/wide.yaml::wide", "2 tests collected*"])


def test_skipped_yaml_files_beside_scenarios_are_counted_and_listed_with_v(project):
    (project.path / "s" / "empty.yaml").write_text("# nothing yet\n")
    (project.path / "s" / "blob.yaml").write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\xff\xd8")
    (project.path / "s" / "scalar.yaml").write_text("42\n")
    (project.path / "s" / "config.yaml").write_text("colour: blue\n")     # another tool's file: fine
    (project.path / "elsewhere").mkdir()
    (project.path / "elsewhere" / "empty.yaml").write_text("")            # no scenario beside it
    result = project.runpytest(*PLUGIN, "--collect-only", "-q", ".")
    result.stdout.fnmatch_lines(["navscenario: 3 YAML files beside scenarios are not scenarios "
                                 "(empty, binary or not a mapping); -v lists them"])
    assert "config.yaml" not in result.stdout.str()
    result = project.runpytest(*PLUGIN, "--collect-only", "-v", ".")
    result.stdout.fnmatch_lines(["navscenario: 3 YAML files beside scenarios are not scenarios*",
                                 "  s/blob.yaml: not text*",
                                 "  s/empty.yaml: empty*",
                                 "  s/scalar.yaml: the top level is 42 (an integer), not a mapping*"])
    assert "elsewhere" not in result.stdout.str() and "config.yaml" not in result.stdout.str()


def test_xdist_workers_send_the_count_to_the_controller(project):
    (project.path / "s" / "empty.yaml").write_text("")
    result = project.runpytest_subprocess(*PLUGIN, "-p", "xdist.plugin", "-n", "2", "-v", "s")
    result.assert_outcomes(passed=1)
    result.stdout.fnmatch_lines(["navscenario: 1 YAML file beside scenarios is not a scenario (empty, binary or not a mapping)",
                                 "  s/empty.yaml: empty*"])
