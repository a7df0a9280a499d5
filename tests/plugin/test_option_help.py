"""``pytest --help`` as a user reads it: every pytest-navscenario option has help text, a metavar
showing its accepted values or a unit, and an ini twin; ``navsearch_out`` is the ini twin of
``--navsearch-out``, its old name ``nav_regressions_dir`` still works."""
from __future__ import annotations

import re

import pytest

UNITS = {"N", "SECONDS", "PATH", "DIR", "SPEC", "NAME", "ADDRESS", "SHARE", "P"}   # ADDRESS: auto or HOST:PORT (--nav-ray); SHARE: 25% or N (--navsearch-shrink-budget); P: a probability (--navsearch-hold)


@pytest.fixture
def plugin_only(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    return pytester


def _sections(text: str) -> dict[str, list[str]]:
    """--help split into its sections: title line -> the lines under it."""
    sections: dict[str, list[str]] = {}
    current = None
    for line in text.splitlines():
        if line and not line.startswith(" ") and line.rstrip().endswith(":"):
            current = sections.setdefault(line.rstrip(), [])
        elif current is not None:
            current.append(line)
    return sections


def _options(lines: list[str]) -> dict[str, tuple[str | None, str]]:
    """--option -> (metavar or None, its whole help text, unwrapped)."""
    found: dict[str, tuple[str | None, str]] = {}
    name = None
    for line in lines:
        m = re.match(r"^  (--[a-z0-9-]+)(?:=(\S+))?(?:\s+(.*))?$", line)
        if m:
            name = m.group(1)
            found[name] = (m.group(2), m.group(3) or "")
        elif name and line.startswith(" " * 10):
            metavar, text = found[name]
            found[name] = (metavar, f"{text} {line.strip()}".strip())
    return found


def _ini_names(lines: list[str]) -> dict[str, str]:
    """ini name -> help text, from the [pytest] ini section."""
    found: dict[str, str] = {}
    name = None
    for line in lines:
        m = re.match(r"^  ([a-z0-9_]+) \(\w+\):(?:\s+(.*))?$", line)
        if m:
            name = m.group(1)
            found[name] = m.group(2) or ""
        elif name and line.startswith(" " * 10):
            found[name] = f"{found[name]} {line.strip()}".strip()
        else:
            name = None
    return found


def test_every_option_has_help_a_value_metavar_and_an_ini_twin(plugin_only):
    from pytest_navscenario.plugin.bags import FORMATS, MODES
    from pytest_navscenario.plugin.reports import MODE_CHOICES, PLOT_CHOICES
    from pytest_navscenario.search.engine import STRATEGIES

    result = plugin_only.runpytest_inprocess("-p", "pytest_navscenario.plugin", "--help")
    assert result.ret == 0
    sections = _sections(result.stdout.str())
    groups = [title for title in sections if "(pytest-navscenario)" in title]
    assert len(groups) >= 3, list(sections)
    options: dict[str, tuple[str | None, str]] = {}
    for title in groups:
        options.update(_options(sections[title]))
    ini_title = next(t for t in sections if t.startswith("[pytest] ini") or "configuration options" in t)
    ini = _ini_names(sections[ini_title])
    assert len(options) >= 24, sorted(options)

    for opt, (metavar, text) in options.items():
        assert len(text) > 30, f"{opt}: no help text"
        assert metavar, f"{opt}: no metavar"
        bare = opt.lstrip("-").replace("-", "_").upper()
        assert metavar.upper() not in (bare, bare.split("_", 1)[-1]), \
            f"{opt}={metavar}: the bare dest name, not the accepted values or a unit"
        assert metavar in UNITS or re.fullmatch(r"\{[a-z0-9]+(,[a-z0-9]+)+\}", metavar), \
            f"{opt}={metavar}: show the accepted values {{a,b}} or a unit ({', '.join(sorted(UNITS))})"
        twin = re.search(r"\[ini: ([a-z0-9_]+)[;\]]", text)
        assert twin, f"{opt}: help does not name its ini twin"
        assert twin.group(1) in ini and len(ini[twin.group(1)]) > 20, f"{opt}: ini {twin.group(1)} missing"

    # the values shown are the values accepted
    def values(opt):
        return set(options[opt][0].strip("{}").split(","))
    assert values("--navsearch-strategy") == set(STRATEGIES)
    assert values("--nav-bag") == set(MODES) and values("--nav-bag-format") == set(FORMATS)
    assert values("--nav-plots") == set(PLOT_CHOICES) and values("--nav-baseline-mode") == set(MODE_CHOICES)

    # the pair is obvious: --navsearch-out <-> navsearch_out, and the old name is documented
    assert "[ini: navsearch_out]" in options["--navsearch-out"][1]
    assert "old name nav_regressions_dir is still read" in options["--navsearch-out"][1]
    assert "old name of navsearch_out" in ini["nav_regressions_dir"]


SEARCH_INI = "[pytest]\n{lines}\n"


@pytest.mark.parametrize("lines, args, expected", [
    ("navsearch_out = new", [], "new"),
    ("nav_regressions_dir = old", [], "old"),                       # the old name keeps working
    ("navsearch_out = same\nnav_regressions_dir = same", [], "same"),
    ("nav_regressions_dir = old", ["--navsearch-out=cli"], "cli"),  # the command line wins
    ("", [], "scenarios/regressions"),
])
def test_navsearch_out_ini_and_its_old_name(plugin_only, lines, args, expected):
    from pytest_navscenario.plugin.search import read_search_settings

    plugin_only.makeini(SEARCH_INI.format(lines=lines))
    config = plugin_only.parseconfigure("-p", "pytest_navscenario.plugin", *args)
    assert read_search_settings(config).out == plugin_only.path / expected


def test_navsearch_out_and_its_old_name_disagreeing_is_a_usage_error(plugin_only):
    plugin_only.makeini(SEARCH_INI.format(lines="navsearch_out = new\nnav_regressions_dir = old"))
    result = plugin_only.runpytest_inprocess("-p", "pytest_navscenario.plugin", "--navsearch", "x")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(["*ini options navsearch_out = 'new' and nav_regressions_dir = 'old' "
                                 "disagree; nav_regressions_dir is the old name of navsearch_out: keep only "
                                 "navsearch_out*"])
