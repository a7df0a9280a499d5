"""RTAMT (the reference implementation of STL robustness) as a test oracle.

RTAMT is a test-only dependency: it pins antlr4-python3-runtime==4.7, which other tools in a
user's environment cannot share. Tests that use it skip with the install hint when it is missing.
"""
from __future__ import annotations

import pytest

INSTALL_HINT = ("RTAMT (the STL reference) is not installed: pip install -e '.[stl-reference]' "
                "(rtamt 0.4.10)")


def rtamt_module():
    return pytest.importorskip("rtamt", reason=INSTALL_HINT)


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
