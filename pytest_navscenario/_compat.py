"""Old import paths keep working.

Before its subpackages (core, scenario, sim, ...) the package was one flat folder
(``pytest_navscenario.loader``, ``pytest_navscenario.search_space``, ...; never released so). Code
written against those paths keeps
running: importing an old path gives a module whose attributes are looked up in the modules that
now hold them, with a DeprecationWarning naming the new path. A name that no longer exists fails
with an AttributeError that says where to look.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
import warnings

PACKAGE = "pytest_navscenario"

# old module (under the package) -> the modules that now hold its names, first match wins
OLD_PATHS: dict[str, tuple[str, ...]] = {
    "errors": ("core.errors",),
    "loader": ("scenario.loader", "scenario.dump"),
    "yaml_tree": ("scenario.yaml_tree",),
    "geometry": ("scenario.geometry",),
    "planner": ("subjects.protocol", "subjects.loading"),
    "exec_subject": ("subjects.external",),
    "subject": ("subjects.resolve",),
    "planners": ("subjects.planners",),
    "planners.dwa": ("subjects.planners.dwa",),
    "planners.potential_field": ("subjects.planners.potential_field",),
    "deadline": ("sim.deadline",),
    "safety": ("sim.safety",),
    "result": ("verdict.result", "sim.trajectory"),
    "oracle": ("verdict.oracle",),
    "metrics": ("verdict.metrics",),
    "paths": ("verdict.paths",),
    "runner": ("harness.runner", "subjects.loading"),
    "conformance": ("harness.conformance",),
    "search_space": ("search.space",),
    "freeze": ("search.freeze",),
    "results": ("report.results_file", "core.files"),
    "summary": ("report.summary",),
    "stats": ("report.stats",),
    "compare": ("report.compare", "report.rerun"),
    "plots": ("report.plots",),
    "html_report": ("report.html",),
    "flaky": ("report.flaky",),
    "bags": ("ros.bag_writer",),
    "bag_import": ("ros.bag_import",),
    "map_import": ("ros.map_import",),
    "world_import": ("ros.world_import",),
    "options": ("plugin.options",),
    "state": ("plugin.state",),
    "collect": ("plugin.collect",),
    "fixtures": ("plugin.fixtures",),
    "payload": ("plugin.payload",),
    "hookspecs": ("plugin.hookspecs",),
    "artifacts": ("plugin.artifacts", "core.files"),
    "bag_plugin": ("plugin.bags",),
    "report_plugin": ("plugin.reports",),
    "search_plugin": ("plugin.search",),
    "cli_run": ("cli.run",),
    "compare_cli": ("cli.compare",),
}


def _forwarding_module(old: str, targets: tuple[str, ...]) -> types.ModuleType:
    full = [f"{PACKAGE}.{t}" for t in targets]
    module = types.ModuleType(f"{PACKAGE}.{old}", f"Moved: see {', '.join(full)}.")

    def __getattr__(name: str):  # noqa: N807 (module-level attribute hook)
        if name.startswith("__"):
            raise AttributeError(name)
        for target in full:
            try:
                mod = importlib.import_module(target)
            except ModuleNotFoundError:
                continue
            if hasattr(mod, name):
                value = getattr(mod, name)
                home = getattr(value, "__module__", None)  # where a class or function is defined
                where = home if isinstance(home, str) and home.startswith(PACKAGE + ".") else target
                warnings.warn(f"{PACKAGE}.{old} moved: import {name} from {where}",
                              DeprecationWarning, stacklevel=2)
                return value
        raise AttributeError(f"{PACKAGE}.{old}.{name} no longer exists; the module {PACKAGE}.{old} "
                             f"moved to {' / '.join(full)} (see the docs' API reference)")

    module.__getattr__ = __getattr__  # type: ignore[attr-defined]
    module.__path__ = []  # lets old sub-paths (planners.dwa) resolve through this finder
    return module


class _OldPathFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``pytest_navscenario.<old name>`` and hands out a forwarding module."""

    def find_spec(self, fullname, path=None, target=None):
        prefix = PACKAGE + "."
        if not fullname.startswith(prefix) or fullname[len(prefix):] not in OLD_PATHS:
            return None
        return importlib.machinery.ModuleSpec(fullname, self, is_package=True)

    def create_module(self, spec):
        old = spec.name[len(PACKAGE) + 1:]
        return _forwarding_module(old, OLD_PATHS[old])

    def exec_module(self, module):
        pass


def install() -> None:
    if not any(isinstance(f, _OldPathFinder) for f in sys.meta_path):
        sys.meta_path.append(_OldPathFinder())
