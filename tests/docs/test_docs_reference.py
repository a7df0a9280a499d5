"""The generated references of the docs site (docs/hooks/reference.py) cover everything the tool
accepts: every pytest option and ini setting the plugin registers in a real pytest session, and every
``navscenario`` subcommand and argument. A new option without docs fails here, without building the site."""
from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def reference():
    spec = importlib.util.spec_from_file_location("docs_reference_hook", ROOT / "docs" / "hooks" / "reference.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module          # dataclasses look their module up while it loads
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop(spec.name, None)


def _registered(config: pytest.Config) -> tuple[dict[str, dict], dict[str, tuple]]:
    """Option string -> attrs, and ini name -> (help, type, default), as pytest holds them."""
    parser = config._parser
    options = {}
    for group in [parser._anonymous, *parser._groups]:
        for option in group.options:
            for name in option.names():
                options[name] = option.attrs()
    return options, dict(parser._inidict)


@pytest.fixture(scope="module")
def plugin_registers(tmp_path_factory):
    """What loading the plugin adds to a real pytest session: options and ini names."""
    mp = pytest.MonkeyPatch()
    mp.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    mp.chdir(tmp_path_factory.mktemp("empty"))
    try:
        from _pytest.config import _prepareconfig
        base = _prepareconfig([])
        with_plugin = _prepareconfig(["-p", "pytest_navscenario.plugin"])
        (base_opts, base_inis), (opts, inis) = _registered(base), _registered(with_plugin)
        base._ensure_unconfigure()
        with_plugin._ensure_unconfigure()
    finally:
        mp.undo()
    added = {name: attrs for name, attrs in opts.items() if name not in base_opts}
    added_inis = {name: value for name, value in inis.items() if name not in base_inis}
    assert "--nav-subject" in added and "nav_subject" in added_inis   # the diff found the plugin
    return added, added_inis


def test_every_registered_pytest_option_is_in_the_generated_reference(reference, plugin_registers):
    options, inis = plugin_registers
    text = reference.pytest_options_markdown()
    missing = [name for name in options if f"`{name}" not in text and f", {name}" not in text]
    assert not missing, f"options missing from the generated option reference: {missing}"
    missing_inis = [name for name in inis if f"{{ #{name} }}" not in text and f"ini: `{name}`" not in text]
    assert not missing_inis, f"ini settings missing from the generated option reference: {missing_inis}"


def test_every_registered_option_has_help_and_an_ini_twin(plugin_registers):
    options, inis = plugin_registers
    for name, attrs in options.items():
        assert (attrs.get("help") or "").strip(), f"{name} has no help text"
        assert attrs["dest"] in inis, f"{name} has no ini twin named {attrs['dest']!r}"
    for name, (help_text, _, _) in inis.items():
        assert help_text.strip(), f"ini {name} has no help text"


def test_option_reference_shows_defaults_and_escapes_markdown(reference):
    text = reference.pytest_options_markdown()
    assert "### `--nav-subject=SPEC` { #nav_subject }" in text
    assert "### `--nav-bag={failed,all,none}` { #nav_bag }" in text
    block = text.split("{ #nav_bag_format }", 1)[1].split("###", 1)[0]
    assert "mcap (rosbag2 + MCAP, default" in block and "ini: `nav_bag_format`" in block
    assert "default: `" not in block                 # the help says it; not said twice
    block = text.split("{ #navsearch }", 1)[1].split("###", 1)[0]
    assert "repeatable" in block
    assert "{ #nav_scenario_glob }" in text.split("## Ini-only settings", 1)[1]
    assert "[ini:" not in text                       # the --help suffix is not repeated
    assert "<" not in text                           # help text cannot open an HTML tag
    assert reference.escape("a <b> *c* [d] |e_f") == r"a &lt;b&gt; \*c\* \[d\] \|e\_f"


def _cli_arguments(parser: argparse.ArgumentParser, prefix: str = "navscenario"):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield prefix, name
                yield from _cli_arguments(sub, f"{prefix} {name}")
        elif not isinstance(action, argparse._HelpAction):
            positional = action.metavar or (
                "{" + ",".join(map(str, action.choices)) + "}" if action.choices else action.dest)
            for option in action.option_strings or [positional]:   # as --help writes a positional
                yield prefix, option


def test_every_cli_subcommand_and_argument_is_in_the_generated_reference(reference):
    from pytest_navscenario.cli.main import SUBCOMMANDS, build_parser
    text = reference.cli_markdown()
    sections = {}
    for chunk in ("\n" + text).split("\n#")[1:]:
        title = chunk.split("`", 2)[1]
        sections[title] = chunk
    for name in SUBCOMMANDS:
        assert f"navscenario {name}" in sections, f"no section for navscenario {name}"
    for prog, argument in _cli_arguments(build_parser()):
        section = sections[prog]
        assert argument in section, f"{prog}: {argument} missing from the CLI reference"


def test_pages_ask_for_the_generated_parts_and_unknown_markers_fail(reference):
    assert "<!-- generated: pytest-options -->" in (ROOT / "docs/reference/options.md").read_text()
    assert "<!-- generated: cli -->" in (ROOT / "docs/reference/cli.md").read_text()
    expanded = reference.expand("intro\n<!-- generated: cli -->\n")
    assert expanded.startswith("intro\n## `navscenario`")
    with pytest.raises(ValueError, match="unknown generated part 'clli'"):
        reference.expand("<!-- generated: clli -->", "x.md")


def test_readme_links_point_at_files_that_exist():
    """The README is read on GitHub: its relative links must reach real files (the docs pages)."""
    import re
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", readme)
    relative = [t for t in targets if "://" not in t]
    assert any(t.startswith("docs/") for t in relative)
    missing = [t for t in relative if not (ROOT / t).exists()]
    assert not missing, f"README links to missing files: {missing}"


def test_tutorial_planner_is_a_working_planner(tmp_path, monkeypatch):
    """The tutorial's `mynav.py` passes check_planner and behaves as the page says on boxes1/boxes2."""
    from pytest_navscenario import Outcome, check_planner, load_scenario, run_scenario
    page = (ROOT / "docs" / "tutorial" / "own-planner.md").read_text(encoding="utf-8")
    code = page.split('```python title="mynav.py"\n', 1)[1].split("```", 1)[0]
    (tmp_path / "mynav_tutorial.py").write_text(code)
    monkeypatch.syspath_prepend(str(tmp_path))
    check = check_planner("mynav_tutorial:StopAndGo")
    assert check.ok, str(check)
    from mynav_tutorial import StopAndGo
    assert run_scenario(load_scenario(ROOT / "scenarios/boxes1.yaml"), StopAndGo).outcome is Outcome.SUCCESS
    assert run_scenario(load_scenario(ROOT / "scenarios/boxes2.yaml"), StopAndGo).outcome is Outcome.SAFETY_STOP


def test_python_api_page_names_every_public_name():
    """Every name the package exports is on the Python API page (a new export without docs fails)."""
    import pytest_navscenario
    page = (ROOT / "docs" / "reference" / "python-api.md").read_text(encoding="utf-8")
    missing = [name for name in pytest_navscenario.__all__ if name != "__version__" and name not in page]
    assert not missing, f"public names missing from docs/reference/python-api.md: {missing}"


def _blocks(text: str) -> dict[str, str]:
    """Option reference: anchor (dest or ini name) -> its block of text."""
    import re
    return {m.group(1): m.group(2) for m in re.finditer(r"\{ #([a-z_]+) \}\n(.*?)(?=\n###|\n## |\Z)", text, re.S)}


def test_option_defaults_are_rendered_as_the_help_says(reference):
    """Issue 23 item 8: no `default: True` for a yes/no choice, no `default: not set` where the help
    says `default 100`: an option whose help states its default gets no second, machine-made one."""
    text = reference.pytest_options_markdown()
    assert "`True`" not in text and "`False`" not in text and "`1.0`" not in text
    blocks = _blocks(text)
    for name in ("nav_summary", "navsearch_budget", "navsearch_seed", "navsearch_strategy",
                 "navsearch_shrink_budget", "navsearch_stuck_after", "navsearch_out", "nav_tick_limit",
                 "nav_plots_max", "nav_scenario_glob"):
        assert "default" in blocks[name].lower(), name                     # the help says it ...
        assert "default: `" not in blocks[name], (name, blocks[name])      # ... and nothing contradicts it
    assert "default: `not set`" in blocks["nav_results"]                 # says nothing: the real default
    assert reference._value_text(True, ("yes", "no")) == "yes" and reference._value_text(False) == "false"


def _stated_number(help_text: str) -> float | None:
    """The number a help text gives as its default ("default 20", "Default 1;", "(default: 10)")."""
    import re
    m = re.search(r"\bdefault:?\s+(-?\d+(?:\.\d+)?)\b(?![%\w])", help_text, re.I)
    return float(m.group(1)) if m else None


def test_defaults_stated_in_help_texts_are_the_real_defaults(plugin_registers):
    """A number a help text states as the default is the value the code uses (pytest options: the
    ini default when it has one; every navscenario argument: argparse's default)."""
    from pytest_navscenario.cli.main import build_parser
    _, inis = plugin_registers
    checked = 0
    for name, (help_text, _, default) in inis.items():
        number = _stated_number(help_text)
        if number is not None and default not in ("", None):
            assert float(default) == number, (name, help_text, default)
            checked += 1
    for prog, action in _cli_actions(build_parser()):
        number = _stated_number(action.help or "")
        if number is not None:
            assert action.default == number, (prog, action.option_strings, action.help, action.default)
            checked += 1
    assert checked >= 8


def _cli_actions(parser: argparse.ArgumentParser, prefix: str = "navscenario"):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _cli_actions(sub, f"{prefix} {name}")
        elif not isinstance(action, argparse._HelpAction):
            yield prefix, action


def test_cli_reference_writes_each_argument_as_its_help_does(reference):
    text = reference.cli_markdown()
    assert "| `--frame {auto,map,odom}` |" in text and "FRAME {auto" not in text
    assert "| `--subject SPEC, -s SPEC` |" in text
    assert "| `SCENARIO.yaml` |" in text
    assert "`10.0`" not in text and "`1.0`" not in text          # 10 and 1, as the help says them


def test_the_tick_limit_defaults_and_their_reasons_are_stated():
    """pytest and navscenario run share one default (run gives an item's outcome); check-planner's
    longer one says why; the docs table gives all of them."""
    from pytest_navscenario.cli.main import build_parser
    from pytest_navscenario.harness.conformance import HUNG_TICK
    from pytest_navscenario.plugin.options import OPTIONS
    from pytest_navscenario.sim.deadline import DEFAULT_TICK_LIMIT

    subs = {name: sub for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)
            for name, sub in a.choices.items()}
    limit = {name: next(a for a in subs[name]._actions if "--tick-limit" in a.option_strings)
             for name in ("run", "check-planner")}
    assert limit["run"].default == DEFAULT_TICK_LIMIT and "pytest" in limit["run"].help
    assert limit["check-planner"].default == HUNG_TICK and "pytest" in limit["check-planner"].help
    assert "check-planner" in dict((o, h) for o, _, h in OPTIONS)["--nav-tick-limit"]
    page = (ROOT / "docs/reference/planner-protocol.md").read_text()
    assert "**How long one tick may take**, and why the defaults differ" in page


def test_the_scenario_format_page_lists_every_declared_key(reference):
    """Issue 28: the reference page's key tables are generated from the declarations the loader and
    the JSON Schema read; every section and key appears, with its range and default."""
    from pytest_navscenario.scenario.format import SCENARIO
    from pytest_navscenario.scenario.keys import walk
    from pytest_navscenario.scenario.search_keys import SEARCH
    page = (ROOT / "docs" / "reference" / "scenario-format.md").read_text(encoding="utf-8")
    assert "<!-- generated: scenario-keys -->" in page and "<!-- generated: scenario-run-only -->" in page
    assert "<!-- generated: search-keys -->" in (ROOT / "docs" / "reference" / "search.md").read_text(encoding="utf-8")
    text = reference.scenario_keys_markdown()
    for path, section in walk(SCENARIO):
        if path.startswith("search"):
            continue
        for key in section.keys:
            assert f"| `{key.name}` |" in text, f"{path}.{key.name}"
    assert "| `beams` | whole number: 1 … 10000 |  | 72 |" in text
    search = reference.search_keys_markdown()
    assert all(f"| `{key.name}` |" in search for key in SEARCH.keys)
    assert "± 1000" in search or "±1000" in search
    assert "edges do not cross" in reference.run_only_markdown()
