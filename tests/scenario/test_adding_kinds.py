"""Adding a terrain element or a kind of body is one module and one registry line: the worked
examples of docs/contributing.md ("Adding a kind of body or a terrain element"), added to a copy
of the package exactly as the page shows, load, build and run."""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "contributing.md"
MARK = re.compile(r"<!-- example: (module|registry) (\S+)(?: (\w+))? -->\s*```python\n(.*?)```", re.S)


def _examples() -> list[tuple[str, str, str | None, str]]:
    return [(m[1], m[2], m[3], m[4]) for m in MARK.finditer(PAGE.read_text(encoding="utf-8"))]


def _apply(copy: Path) -> None:
    """Write each example module and add each registry line at the end of its registry."""
    for what, path, registry, code in _examples():
        target = copy / path
        if what == "module":
            assert not target.exists(), f"{path} exists already: the example must be a new module"
            target.write_text(code, encoding="utf-8")
            continue
        text = target.read_text(encoding="utf-8")
        start = re.search(rf"^{registry}\b[^\n]*= [({{]\n", text, re.M)
        assert start, f"no registry {registry} in {path}"
        end = text.index("\n)" if text[start.end() - 2] == "(" else "\n}", start.end())
        assert code.count("\n") == 1, "a registry addition is one line"
        target.write_text(text[:end + 1] + code + text[end + 1:], encoding="utf-8")


def test_the_page_shows_a_module_and_one_registry_line_for_each_kind():
    kinds = [(what, path) for what, path, _, _ in _examples()]
    assert ("module", "pytest_navscenario/scenario/terrain/kerb.py") in kinds
    assert ("module", "pytest_navscenario/scenario/bodies/crawler.py") in kinds
    assert [what for what, _ in kinds].count("registry") == 3


SCRIPT = textwrap.dedent('''
    import json
    from pytest_navscenario.scenario.loader import loads_scenario
    from pytest_navscenario.scenario.json_schema import scenario_schema
    from pytest_navscenario.scenario.ground.surface import ground_height
    from pytest_navscenario.sim import simulate

    class Straight:
        def reset(self, scenario): pass
        def act(self, obs): return (0.5, 0.0, 0.0)

    def scene(kerb, body):
        return loads_scenario(f"""
    version: 1
    robot: {{footprint: {{shape: box, length: 0.6, width: 0.4}}, drive: diff, body: {body},
            safety: {{enabled: false}}}}
    mission: {{start: {{x: 0.0, y: 0.0, yaw: 0.0}}, goal: {{x: 5.0, y: 0.0}}, timeout: 20.0}}
    terrain: [{{type: kerb, x: 2.5, y: 0.0, length: 0.3, width: 3.0, height: {kerb}}}]
    """)

    low = scene(0.03, "{type: crawler}")
    out = {"height": float(ground_height(low, [2.5], [0.0])[0]),
           "name": low.terrain[0].name,
           "schema": "kerb" in json.dumps(scenario_schema()) and "crawler" in json.dumps(scenario_schema()),
           "low": simulate(low, Straight(), 0).end,
           "high": simulate(scene(0.12, "{type: crawler}"), Straight(), 0).end,
           "wheeled": simulate(scene(0.03, "{type: wheeled}"), Straight(), 0).end}
    print(json.dumps(out))
''')


def test_the_worked_examples_load_build_and_run(tmp_path):
    copy = tmp_path / "checkout"
    shutil.copytree(ROOT / "pytest_navscenario", copy / "pytest_navscenario",
                    ignore=shutil.ignore_patterns("__pycache__"))
    _apply(copy)
    run = subprocess.run([sys.executable, "-c", SCRIPT], cwd=tmp_path, capture_output=True, text=True,
                         env={"PYTHONPATH": str(copy), "PATH": "/usr/bin:/bin"}, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    import json
    out = json.loads(run.stdout.strip().splitlines()[-1])
    assert out["height"] == pytest.approx(0.03)
    assert out["name"] == "kerb1"
    assert out["schema"]
    assert out["low"] == "goal"          # 3 cm: within the crawler's 5 cm
    assert out["high"] != "goal"         # 12 cm: a step it cannot climb
    assert out["wheeled"] == "goal"      # the new element is ground for the built-in bodies too


def test_the_wheeled_bodys_slope_has_one_home():
    """The safety layer's slope limit and the crossing estimates read the same grip formula
    (scenario/bodies/wheeled.py ``climbs``), so changing the body changes both alike."""
    from pytest_navscenario.scenario.bodies import WheeledBody, body_kind, climb_limit
    from pytest_navscenario.scenario.bodies.wheeled import WHEELED_TORQUE_SLOPE
    from pytest_navscenario.scenario.model import Footprint

    heavy = WheeledBody(mass=120.0)                 # 2 x 10 N m on 0.1 m wheels: asin(0.17) = 9.8 deg
    kind = body_kind(heavy)
    assert kind.climbs(heavy) == pytest.approx(9.78, abs=0.01)
    assert climb_limit(heavy) == kind.climbs(heavy)
    assert kind.capability(heavy, Footprint()).max_slope == pytest.approx(WHEELED_TORQUE_SLOPE * kind.climbs(heavy))
    assert climb_limit(WheeledBody(max_wheel_torque=100.0, tip_angle=30.0)) == 30.0   # the tip angle caps it
