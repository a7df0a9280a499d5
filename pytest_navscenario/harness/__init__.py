"""Harness: one scenario against one subject, end to end.

In: a ``Scenario`` and a subject (spec, class, factory or instance). Out: an ``EpisodeResult``
(``runner.run_scenario``: simulate, then judge), or a ``PlannerCheck`` (``conformance.
check_planner``: does a planner honour the protocol, limits, time and determinism).

Read first: ``runner.py``.
"""
