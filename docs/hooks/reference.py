"""MkDocs hook: the option and CLI references, generated from the code so they cannot drift.

A page asks for a generated part with a marker line of its own:

    <!-- generated: pytest-options -->   every pytest option and ini setting the plugin registers
    <!-- generated: cli -->              every ``navscenario`` subcommand and its arguments
    <!-- generated: scenario-keys -->    every key of the scenario format, section by section
    <!-- generated: search-keys -->      every key of a seed's ``search:`` section
    <!-- generated: scenario-run-only --> the checks across keys that need a run (no schema says them)

The pytest options are read by calling the plugin's own ``pytest_addoption`` hooks (the plugin
module and every feature plugin it lists in ``pytest_plugins``) with a recording parser, so what
is documented is exactly what the plugin registers: flag, metavar, help, ini twin and default.
The CLI is read from the argparse parser that ``navscenario`` itself builds (``build_parser``).
The scenario keys are read from the declarations the loader and the JSON Schema read
(``scenario/keys.py``, ``format.SCENARIO``), and the schema itself is added to the site at
``schema/scenario-v1.json`` (``on_files``). An unknown marker stops the build. ``tests/docs/test_docs_reference.py`` checks that every option a
real pytest session gets from the plugin appears here.
"""
from __future__ import annotations

import argparse
import html
import importlib
import os
import re
from dataclasses import dataclass, field
from typing import Any

PLUGIN = "pytest_navscenario.plugin"
MARKER = re.compile(r"^<!-- generated: ([a-z-]+) -->$", re.MULTILINE)
_INI_SUFFIX = re.compile(r"\s*\[ini: [^\]]*\]\s*$")
_NOTSET = object()


# -- reading the pytest options -----------------------------------------------------------------
@dataclass
class Option:
    names: tuple[str, ...]
    attrs: dict[str, Any]

    @property
    def dest(self) -> str:
        return self.attrs.get("dest") or self.names[-1].lstrip("-").replace("-", "_")


@dataclass
class Group:
    name: str
    description: str
    options: list[Option] = field(default_factory=list)

    def addoption(self, *names: str, **attrs: Any) -> None:
        self.options.append(Option(names, attrs))

    _addoption = addoption


@dataclass
class Ini:
    name: str
    help: str
    type: str | None
    default: Any


class RecordingParser:
    """Stands in for pytest's Parser: records what ``pytest_addoption`` registers."""

    def __init__(self) -> None:
        self.groups: dict[str, Group] = {}
        self.inis: dict[str, Ini] = {}

    def getgroup(self, name: str, description: str = "", after: str | None = None) -> Group:
        group = self.groups.setdefault(name, Group(name, description))
        group.description = group.description or description
        return group

    def addoption(self, *names: str, **attrs: Any) -> None:
        self.getgroup("general", "general").addoption(*names, **attrs)

    def addini(self, name: str, help: str, type: str | None = None, default: Any = _NOTSET,
               **_: Any) -> None:
        self.inis[name] = Ini(name, help, type, default)


def plugin_modules() -> list[Any]:
    """The plugin module and the feature plugins it registers through ``pytest_plugins``."""
    seen: list[Any] = []
    todo = [PLUGIN]
    while todo:
        module = importlib.import_module(todo.pop(0))
        if module in seen:
            continue
        seen.append(module)
        todo.extend(getattr(module, "pytest_plugins", []))
    return seen


def record_options() -> RecordingParser:
    parser = RecordingParser()
    for module in plugin_modules():
        hook = getattr(module, "pytest_addoption", None)
        if hook is not None:
            hook(parser)
    return parser


# -- rendering ----------------------------------------------------------------------------------
def escape(text: str) -> str:
    """Plain help text as Markdown: no accidental HTML, emphasis, links or table cells."""
    text = html.escape(" ".join(str(text).split()), quote=False)
    return re.sub(r"([\\`*_\[\]|])", r"\\\1", text)


_STATES_DEFAULT = re.compile(r"\bdefault\b", re.IGNORECASE)


def states_default(help_text: str) -> bool:
    """True when the help text says what the default is ("default 100", "yes (default) or no",
    "Default: the built-in 'dwa'"): the page then shows the help's own words, never a second,
    machine-made default next to it that could contradict them."""
    return bool(_STATES_DEFAULT.search(help_text))


