"""Hostile scenario files (issue 7): each gives a clear ScenarioError, never a crash, a hang or a
traceback from deep inside; a Hypothesis fuzz shows loading raises nothing else."""
from __future__ import annotations

import random
import textwrap

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pytest_navscenario import ScenarioError, load_scenario, loads_scenario
from pytest_navscenario.scenario.loader import SCENARIO_LIMITS, scenario_from_dict
from pytest_navscenario.scenario.dump import dump_scenario, scenario_to_dict

VALID = textwrap.dedent("""\
    version: 1
    mission:
      start: {x: 0, y: 0, yaw: 90}
      goal: {x: 0, y: 10, yaw: 90}
    obstacles:
      - {type: box, x: 3, y: 5, length: 1, width: 1}
    """)


def load_text(tmp_path, text: str | bytes, name: str = "hostile.yaml") -> ScenarioError:
    path = tmp_path / name
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(path) in str(info.value)
    return info.value


BILLION_LAUGHS = textwrap.dedent("""\
    version: 1
    a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]
    b: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a]
    c: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b]
    d: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c]
    e: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d]
    f: &f [*e,*e,*e,*e,*e,*e,*e,*e,*e]
    g: &g [*f,*f,*f,*f,*f,*f,*f,*f,*f]
    h: &h [*g,*g,*g,*g,*g,*g,*g,*g,*g]
    i: &i [*h,*h,*h,*h,*h,*h,*h,*h,*h]
    mission: *i
    """)


def test_alias_bomb_is_refused_before_it_expands(tmp_path):
    err = load_text(tmp_path, BILLION_LAUGHS)
    assert "alias bomb" in str(err) and f"more than {SCENARIO_LIMITS['max_nodes']} values" in str(err)
    assert err.line == 7  # refused while composing, at the first alias level past the limit


def test_merge_key_bomb_is_refused(tmp_path):
    lines = ["version: 1", "a0: &a0 {k: 1}"]
    lines += [f"a{i}: &a{i} {{<<: [*a{i - 1}, *a{i - 1}], k{i}: [*a{i - 1}, *a{i - 1}]}}" for i in range(1, 40)]
    err = load_text(tmp_path, "\n".join(lines) + "\n")
    assert "alias bomb" in str(err)


def test_small_aliases_and_merge_keys_work_like_safe_load():
    text = VALID + textwrap.dedent("""\
        robot:
          lidar: &lidar {beams: 18, range_max: 5}
        provenance:
          base: *lidar
          other: {<<: *lidar, beams: 9}
        """)
    s = loads_scenario(text)
    assert s.robot.lidar.beams == 18
    assert s.provenance == yaml.safe_load(text)["provenance"] == {"base": {"beams": 18, "range_max": 5},
                                                                 "other": {"beams": 9, "range_max": 5}}


def test_recursive_alias_is_an_error_not_a_hang(tmp_path):
    err = load_text(tmp_path, VALID + "search: &s {me: *s}\n")
    assert "alias *s" in str(err) and err.line == 7


@pytest.mark.parametrize("text", [
    "version: 1\nmission: " + "[" * 100_000 + "]" * 100_000 + "\n",   # libyaml's composer would segfault
    "version: 1\nmission: " + "{a: " * 50_000 + "1" + "}" * 50_000 + "\n",
    "version: 1\nmission:\n" + "".join(" " * i + f"k{i}:\n" for i in range(1, 200)),
], ids=["flow-lists", "flow-maps", "block"])
def test_deep_nesting_is_an_error_not_a_crash(tmp_path, text):
    err = load_text(tmp_path, text)
    assert f"more than {SCENARIO_LIMITS['max_depth']} levels" in str(err)


def test_deep_nesting_in_a_mapping_is_an_error():
    data: dict = {"version": 1, "mission": {}}
    inner = data["mission"]
    for _ in range(10_000):
        inner["x"] = {}
        inner = inner["x"]
    with pytest.raises(ScenarioError, match="nests more than"):
        scenario_from_dict(data)


