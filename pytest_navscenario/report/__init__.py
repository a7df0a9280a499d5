"""Report: what a run tells its users.

In: episode results and results-file records. Out: the results file (JSON Lines, one record per
episode), the terminal summary with confidence intervals, comparisons of two runs (rates, McNemar,
fixed and broken lists, JUnit), plots, and the self-contained HTML reports.

Read first: ``results_file.py`` (the record format), then ``summary.py``, ``compare.py``
(``requirement_compare.py``: per requirement), ``plots.py`` (a trajectory picture's layout and order;
its parts: ``figures.py``, ``map_parts.py`` the map's layers, ``map_moments.py`` its key moments,
``terrain_plot.py`` the ground and the side profile, ``requirement_plot.py`` requirements on the map
and over time, ``labels.py`` label placement, ``bars.py`` the comparison's bar chart), ``html.py``
(rendered from ``templates/``), ``stats.py``, ``flaky.py``, ``rerun.py``.
"""