def _value_text(value: Any, choices: tuple[str, ...] = ()) -> str:
    """A default written as a user types it: yes/no for a {yes,no} choice (true/false for a
    plain ini boolean), 1 not 1.0, list items separated by spaces."""
    if isinstance(value, bool):
        if {"yes", "no"} <= set(choices):
            return "yes" if value else "no"
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, (list, tuple)):
        return " ".join(str(v) for v in value)
    return str(value)


def _ini_default(ini: Ini, choices: tuple[str, ...] = ()) -> str:
    default = ini.default
    if default is _NOTSET or default in ("", None, []):
        return "not set"
    return _value_text(default, choices)


def _metavar_choices(metavar: str | None) -> tuple[str, ...]:
    """The accepted values of a metavar written as {a,b,c}."""
    if metavar and metavar.startswith("{") and metavar.endswith("}"):
        return tuple(metavar[1:-1].split(","))
    return ()


def _option_block(option: Option, inis: dict[str, Ini]) -> list[str]:
    flags = ", ".join(option.names)
    metavar = option.attrs.get("metavar")
    title = f"{flags}={metavar}" if metavar else flags
    ini = inis.get(option.dest)
    help_text = _INI_SUFFIX.sub("", (option.attrs.get("help") or "").replace("%%", "%"))   # argparse's escape
    facts = [f"ini: `{ini.name}`" if ini else "no ini twin"]
    if ini is not None and not states_default(help_text):
        facts.append(f"default: `{_ini_default(ini, _metavar_choices(metavar))}`")
    if option.attrs.get("action") == "append":
        facts.append("repeatable")
    return [f"### `{title}` {{ #{option.dest} }}", "", escape(help_text), "",
            " · ".join(facts), ""]


def pytest_options_markdown() -> str:
    parser = record_options()
    lines: list[str] = []
    dests = set()
    for group in parser.groups.values():
        title = group.description or group.name
        lines += [f"## {escape(title[:1].upper() + title[1:])}", ""]
        for option in group.options:
            dests.add(option.dest)
            lines += _option_block(option, parser.inis)
    ini_only = [ini for name, ini in parser.inis.items() if name not in dests]
    if ini_only:
        lines += ["## Ini-only settings", "",
                  "Set in `pytest.ini`, `pyproject.toml` (`[tool.pytest.ini_options]`), `tox.ini` "
                  "or `setup.cfg`; there is no command-line flag (`-o NAME=VALUE` works as for any "
                  "ini setting).", ""]
        for ini in ini_only:
            facts = [] if states_default(ini.help) else [f"default: `{_ini_default(ini)}`"]
            if ini.type:
                facts.append(f"type: {ini.type}")
            lines += [f"### `{ini.name}` {{ #{ini.name} }}", "", escape(ini.help), ""]
            lines += [" · ".join(facts), ""] if facts else []
    return "\n".join(lines)


def _usage(parser: argparse.ArgumentParser) -> str:
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "80"             # argparse wraps at the terminal width: fix it
    try:
        return parser.format_usage().strip()
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


