"""RTAMT (the reference implementation of STL robustness) as a test oracle.

RTAMT is a test-only dependency: it pins antlr4-python3-runtime==4.7, which other tools in a
user's environment cannot share. Tests that use it skip with the install hint when it is missing.
"""
from __future__ import annotations

import warnings

import pytest

INSTALL_HINT = ("RTAMT (the STL reference) is not installed: pip install -e '.[stl-reference]' "
                "(rtamt 0.4.10, Python < 3.13)")


def rtamt_module():
    """The rtamt module, or a skip with the install hint (an import that fails counts as missing:
    its ANTLR 4.7 runtime does not import on newer Pythons)."""
    try:
        with warnings.catch_warnings():      # its ANTLR runtime imports typing.io (deprecated)
            warnings.simplefilter("ignore", DeprecationWarning)
            import rtamt
    except ImportError as err:
        pytest.skip(f"{INSTALL_HINT} [{type(err).__name__}: {err}]")
    return rtamt


def rtamt_robustness(text: str, signals: dict, dt: float) -> list[float]:
    """RTAMT's offline discrete-time robustness of ``text`` at every sample (period ``dt`` s)."""
    rtamt = rtamt_module()
    spec = rtamt.StlDiscreteTimeSpecification()
    for name in signals:
        spec.declare_var(name, "float")
    spec.spec = text
    period_ms = round(dt * 1000)
    assert abs(period_ms / 1000 - dt) < 1e-12, "the reference takes whole milliseconds"
    spec.set_sampling_period(period_ms, "ms", 0.1)
    spec.parse()
    n = len(next(iter(signals.values())))
    data = {"time": [i * period_ms / 1000 for i in range(n)]}
    for name, values in signals.items():
        data[name] = [float(v) for v in values]      # fresh lists: RTAMT pads some in place
    return [value for _, value in spec.evaluate(data)]
