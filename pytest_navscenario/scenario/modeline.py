"""The first line of every scenario file the tool writes: the YAML language server's modeline,
naming the scenario schema so that an editor completes keys, shows their documentation and marks
mistakes as they are typed (a comment: no scenario's meaning or content hash changes).

The schema is not published at a URL, so the modeline names a file the project has:
``.navscenario/scenario-v1.json`` at the project's root (the nearest folder above the scenario that
holds pyproject.toml, setup.cfg, setup.py, tox.ini, pytest.ini, .git or .navscenario; else the
scenario's own folder), written relative to the scenario file, as the language server resolves it.
``navscenario schema -o .navscenario/scenario-v1.json`` writes that file once per project; the
search and the importers write it too when they write scenarios into a project that lacks it (or
has an older one), and beside the scenario in a folder with no project marker (the file its
modeline names there), so their files work in an editor without setup. (``save_scenario``, the
library's own writer, writes no schema.)
"""
from __future__ import annotations

import functools
import os
from pathlib import Path

PREFIX = "# yaml-language-server: $schema="
PROJECT_MARKERS = ("pyproject.toml", "setup.cfg", "setup.py", "tox.ini", "pytest.ini", ".git", ".navscenario")
_ENSURED: set[Path] = set()       # project schemas written (or found current) by this process


def schema_file_name() -> str:
    from .model import SCHEMA_VERSION
    return f"scenario-v{SCHEMA_VERSION}.json"


def project_root(scenario_path: str | os.PathLike) -> Path | None:
    """The nearest folder at or above the scenario's folder that holds a project marker, or None."""
    return _root_of(os.path.dirname(os.path.abspath(scenario_path)))


@functools.lru_cache(maxsize=256)
def _root_of(folder: str) -> Path | None:
    """(cached per folder: a generated suite writes hundreds of files into one folder)"""
    path = Path(folder)
    for candidate in (path, *path.parents):
        if any((candidate / marker).exists() for marker in PROJECT_MARKERS):
            return candidate
    return None


def project_schema(scenario_path: str | os.PathLike) -> Path:
    """Where the schema of the project holding ``scenario_path`` lives."""
    root = project_root(scenario_path) or Path(os.path.abspath(scenario_path)).parent
    return root / ".navscenario" / schema_file_name()


def modeline(scenario_path: str | os.PathLike) -> str:
    """The modeline for a scenario written at ``scenario_path`` (one line, no newline)."""
    folder = Path(os.path.abspath(scenario_path)).parent
    relative = os.path.relpath(project_schema(scenario_path), folder)
    return PREFIX + Path(relative).as_posix()


def with_modeline(text: str, scenario_path: str | os.PathLike) -> str:
    """``text`` (scenario YAML) with the modeline as its first line (replacing an old one)."""
    if text.startswith(PREFIX):
        text = text.split("\n", 1)[1] if "\n" in text else ""
    return modeline(scenario_path) + "\n" + text


def ensure_project_schema(scenario_path: str | os.PathLike) -> Path:
    """Write the schema the modeline of ``scenario_path`` names when the file is missing or not
    this version's: at the project's root (see ``project_root``), or, in a folder with no project
    marker, beside the scenario (issue 32: an import there wrote a modeline naming a file that did
    not exist). Returns the schema's path."""
    target = project_schema(scenario_path)
    if target in _ENSURED:
        return target
    from ..core.files import atomic_write_text
    from .json_schema import schema_text

    text = schema_text()
    try:
        current = target.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        current = None
    if current != text:
        target.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(target, text)
    _ENSURED.add(target)
    return target