def _invocation(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """An argument as the command's own --help writes it: ``--frame {auto,map,odom}``,
    ``-s SPEC, --subject SPEC``, ``SCENARIO.yaml``."""
    return parser._get_formatter()._format_action_invocation(action)


def _argument_row(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    name = _invocation(parser, action)
    formatter = parser._get_formatter()
    try:
        help_text = formatter._expand_help(action) if action.help else ""
    except (KeyError, TypeError, ValueError):
        help_text = action.help or ""
    default = action.default
    shown = ("" if default in (None, False, argparse.SUPPRESS, "") or action.nargs == 0
             else f"`{_value_text(default, tuple(str(c) for c in action.choices or ()))}`")
    return f"| `{name}` | {escape(help_text)} | {shown} |"


def _parser_section(parser: argparse.ArgumentParser, level: int) -> list[str]:
    lines = [f"{'#' * level} `{parser.prog}` {{ #{parser.prog.replace(' ', '-')} }}", ""]
    if parser.description:
        lines += [escape(parser.description), ""]
    lines += ["```text", _usage(parser), "```", ""]
    rows = [a for a in parser._actions
            if a.help != argparse.SUPPRESS and not isinstance(a, (argparse._HelpAction,
                                                                   argparse._SubParsersAction))]
    if rows:
        lines += ["| argument | meaning | default |", "|---|---|---|"]
        lines += [_argument_row(parser, a) for a in rows]
        lines.append("")
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {c.dest: c.help for c in action._choices_actions}
            lines += ["| subcommand | purpose |", "|---|---|"]
            lines += [f"| [`{name}`](#{sub.prog.replace(' ', '-')}) | {escape(helps.get(name) or '')} |"
                      for name, sub in action.choices.items()]
            lines.append("")
            for sub in action.choices.values():
                lines += _parser_section(sub, level + 1)
    return lines


def cli_markdown() -> str:
    from pytest_navscenario.cli.main import build_parser
    return "\n".join(_parser_section(build_parser(), 2))


# -- the scenario format ------------------------------------------------------------------------
_KIND_WORDS = {"number": "number", "integer": "whole number", "text": "text", "flag": "true / false",
               "choice": "one of", "version": "whole number", "sub": "mapping", "listed": "list of mappings",
               "point": "[x, y]", "points": "list of [x, y]", "rows": "list of rows", "scale": "number or [sx, sy, sz]",
               "free": "free-form mapping", "marks": "list of marks", "elements": "list of typed mappings",
               "variant": "mapping with a type", "range": "number or [lo, hi]", "size_range": "number or [lo, hi]",
               "names": "list of names"}


def _anchor(title: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-") or "top-level"


def _key_rows(section: Any) -> list[str]:
    from pytest_navscenario.scenario.json_schema import describe_default, describe_range
    rows = ["| key | type and range | unit | default | meaning |", "|---|---|---|---|---|"]
    for key in section.keys:
        kind = _KIND_WORDS.get(key.kind, key.kind)
        allowed = describe_range(key)
        rows.append(f"| `{key.name}` | {escape(kind + (': ' + allowed if allowed else ''))} | {escape(key.unit)} | "
                    f"{escape(describe_default(key))} | {escape(key.doc)} |")
    return rows


def _sections_markdown(root: Any, skip: tuple[str, ...] = ()) -> str:
    from pytest_navscenario.scenario.keys import walk
    seen: dict[int, list[str]] = {}
    order: list[Any] = []
    for path, section in walk(root):
        if any(path == s or path.startswith(s + ".") for s in skip):
            continue
        where = section.path if "(" in section.path else (path or "top level")
        if id(section) not in seen:
            seen[id(section)] = []
            order.append(section)
        if where not in seen[id(section)]:
            seen[id(section)].append(where)
    lines: list[str] = []
    for section in order:
        if not section.keys:
            continue
        title = ", ".join(seen[id(section)])
        lines += [f"### `{title}` {{ #{_anchor('keys ' + seen[id(section)][0])} }}", "",
                  escape(section.doc[:1].upper() + section.doc[1:]) + ".", ""]
        lines += _key_rows(section) + [""]
    return "\n".join(lines)


def scenario_keys_markdown() -> str:
    from pytest_navscenario.scenario.format import SCENARIO
    return _sections_markdown(SCENARIO, skip=("search",))


def search_keys_markdown() -> str:
    from pytest_navscenario.scenario.search_keys import SEARCH
    return "\n".join(_key_rows(SEARCH))


def run_only_markdown() -> str:
    from pytest_navscenario.scenario.json_schema import run_only_checks
    return "\n".join(f"* `{where}`: {escape(rule)}" for where, rule in run_only_checks())


GENERATORS = {"pytest-options": pytest_options_markdown, "cli": cli_markdown,
              "scenario-keys": scenario_keys_markdown, "search-keys": search_keys_markdown,
              "scenario-run-only": run_only_markdown}


def expand(markdown: str, where: str = "page") -> str:
    def replace(match: re.Match[str]) -> str:
        name = match.group(1)
        if name not in GENERATORS:
            raise ValueError(f"{where}: unknown generated part {name!r} "
                             f"(known: {', '.join(sorted(GENERATORS))})")
        return GENERATORS[name]()
    return MARKER.sub(replace, markdown)


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    """MkDocs event: fill in the generated parts of a page."""
    return expand(markdown, page.file.src_path)


def on_files(files: Any, config: Any) -> Any:
    """MkDocs event: the scenario format's JSON Schema, generated, at a stable path of the site
    (schema/scenario-v1.json), so pages link to it and a published site serves it."""
    from mkdocs.structure.files import File
    from pytest_navscenario.scenario.json_schema import SCHEMA_FILE, schema_text
    files.append(File.generated(config, f"schema/{SCHEMA_FILE}", content=schema_text()))
    return files