@pytest.mark.parametrize("value,fragment", [
    ("1e308", "beyond the supported magnitude"), ("1.0e+308", "beyond the supported magnitude"),
    ("-2.0e6", "beyond the supported magnitude"), ("1" + "0" * 400, "beyond the supported magnitude"),
    ("1" + "0" * 5000, "cannot read value"), (".nan", "finite"), ("-.inf", "finite"),
    ("'12'", "expected a number, got '12'"), ("twelve", "expected a number, got 'twelve'"),
    ("[1, 2]", "expected a number, got a list"), ("{a: 1}", "expected a number, got a mapping"),
    ("", "expected a number, got null"), ("2001-12-14", "expected a number, got a date value"),
    ("!!binary aGVsbG8=", "expected a number, got a bytes value"),
], ids=lambda v: v[:20] if isinstance(v, str) else None)
def test_absurd_or_wrong_numbers(tmp_path, value, fragment):
    err = load_text(tmp_path, VALID.replace("x: 3,", f"x: {value},"))
    assert fragment in str(err) and err.line == 6
    assert err.field == "obstacles[0].x" or fragment == "cannot read value"


@pytest.mark.parametrize("data", [
    random.Random(7).randbytes(4096),                 # binary garbage
    b"\x89PNG\r\n\x1a\n" + bytes(range(256)),         # an image
    b"version: 1\nname: caf\xe9\n",                   # Latin-1, not UTF-8
    "version: 1\n".encode("utf-16"),                  # UTF-16
    b"version: 1\nname: a\x00b\n",                    # NUL inside text
    b"",                                              # empty
    b"   \n\n# only a comment\n",
], ids=["random", "png", "latin1", "utf16", "nul", "empty", "comment"])
def test_garbage_and_empty_files(tmp_path, data):
    err = load_text(tmp_path, data)
    assert err.hint


def test_a_directory_named_like_a_scenario(tmp_path):
    (tmp_path / "boxes1.yaml").mkdir()
    with pytest.raises(ScenarioError, match="is a directory, not a scenario file"):
        load_scenario(tmp_path / "boxes1.yaml")
    with pytest.raises(ScenarioError, match="no such scenario file"):
        load_scenario(tmp_path / "missing.yaml")


def _load_in_a_process(path) -> str:
    """Load ``path`` in a fresh process (a read that blocks on a named pipe ends with it after 20 s):
    what the loader said."""
    import subprocess
    import sys
    code = ("import sys\nfrom pytest_navscenario import ScenarioError, load_scenario\n"
            "try:\n    load_scenario(sys.argv[1])\nexcept ScenarioError as e:\n    print(repr(e.field), e)\n")
    try:
        done = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=20)
    except subprocess.TimeoutExpired:
        pytest.fail(f"loading {path.name} hung (reading a named pipe)")
    return done.stdout


@pytest.mark.skipif(not hasattr(__import__("os"), "mkfifo"), reason="named pipes are POSIX")
def test_a_named_pipe_named_like_a_scenario_or_its_robot_is_an_error_not_a_hang(tmp_path):
    import os
    os.mkfifo(tmp_path / "pipe.yaml")
    assert "is not a regular file" in _load_in_a_process(tmp_path / "pipe.yaml")
    os.mkfifo(tmp_path / "robot.xml")
    (tmp_path / "s.yaml").write_text("version: 1\nrobot: {drive: diff, body: {type: mjcf, file: robot.xml, "
                                     "controller: 'c:C'}}\nmission: {start: {x: 0, y: 0}, goal: {x: 5, y: 0}}\n")
    said = _load_in_a_process(tmp_path / "s.yaml")
    assert said.startswith("'robot.body.file'") and "is not a file" in said


def test_python_tags_are_refused_and_never_run(tmp_path):
    marker = tmp_path / "pwned"
    err = load_text(tmp_path, VALID + f"search: !!python/object/apply:os.system ['touch {marker}']\n")
    assert "unsupported YAML tag" in str(err) and not marker.exists()


def obstacle_lines(n: int) -> str:
    return "".join(f"  - {{type: cylinder, x: {10 + i % 100}, y: {10 + i // 100}, radius: 0.2}}\n" for i in range(n))


def test_too_many_obstacles_is_a_clear_error(tmp_path):
    limit = int(SCENARIO_LIMITS["max_obstacles"])
    err = load_text(tmp_path, VALID + obstacle_lines(20_000))
    assert f"obstacles: more than {limit} obstacles, the limit" in str(err) and err.line == 5


def test_obstacles_up_to_the_limit_load(tmp_path):
    limit = int(SCENARIO_LIMITS["max_obstacles"])
    path = tmp_path / "many.yaml"
    path.write_text(VALID + obstacle_lines(limit - 1))
    s = load_scenario(path)
    assert len(s.obstacles) == limit and s.obstacles[-1].name == f"cyl{limit - 1}"


