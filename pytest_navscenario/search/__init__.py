"""Search: find scenarios near a seed that make the planner fail, shrink them, freeze them.

In: a seed ``Scenario`` (its ``search:`` section bounds the space) and a way to run an episode.
Out: a ``SearchReport`` (every candidate simulated, the distinct failures, each shrunk toward the
seed) and frozen scenario files with provenance, which are ordinary regression scenarios.

Read first: ``space.py`` (what may change, by how much, and which candidates are valid), then
``engine.py`` (``run_search``, ``SearchConfig`` and the ask/tell loop), ``strategies/`` (one module
per strategy, one registry of their names, ``protocol.Strategy`` the interface), ``report.py``
(``Candidate``, ``Failure``, ``SearchReport``), ``evaluation.py`` (one candidate's episode and the
``Simulator`` that records it), ``evaluators.py`` (the ``Evaluator`` hooks and their defaults),
``confirming.py`` and ``holding.py`` (failures that hold), ``shrinker.py`` (shrinking, driven by
Hypothesis), ``fitness.py`` (reading an episode: robustness and cause signature), ``parallel.py``
and ``batched.py`` (evaluators on worker processes and in lockstep batches), ``freeze.py``
(writing) and ``suite.py`` (the generated suite as scenario files); ``discards.py`` says why
many candidates were discarded and what to change in the seed's ``search:`` section.

Names are imported lazily so that importing this package stays cheap.
"""
from __future__ import annotations

from ..core.lazy import lazy_exports

_EXPORTS = {name: "engine" for name in ("run_search", "SearchConfig", "STRATEGIES", "is_duplicate",
                                         "is_near_failure")}
_EXPORTS.update({name: "report" for name in ("Candidate", "Failure", "SearchReport")})
_EXPORTS.update({name: "shrinker" for name in ("shrink_failure", "ShrinkBudget", "shrink_plan", "shrink_order",
                                                "shrink_all")})
_EXPORTS.update(SearchSpace="space", scenarios_around="space", invalid_reason="space",
                freeze_failures="freeze", write_search_log="freeze", write_suite="suite")
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_exports(__name__, _EXPORTS)
