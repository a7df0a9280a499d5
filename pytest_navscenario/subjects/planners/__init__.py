"""Built-in reference planners (test subjects and examples of the planner protocol).

* ``dwa`` -> :class:`DynamicWindowPlanner` (Fox et al. 1997): footprint-aware, the strong one.
* ``potential-field`` -> :class:`PotentialFieldPlanner` (Khatib 1986): reactive, the weak one.

Both use only the lidar (``obs.ranges`` / ``obs.angles``), never the obstacle map. The classes
are imported lazily so that importing this package costs nothing.
"""
from __future__ import annotations

from ...core.lazy import lazy_exports

_EXPORTS = {
    "DynamicWindowPlanner": "dwa",
    "PotentialFieldPlanner": "potential_field",
}
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_exports(__name__, _EXPORTS)
