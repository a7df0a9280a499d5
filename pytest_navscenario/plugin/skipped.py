"""YAML files beside scenarios that are not scenarios (issue 15): empty, binary or not a mapping.

Such a file matches the scenario glob but is skipped by collection; when it sits in a folder that
holds scenarios it is most likely a broken or unfinished scenario, so the terminal summary counts
them ("3 YAML files beside scenarios are not scenarios ..."), and ``-v`` lists each with why.
A YAML mapping without scenario keys (another tool's config) is not reported. Under xdist the
workers collect: each sends its list to the controller in ``workeroutput``.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

PARSE_LIMIT = 256 * 1024   # bytes: larger non-scenario files are another tool's data, not parsed
WORKER_KEY = "navscenario_not_scenarios"


def why_not_a_scenario(data: bytes) -> str | None:
    """Why a YAML file that does not look like a scenario is suspicious, or None if it is some
    other YAML document (a mapping, or too large to be a scenario)."""
    from ..scenario.loader import text_codec
    try:
        text = data.decode(text_codec(data))
    except UnicodeDecodeError:
        return "not text (binary?)"
    if "\x00" in text:
        return "not text (binary?)"
    if len(data) > PARSE_LIMIT:
        return None
    import yaml
    try:
        docs = [d for d in yaml.safe_load_all(text)]
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        return f"not valid YAML{where}: {getattr(exc, 'problem', None) or exc}"
    except Exception:       # constructor limits, recursion: not a scenario either way
        return None
    docs = [d for d in docs if d is not None]
    if not docs:
        return "empty (no YAML document)"
    root = docs[0]
    if isinstance(root, dict):
        return None
    return f"the top level is {_describe(root)}, not a mapping"


def _describe(value: Any) -> str:
    if isinstance(value, list):
        return "a list"
    kind = {bool: "a boolean", int: "an integer", float: "a number", str: "a string"}.get(type(value))
    shown = repr(value) if len(repr(value)) <= 40 else repr(value)[:37] + "..."
    return f"{shown} ({kind})" if kind else f"a {type(value).__name__} value"


def add_skipped(state: Any, path: Path, reason: str) -> None:
    state.not_scenarios.append((str(path), reason))


def beside_scenarios(state: Any) -> list[tuple[str, str]]:
    """The skipped files in a folder that also holds a collected scenario file, sorted."""
    folders = set(state.scenario_folders)
    return sorted((p, r) for p, r in set(state.not_scenarios) if str(Path(p).parent) in folders)


def summary_lines(state: Any, rel: Any, verbose: bool) -> list[str]:
    found = beside_scenarios(state)
    if not found:
        return []
    n = len(found)
    lines = [f"navscenario: {n} YAML file{'s' if n != 1 else ''} beside scenarios "
             f"{'are not scenarios' if n != 1 else 'is not a scenario'} (empty, binary or not a mapping)"
             + ("" if verbose else "; -v lists them")]
    if verbose:
        lines += [f"  {rel(Path(p))}: {r}" for p, r in found]
    return lines
