"""Search strategies: one module each, named in one registry, imported only when a search uses them.

Read first: ``protocol.py`` (``Strategy``: what ``engine.run_search`` asks of a strategy, and
``BaseStrategy``'s defaults), then a strategy module: ``uniform_random.py`` (``random``, the
baseline), ``hillclimb.py`` (``hillclimb``, the Surrealist baseline), ``evolve.py`` (``evolve``, the
default quality-diversity search, with its aimed operators in ``aim.py``).

``STRATEGIES`` maps each name to ``"module:Class"`` (or to a class) and a line of help, as Hypothesis's
``AVAILABLE_PROVIDERS`` maps a backend's name to its provider: a strategy is named here only, and
the engine, the plugin's ``--navsearch-strategy`` choices, the ini option and the docs read the
names from here. Adding a strategy is one new module and one line below (docs/contributing.md).
"""
from __future__ import annotations

import importlib
from typing import Any, NamedTuple

from ...core.lazy import lazy_exports
from .protocol import GENERATION, BaseStrategy, GaveUp, Strategy

class Registered(NamedTuple):
    """A registry entry: where the class is, and one line for ``--navsearch-strategy``'s help."""
    target: Any      # "module:Class" (a module of this package, or a dotted module path) or the class
    summary: str


#: name -> Registered; the first is the default. One line per strategy.
STRATEGIES: dict[str, Registered] = {
    "evolve": Registered("evolve:Evolve", "default: quality-diversity search drawn by Hypothesis; looks for "
                                          "new ways of failing"),
    "random": Registered("uniform_random:RandomStrategy", "uniform sampling over the same space, a baseline"),
    "hillclimb": Registered("hillclimb:HillClimb", "the Surrealist baseline: adaptive-step hill-climb on one "
                                                   "obstacle at a time, minimising clearance"),
}


def names() -> tuple[str, ...]:
    """The strategy names, the default (evolve) first."""
    return tuple(STRATEGIES)


def describe() -> str:
    """The choices as a sentence, for option help: ``evolve (...), random (...) or hillclimb (...)``."""
    parts = [f"{name} ({entry.summary})" for name, entry in STRATEGIES.items()]
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " or " + parts[-1]


def strategy_class(name: str) -> type:
    """The class registered as ``name`` (imported now); ValueError naming the choices otherwise."""
    try:
        target = STRATEGIES[name].target
    except KeyError:
        raise ValueError(f"unknown search strategy {name!r}; use one of {', '.join(STRATEGIES)}") from None
    if isinstance(target, str):
        module, _, attr = target.partition(":")
        mod = importlib.import_module(f"{__name__}.{module}" if "." not in module else module)
        target = getattr(mod, attr)
    return target


def make_strategy(name: str, space: Any, report: Any, budget: int, seed_value: int) -> Strategy:
    """A fresh ``name`` strategy for one search (see protocol.Strategy)."""
    return strategy_class(name)(space, report, budget, seed_value)


# the names the strategy modules define, for ``from pytest_navscenario.search.strategies import X``
_EXPORTS = {name: "uniform_random" for name in ("RandomStrategy",)}
_EXPORTS.update({name: "hillclimb" for name in ("HillClimb", "HILLCLIMB_STEP", "HILLCLIMB_MIN_STEP",
                                                 "HILLCLIMB_STALL")})
_EXPORTS.update({name: "evolve" for name in ("Evolve", "OPERATORS", "PATH_OPERATORS", "MUTATION_SCALES",
                                              "HUNT_DRAWS", "ROOM_LEVELS", "STREAM_BITS", "NEAR_COPY")})
_EXPORTS.update({name: "aim" for name in ("QUARTERS", "SQUEEZE_BAND", "RETIME_LAG", "RETIME_STARTS",
                                           "RETIME_SPEEDS", "CROWD_GAP", "SHIFT_RADIUS", "_Targets")})
_EXPORTS.update({name: "admission" for name in ("Admission", "uniform", "MAX_INVALID_FACTOR")})
__all__ = ["STRATEGIES", "GENERATION", "BaseStrategy", "GaveUp", "Registered", "Strategy", "describe",
           "make_strategy", "names", "strategy_class", *_EXPORTS]

__getattr__ = lazy_exports(__name__, _EXPORTS)
