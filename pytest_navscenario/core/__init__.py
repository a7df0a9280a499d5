"""Core: what every layer shares.

In: nothing from the rest of the package. Out: the exception hierarchy (``errors``: every error a
user sees derives from ``NavScenarioError``) and safe file writing (``files``: atomic whole-file
writes, JSON-safe values, file names safe on every platform), and the MuJoCo release in use
(``versions``, named without importing it).

Read first: ``errors.py``.
"""
