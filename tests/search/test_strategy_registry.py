"""Search strategies are named in one registry (search/strategies/__init__.py): the engine, the
plugin's option and its help read it, and docs/contributing.md's worked example -- one new module
plus one registry line -- runs as written."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from pytest_navscenario.search import strategies
from pytest_navscenario.search.engine import STRATEGIES, run_search
from pytest_navscenario.search.space import SearchSpace
from pytest_navscenario.search.strategies import Registered, Strategy

from straight_planner import Straight
from test_search import SEED_YAML

PAGE = Path(__file__).resolve().parents[2] / "docs" / "contributing.md"


def _section() -> str:
    text = PAGE.read_text()
    start = text.index("## Adding a search strategy")
    return text[start:text.index("\n## ", start + 1)]          # to the next section, whichever it is


def _blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", _section(), re.S)


@pytest.fixture
def corners(tmp_path, monkeypatch):
    """The page's module written as the package ``mystrategies`` and registered under a dotted path,
    as the page says a strategy outside the package is."""
    module, line = _blocks()
    assert "class Corners(BaseStrategy)" in module and line.strip().startswith('"corners": Registered(')
    (tmp_path / "mystrategies").mkdir()
    (tmp_path / "mystrategies" / "__init__.py").write_text("")
    (tmp_path / "mystrategies" / "corners.py").write_text(module)
    monkeypatch.syspath_prepend(str(tmp_path))
    entry = eval("{" + line.strip() + "}", {"Registered": Registered})["corners"]   # the page's line ...
    monkeypatch.setitem(strategies.STRATEGIES, "corners",                 # ... pointed at mystrategies
                        entry._replace(target="mystrategies." + entry.target))
    return tmp_path


def test_every_strategy_is_named_in_the_registry_and_follows_the_protocol():
    from pytest_navscenario.plugin import search_options

    assert STRATEGIES == strategies.names() == search_options.STRATEGY_NAMES == ("evolve", "random", "hillclimb")
    for name in strategies.names():
        cls = strategies.strategy_class(name)
        assert cls.__module__ == f"pytest_navscenario.search.strategies.{strategies.STRATEGIES[name].target.split(':')[0]}"
        for attr in ("ask", "tell", "confirmed", "lag"):
            assert hasattr(cls, attr), (name, attr)
    with pytest.raises(ValueError, match="unknown search strategy 'nope'; use one of evolve, random, hillclimb"):
        strategies.strategy_class("nope")


def test_the_contributing_pages_strategy_runs_as_written(corners):
    from pytest_navscenario.scenario.loader import loads_scenario

    seed = loads_scenario(SEED_YAML, "crate.yaml", name="crate")
    space = SearchSpace(seed)
    report = run_search(seed, Straight, budget=12, seed_value=1, strategy="corners", shrink_budget=0)
    assert isinstance(strategies.make_strategy("corners", space, report, 12, 0), Strategy)
    assert report.sims_used == 12 and report.strategy == "corners"
    search = [c for c in report.candidates if c.phase == "search"]
    params = [(p.lo, p.hi) for p in space.params]
    assert all(c.origin == "corner" for c in search)
    assert all(v in bounds for c in search for v, bounds in zip(c.offsets, params))


def test_a_registered_strategy_is_a_choice_of_the_plugin(corners, pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(straight_planner=(Path(__file__).parent / "straight_planner.py").read_text())
    pytester.syspathinsert()
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "crate.yaml").write_text(SEED_YAML.replace("name: crate\n", ""))
    pytester.makeini("[pytest]\nnav_scenario_paths = scenarios\n")
    result = pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "--nav-subject=straight_planner:Straight",
                                          "--navsearch", "crate", "--budget", "8", "--navsearch-strategy", "corners",
                                          "--navsearch-shrink-budget", "0")
    assert result.ret == 0, result.stdout.str()
    result.stdout.fnmatch_lines(["*crate vs straight_planner:Straight*(corners, search seed 0): 8/8 sims*"])
    bad = pytester.runpytest_inprocess("-p", "pytest_navscenario.plugin", "--navsearch", "crate",
                                       "--navsearch-strategy", "nope")
    assert bad.ret != 0
    bad.stderr.fnmatch_lines(["*unknown strategy 'nope'; use one of evolve, random, hillclimb, corners*"])
