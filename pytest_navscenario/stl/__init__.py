"""Requirements in signal temporal logic (STL): the formula language and its robustness.

In: a formula's text in RTAMT's discrete-time syntax and, to evaluate it, its signals as arrays
sampled every ``dt`` seconds. Out: a ``Formula`` (``parse``; ``StlSyntaxError`` with the column
and a fix on a mistake; ``Formula.check_period(dt)`` checks its intervals against a period), the robustness at every sample (``robustness``: RTAMT's offline
discrete-time semantics, vectorised with numpy) and the verdict (``evaluate`` -> ``Evaluation``:
the robustness at time 0, violated or not, the first violation's time and sample).

Pure Python and numpy; imports nothing of the package but ``core/``. The API::

    from pytest_navscenario.stl import parse, Formula, StlSyntaxError, robustness, evaluate, Evaluation
    f = parse("always ((d_walker < 1.5) implies (speed <= 0.3))")
    f.signals                      # frozenset({'d_walker', 'speed'})
    f.text                         # canonical text: 'always((d_walker < 1.5) implies (speed <= 0.3))'
    rho = robustness(f, {"d_walker": d, "speed": v}, dt=0.1)     # float64 array, one per sample
    ev = evaluate(f, {"d_walker": d, "speed": v}, dt=0.1)        # Evaluation(robustness=rho[0], ...)

Read first: ``formula.py`` (``parse``, ``Formula``), then ``parser.py`` (the precedence),
``evaluation.py`` (``robustness``, ``evaluate``), ``plan.py`` (each operator as array work) and
``windows.py`` (the sliding-window and until kernels). The language's reference is
docs/reference/requirements-language.md.
"""
from __future__ import annotations

from .errors import StlError, StlEvaluationError, StlSyntaxError
from .evaluation import Evaluation, evaluate, robustness
from .formula import Formula, parse

__all__ = ["parse", "Formula", "StlError", "StlSyntaxError", "StlEvaluationError",
           "robustness", "evaluate", "Evaluation"]
