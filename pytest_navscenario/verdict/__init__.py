"""Verdict: what an episode means.

In: a ``Scenario`` and the simulation's record (trajectory and ending event). Out: the
``Outcome`` (subject-error, collision, fall, safety-stop, requirement, timeout, success, in that
precedence), a one line message, the ``Metrics`` (clearance, gap, path length and efficiency,
duration, smoothness, reference deviation) and each requirement's verdict, bundled in an
``EpisodeResult``. Pure functions of their inputs.

Read first: ``result.py`` (the types), then ``oracle.py`` (the outcome), ``metrics.py`` and
``paths.py`` (shortest footprint paths, cached), ``gaps.py`` (exact distances between rounded boxes,
the narrowest obstacle gap, the obstacles paths keep clear of), ``requirements.py`` (the scenario's
STL requirements checked) and ``signals.py`` (the signals they name, per control tick).
"""