def test_oversized_file_is_refused_unread(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_bytes(b"#" * (int(SCENARIO_LIMITS["max_file_bytes"]) + 10))
    with pytest.raises(ScenarioError, match="larger than the limit"):
        load_scenario(path)


# ------------------------------------------------------------------ fuzz: only ScenarioError, or success

YAML_ALPHABET = st.sampled_from(list("{}[]:-,&*!#|>'\"%@`?\n \t0123456789.eE+abxyz") +
                                ["version: 1\n", "mission:\n", "  start: {x: 0, y: 0}\n", "  goal: {x: 1, y: 9}\n",
                                 "obstacles:\n", "  - {type: box, ", "x: 1, y: 2, length: 1, width: 1}\n", "&a ",
                                 "*a", "<<: ", "!!binary ", "!!float ", ".nan", "1e308", "\ud800", "\x00", "\ufeff"])


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(YAML_ALPHABET, max_size=40).map("".join))
def test_fuzz_yaml_text_raises_only_scenario_error(text):
    try:
        loads_scenario(text)
    except ScenarioError:
        pass


json_like = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8) | st.binary(max_size=4),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8) | st.integers(), inner,
                                                                   max_size=4),
    max_leaves=6)
KEYS = ["version", "mission", "start", "goal", "x", "y", "yaw", "obstacles", "type", "robot", "lidar", "beams",
        "footprint", "shape", "marks", "simulation", "timestep", "reference", "points", "name", "length"]


def _mutate(data, paths, replacement):
    """Replace one value somewhere in the nested data (chosen by index) by ``replacement``."""
    spots = []

    def walk(obj):
        if isinstance(obj, dict):
            for k in list(obj):
                spots.append((obj, k))
                walk(obj[k])
        elif isinstance(obj, list):
            for i in range(len(obj)):
                spots.append((obj, i))
                walk(obj[i])
    walk(data)
    for index in paths:
        container, key = spots[index % len(spots)]
        container[key] = replacement
    return data


DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
BASE_DICT = scenario_to_dict(loads_scenario(VALID + "marks: [slow, {skip: why}]\nreference: {points: [[0, 0, 0]]}\n"))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.integers(0, 10_000), min_size=1, max_size=3), json_like,
       st.dictionaries(st.sampled_from(KEYS), json_like, max_size=3))
def test_fuzz_scenario_mappings_raise_only_scenario_error(paths, replacement, extra):
    import copy
    data = _mutate(copy.deepcopy(BASE_DICT), paths, replacement)
    data.update(extra)
    for attempt in (lambda: scenario_from_dict(data), lambda: loads_scenario(yaml.dump(data, Dumper=DUMPER))):
        try:
            s = attempt()
        except ScenarioError:
            continue
        assert loads_scenario(dump_scenario(s)) == s  # whatever loads also round-trips


def test_a_3d_lidar_too_dense_to_scan_or_to_record_is_refused_at_load_with_its_field(tmp_path):
    # 256 x 10000 rays passed before: 0.9 s CPU a scan, 10 MB recorded a tick (3 GB for 30 s)
    robot = "robot: {drive: diff, lidar3d: {rings: %d, beams: %d}}\n"
    base = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 5, y: 0}, timeout: %g}\n"
    err = load_text(tmp_path, base % 30 + robot % (256, 10000))
    assert err.field == "robot.lidar3d.beams" and err.line == 3
    assert "256 rings x 10000 beams = 2560000 rays a scan, more than the limit of 262144" in err.message
    assert "fix: " in str(err) and "rings x beams" in err.hint
    err = load_text(tmp_path, base % 300 + robot % (128, 2048))      # 3001 scans of 1 MB: 3.1 GB
    assert err.field == "robot.lidar3d" and err.line == 3
    assert "3001 scans of 128 x 2048 ranges (float32) would record 2.9 GiB, more than the limit of 1 GiB" \
        in err.message
    assert "mission.timeout" in err.hint and "control_rate" in err.hint
    assert load_scenario(_write(tmp_path, base % 30 + robot % (128, 2048))).robot.lidar3d.beams == 2048
    assert load_scenario(_write(tmp_path, base % 4600 + robot % (16, 360))).robot.lidar3d.rings == 16


def _write(folder, text: str):
    path = folder / "fine.yaml"
    path.write_text(text)
    return path
