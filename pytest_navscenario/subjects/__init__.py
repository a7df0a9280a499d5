"""Subjects: the planners under test and how they are reached.

In: a subject spec as a user writes it (``dwa``, ``package.module:Attribute``,
``exec:PROGRAM ARGS``). Out: a planner factory whose planners answer the protocol: ``reset
(scenario)`` once per episode, ``act(Observation) -> Command`` once per tick.

Read first: ``protocol.py`` (Observation, Command, Planner), then ``loading.py`` (spec to factory,
protocol check), ``external.py`` (planners in another process, JSON Lines over pipes),
``resolve.py`` (the session's subject with its name and version) and ``planners/`` (the built-in
``dwa`` and ``potential-field``).
"""
