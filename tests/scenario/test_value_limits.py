"""Issue 26 items 9 and 11 and its "latency longer than the timeout": mesh coordinates and scale are
range-checked, a NUL byte in a path is a scenario error (not a crash of collection or check-planner),
and a delay the robot can never outlive is refused, each with file, line and field."""
from __future__ import annotations

import struct
import textwrap
from pathlib import Path

import pytest

from pytest_navscenario import ScenarioError, load_scenario
from pytest_navscenario.cli.main import main as cli_main

HEAD = textwrap.dedent("""\
    version: 1
    mission:
      start: {x: 0, y: 0}
      goal: {x: 0, y: 10}
    """)


def write_stl(path: Path, corners: float) -> Path:
    """A binary STL of one tetrahedron reaching ``corners`` metres from the origin."""
    v = [(0, 0, 0), (corners, 0, 0), (0, corners, 0), (0, 0, corners)]
    faces = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (2, 0, 3)]
    with open(path, "wb") as fh:
        fh.write(b"\0" * 80 + struct.pack("<I", len(faces)))
        for a, b, c in faces:
            fh.write(struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *v[i]) for i in (a, b, c)) + b"\0\0")
    return path


def load_error(tmp_path: Path, text: str) -> ScenarioError:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(info.value).startswith(f"{path}:{info.value.line}: {info.value.field}: ")
    return info.value


@pytest.mark.parametrize("corners, scale, field, message", [
    (1e30, "1", "obstacles[0].file", "a vertex lies 1e+30 m from the mesh's origin"),
    (2.0, "1000000", "obstacles[0].scale", "must be <= 1000, got 1000000.0"),
    (2000.0, "1000", "obstacles[0].file", "a vertex lies 2e+06 m from the mesh's origin"),
    (2.0, "[1, 1, 5000]", "obstacles[0].scale[2]", "must be <= 1000"),
])
def test_mesh_coordinates_and_scale_are_range_checked(tmp_path, corners, scale, field, message):
    write_stl(tmp_path / "part.stl", corners)
    err = load_error(tmp_path, HEAD + f"obstacles:\n  - {{type: mesh, file: part.stl, x: 5, y: 5, scale: {scale}}}\n")
    assert (err.line, err.field) == (6, field) and message in str(err)


def test_a_mesh_within_the_limits_still_loads(tmp_path):
    write_stl(tmp_path / "part.stl", 2000.0)
    s = load_scenario(_write(tmp_path, HEAD + "obstacles:\n  - {type: mesh, file: part.stl, x: 5, y: 5, scale: 0.001}\n"))
    assert s.obstacles[0].height == pytest.approx(2.0)


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("entry, field", [
    ('obstacles:\n  - {type: mesh, file: "meshes/a\\0.stl"}\n', "obstacles[0].file"),
    ('reference: {file: "runs/a\\0.csv"}\n', "reference.file"),
])
def test_a_nul_byte_in_a_path_is_a_scenario_error(tmp_path, entry, field):
    err = load_error(tmp_path, HEAD + entry)
    assert (err.line, err.field) == (5 if entry.startswith("reference") else 6, field)
    assert "NUL byte" in str(err) and err.hint


def test_check_planner_reports_a_nul_byte_in_a_mesh_path_as_a_scenario_error(tmp_path, capsys):
    path = _write(tmp_path, HEAD + 'obstacles:\n  - {type: mesh, file: "meshes/a\\0.stl"}\n')
    assert cli_main(["check-planner", "potential-field", "--scenario", str(path), "--ticks", "2"]) == 2
    err = capsys.readouterr().err
    assert "obstacles[0].file" in err and "NUL byte" in err and "Traceback" not in err


@pytest.mark.parametrize("latency, field, message", [
    ("{command: 5.0}", "robot.latency.command", "no command would act before the episode ends"),
    ("{observation: 6.0}", "robot.latency.observation", "a delay of 6.0 s is not shorter than the timeout (5.0 s)"),
])
def test_a_latency_not_shorter_than_the_timeout_is_refused(tmp_path, latency, field, message):
    text = f"version: 1\nrobot:\n  latency: {latency}\n" + HEAD.replace("version: 1\n", "") + "  timeout: 5\n"
    err = load_error(tmp_path, text)
    assert (err.line, err.field) == (3, field) and message in str(err)
    assert load_scenario(_write(tmp_path, text.replace("5.0}", "4.9}").replace("6.0}", "4.9}")))
