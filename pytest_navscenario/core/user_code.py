"""A user's own code named by a spec, ``package.module:Attribute`` (a planner, a body controller,
...): found and imported the same way wherever a user can name one.

Where a module is looked up, in this order:

1. ``sys.path`` as it is: installed packages, ``PYTHONPATH``, a script's folder, the current
   folder under ``python -m``;
2. then the *project folders* the caller gives: pytest gives its rootdir, the ``navscenario``
   command its current folder. A project folder is used only for a module that sys.path does
   not have, and is then appended to the **end** of ``sys.path`` (so the module's own imports of
   its neighbours work, and worker processes started later, which copy sys.path, find it too).

So an installed package always wins over a file of the same name in the project: nothing the
user installed is shadowed by accident. When that happens (the project has ``mynav.py`` but an
installed ``mynav`` is imported), a ``ShadowedModuleWarning`` says which file is used and why.
"""
from __future__ import annotations

import importlib
import importlib.machinery
import importlib.util
import inspect
import os
import site
import sys
import sysconfig
import warnings
from pathlib import Path
from typing import Any, Iterable, Sequence

from .errors import SubjectLoadError


class ShadowedModuleWarning(UserWarning):
    """A project folder holds a module of the same name as one sys.path already has; the one on
    sys.path (e.g. an installed package) is used."""


def spec_module(spec: str) -> str | None:
    """The module part of ``package.module:Attribute`` (None when ``spec`` is not of that form)."""
    module, sep, attr = spec.strip().partition(":")
    if not sep or not module or not attr:
        return None
    return module


def _locations(spec: Any) -> set[Path]:
    """The files and folders a module spec stands for (a module file, a package's folders)."""
    out = set()
    if spec.origin and spec.origin not in ("namespace", "built-in", "frozen") and os.path.exists(spec.origin):
        origin = Path(spec.origin).resolve()
        out.add(origin.parent if origin.name.startswith("__init__.") else origin)
    for folder in spec.submodule_search_locations or ():
        out.add(Path(folder).resolve())
    return out


def _in_folder(top: str, folder: str | os.PathLike) -> Any:
    """The spec of the top-level module ``top`` in ``folder`` alone (None if it is not there)."""
    try:
        return importlib.machinery.PathFinder.find_spec(top, [os.fspath(folder)])
    except (ImportError, ValueError, OSError):
        return None


def look_in_project(module_name: str, folders: Iterable[str | os.PathLike]) -> Path | None:
    """Make ``module_name`` importable from the first of ``folders`` that has it, when sys.path
    does not: that folder is appended to sys.path and returned. None when sys.path already has
    the module (a project folder's module of the same name then gets a ShadowedModuleWarning,
    unless it was imported before) or no folder has it. Imports nothing but the module's parent packages when they are on
    sys.path already (as ``importlib.util.find_spec`` does)."""
    top = module_name.split(".")[0]
    folders = [Path(f) for f in folders if f]
    try:
        found = importlib.util.find_spec(top)
    except (ImportError, ValueError):
        found = None
    if found is not None:
        if top not in sys.modules:   # already imported (by a conftest, say): nothing is chosen here
            _warn_if_shadowed(module_name, found, folders)
        return None
    for folder in folders:
        if _in_folder(top, folder) is not None:
            entry = os.fspath(folder)
            if entry not in sys.path:
                sys.path.append(entry)
                importlib.invalidate_caches()
            return folder
    return None


def _warn_if_shadowed(module_name: str, found: Any, folders: Sequence[Path]) -> None:
    top = module_name.split(".")[0]
    used = _locations(found)
    for folder in folders:
        mine = _in_folder(top, folder)
        if mine is None:
            continue
        theirs = _locations(mine)
        if theirs and not theirs & used:
            where = ", ".join(sorted(str(p) for p in used)) or "sys.path"
            warnings.warn(
                f"module {top!r} is imported from {where}, not from the project's "
                f"{', '.join(sorted(str(p) for p in theirs))}: a module on sys.path (an installed "
                f"package, PYTHONPATH) wins over the project folder; rename the project's module "
                f"or uninstall the other one", ShadowedModuleWarning, stacklevel=3)
        return


