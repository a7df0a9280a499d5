"""Built-in reference planners (test subjects and examples of the planner protocol).

* ``dwa`` -> :class:`DynamicWindowPlanner` (Fox et al. 1997): footprint-aware, the strong one.
* ``potential-field`` -> :class:`PotentialFieldPlanner` (Khatib 1986): reactive, the weak one.

Both use only the lidar (``obs.ranges`` / ``obs.angles``), never the obstacle map. The classes
are imported lazily so that importing this package costs nothing.
"""
from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "DynamicWindowPlanner": "dwa",
    "PotentialFieldPlanner": "potential_field",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'pytest_navscenario.subjects.planners' has no attribute {name!r}")
    return getattr(importlib.import_module(f".{module}", __name__), name)
