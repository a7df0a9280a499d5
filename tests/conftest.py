"""Suite-wide check (issue 28): every scenario file the tool wrote during this test session (frozen
failures, generated suites, imported seeds: each starts with the YAML language server's modeline)
validates against the scenario schema, as an editor or check-jsonschema would read it. Checked
once per process at the end of the session, over the session's temporary folders (pytester runs
included); a file that does not validate is an error of the session's last test. The check needs
the dev extra's reference validator (jsonschema, and ruamel.yaml through check-jsonschema): without
it the check is left out and the report header says so."""
from __future__ import annotations

import importlib.util

import pytest

# Top-level names only: find_spec("ruamel.yaml") would import the "ruamel" namespace into this process,
# and pytester's in-process runs, which drop the modules they imported, would then leave it holding a
# stale ruamel.yaml (rosbags' metadata reader failed on valid YAML after one).
SCHEMA_CHECK_MISSING = [name for name in ("jsonschema", "ruamel") if importlib.util.find_spec(name) is None]

# Extension modules built with pybind11 register their types once per process: imported a second
# time they fail ('generic_type: type "FillType" is already registered!'). pytester's in-process runs
# drop the modules first imported inside them, so one of these first imported by a plugin run inside
# a test was re-imported by the next test of that worker (8 from-bag and terrain-picture tests failed
# with contourpy, depending on which tests a worker got). Imported here first, they are kept.
for _name in ("contourpy", "mujoco", "onnxruntime", "kiss_icp"):
    if importlib.util.find_spec(_name) is not None:
        importlib.import_module(_name)


def pytest_report_header(config: pytest.Config) -> str | None:
    if SCHEMA_CHECK_MISSING:
        return (f"written scenario files are not checked against the schema ({', '.join(SCHEMA_CHECK_MISSING)} "
                f"missing): pip install -e '.[dev]'")
    return None


@pytest.fixture(scope="session", autouse=True)
def _written_scenarios_validate(tmp_path_factory: pytest.TempPathFactory):
    yield
    if SCHEMA_CHECK_MISSING:
        return
    from pytest_navscenario.scenario.modeline import PREFIX

    base = tmp_path_factory.getbasetemp()
    written = []
    for path in base.rglob("*.yaml"):
        if not path.is_file():   # a named pipe a test made (opening it would wait for a writer)
            continue
        try:
            with open(path, encoding="utf-8") as fh:
                if fh.readline().startswith(PREFIX):
                    written.append(path)
        except (OSError, UnicodeDecodeError):
            continue
    if not written:
        return
    import jsonschema
    from ruamel.yaml import YAML

    from pytest_navscenario.scenario.json_schema import scenario_schema

    validator = jsonschema.Draft202012Validator(scenario_schema())
    reader = YAML(typ="safe", pure=True)
    problems = []
    for path in written:
        errors = [f"{'/'.join(map(str, e.absolute_path))}: {e.message}"
                  for e in validator.iter_errors(reader.load(path.read_text(encoding="utf-8")))]
        if errors:
            problems.append(f"{path}: " + "; ".join(errors[:3]))
    if problems:
        pytest.fail(f"{len(problems)} of the {len(written)} scenario files written during the session do not "
                    f"validate against the scenario schema:\n" + "\n".join(problems[:20]), pytrace=False)