def load_object(spec: str, *, what: str = "subject", project: Iterable[str | os.PathLike] = (),
                error: type[Exception] = SubjectLoadError) -> Any:
    """The object ``package.module:Attribute`` names (attributes may be dotted: ``mod:Outer.Inner``),
    the module looked up as the module docstring says (sys.path, then the ``project`` folders).
    Raises ``error`` saying what was looked for, where, and how to fix it; ``what`` names the
    spec in messages (e.g. "subject", "controller")."""
    module_name = spec_module(spec)
    if module_name is None:
        raise error(f"{what} {spec!r} is not of the form 'package.module:Attribute'")
    attr_path = spec.strip().partition(":")[2]
    folders = [Path(f) for f in project if f]
    look_in_project(module_name, folders)
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # ImportError, or an error raised by the module's own code
        raise error(f"{what} {spec!r}: cannot import module {module_name!r}: {type(exc).__name__}: "
                    f"{exc} ({_import_hint(module_name, exc, folders)})") from exc
    obj: Any = module
    for part in attr_path.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            public = sorted(n for n in dir(module) if not n.startswith("_"))
            raise error(f"{what} {spec!r}: module {module_name!r} has no attribute {attr_path!r} "
                        f"(it has: {', '.join(public[:20])})") from None
    return obj


def _import_hint(module_name: str, exc: BaseException, folders: Sequence[Path]) -> str:
    """Where the module was looked for and what to do, for an import that failed."""
    missing = getattr(exc, "name", None) if isinstance(exc, ModuleNotFoundError) else None
    if missing is not None and not (module_name == missing or module_name.startswith(missing + ".")):
        return (f"the module was found, but it imports {missing!r}, which is not installed: "
                f"install it in this environment")
    if missing is None:
        return "the module was found, but importing it raised this error"
    looked = "looked on sys.path" + (
        f", then in {', '.join(str(f) for f in folders)}" if folders else "")
    top = module_name.split(".")[0]
    return (f"{looked}; put {top}.py or the package folder {top}/ there, install it "
            f"(pip install -e .), or add its folder to PYTHONPATH")


def _library_folders() -> list[Path]:
    """The folders of code that is not the user's: the standard library, site-packages (the
    environment's, the base interpreter's, the user's), and this plugin's own package."""
    names = ("stdlib", "platstdlib", "purelib", "platlib")
    places = set()
    for paths in (sysconfig.get_paths(),
                  sysconfig.get_paths(vars={"base": sys.base_prefix, "platbase": sys.base_exec_prefix,
                                            "installed_base": sys.base_prefix,
                                            "installed_platbase": sys.base_exec_prefix})):
        places.update(paths[n] for n in names if paths.get(n))
    try:
        places.update(site.getsitepackages())
        places.add(site.getusersitepackages())
    except AttributeError:   # a virtualenv's old site module
        pass
    places.add(os.fspath(Path(__file__).resolve().parents[1]))
    return [Path(p).resolve() for p in places if p]


def own_code(obj: Any, spec: str, *, what: str, error: type[Exception] = SubjectLoadError) -> Any:
    """``obj`` if it is a class or function defined in a Python file of the user's own (found as
    the module docstring says), else ``error`` saying why and what to name instead: a builtin
    (``os:fork``, ``signal:pause``), a callable of the standard library or of an installed
    package (site-packages), or an object that is neither a class nor a function is refused, so
    that a scenario file can only name code its user wrote."""
    fix = f"name a class or function of your own module ({what}s live beside the scenario or in the project)"
    if not (inspect.isclass(obj) or inspect.isfunction(obj)):
        raise error(f"{what} {spec!r} is a {type(obj).__name__}, not a class or function of your own "
                    f"module (fix: {fix})")
    module = sys.modules.get(getattr(obj, "__module__", None) or "")
    origin = getattr(module, "__file__", None)
    if not origin or not origin.endswith(".py"):
        raise error(f"{what} {spec!r} is defined in {getattr(obj, '__module__', '?')!r}, which is not a "
                    f"Python file of yours (built in or compiled) (fix: {fix})")
    path = Path(origin).resolve()
    for folder in _library_folders():
        if path.is_relative_to(folder):
            raise error(f"{what} {spec!r} is defined in {path}, in {folder} (the standard library, an "
                        f"installed package or this plugin), not in your own code (fix: {fix})")
    return obj
