"""Lazy package exports (PEP 562): a package names what it exports and from which of its modules,
and a module is imported only when one of its names is first used. This keeps ``import
pytest_navscenario`` and the pytest plugin's load free of numpy, MuJoCo and matplotlib."""
from __future__ import annotations

import importlib
from typing import Any, Callable, Mapping


def lazy_exports(package: str, exports: Mapping[str, str], hint: str = "") -> Callable[[str], Any]:
    """The module-level ``__getattr__`` of ``package``: ``exports`` maps a name to the module of the
    package (relative, dotted) that defines it; ``hint`` is added to the error for unknown names."""

    def __getattr__(name: str) -> Any:  # noqa: N807 (the module attribute hook)
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}{hint}")
        return getattr(importlib.import_module(f".{module}", package), name)

    return __getattr__
