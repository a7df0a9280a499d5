"""The array kernels of the temporal operators, each a few whole-array numpy operations.

Every kernel reads the trace as RTAMT's offline discrete-time evaluator does, end of trace
included: a window ``[i+a, i+b]`` is cut at the last sample; an empty window holds ``fill`` (the
identity of the reduction: +inf for a minimum, -inf for a maximum), so ``always[a:b]`` holds and
``eventually[a:b]`` fails where nothing is left of the trace.

- ``window``: a sliding minimum or maximum over ``[i+a, i+b]``, van Herk/Gil-Werman (blocks of the
  window's length, a prefix and a suffix accumulate per block, one combining operation): O(n)
  whatever the window; short windows as shifted pairwise operations.
- ``until``: ``max over m in [i+a, i+b] of min(psi[m], min(phi[i..m-1]))``. The unbounded until
  is the recurrence ``U[i] = max(psi[i], min(phi[i], U[i+1]))``, a composition of maps
  ``x -> max(p, min(q, x))``, which compose to maps of the same form, so a parallel suffix scan
  (doubling steps, ceil(log2 n) of them, each three array operations) computes it without a loop
  over samples. The bounded until follows from lattice identities (max/min are distributive, so
  an identity of and/or that holds for true/false holds for robustness):
  ``phi U[a:b] psi = always[0:a-1] phi  and  shift_a(U(phi, psi) and eventually[0:b-a] psi)``.
- The past operators (``historically``, ``once``, ``since``) are the future ones on the reversed
  trace.
"""
from __future__ import annotations

import numpy as np

INF = np.inf
_SHIFTS_UP_TO = 6        # windows this short: pairwise shifted operations beat the block method


def suffix(x: np.ndarray, fn: np.ufunc) -> np.ndarray:
    """``fn`` over ``x[i:]`` at every i (unbounded always/eventually)."""
    return fn.accumulate(x[::-1])[::-1]


def window(x: np.ndarray, a: int, b: int, fn: np.ufunc, fill: float) -> np.ndarray:
    """``fn`` (np.minimum or np.maximum) over ``x[i+a : i+b+1]`` cut at the end; ``fill`` if empty."""
    n = x.shape[0]
    if a >= n:
        return np.full(n, fill)
    w = min(b - a + 1, n - a)          # past n - a the window only adds fill: exact
    if w == 1:
        out = np.full(n, fill)
        out[: n - a] = x[a:]
        return out
    if w <= _SHIFTS_UP_TO:
        z = np.full(n + w - 1, fill)
        z[: n - a] = x[a:]
        out = z[:n].copy()
        for k in range(1, w):
            fn(out, z[k:k + n], out=out)
        return out
    length = -(-(n + w - 1) // w) * w
    z = np.full(length, fill)
    z[: n - a] = x[a:]
    blocks = z.reshape(-1, w)
    prefix = fn.accumulate(blocks, axis=1).ravel()
    suffix_ = fn.accumulate(blocks[:, ::-1], axis=1)[:, ::-1].ravel()
    return fn(suffix_[:n], prefix[w - 1:w - 1 + n])


def until_unbounded(phi: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """``U[i] = max(psi[i], min(phi[i], U[i+1]))`` with ``U[n] = -inf``, by a doubling scan."""
    n = phi.shape[0]
    p = psi.copy()
    q = phi.copy()
    d = 1
    while d < n:
        m = n - d
        p[:m] = np.maximum(p[:m], np.minimum(q[:m], p[d:]))
        if 2 * d < n:
            q[:m] = np.minimum(q[:m], q[d:])
        d *= 2
    return p


def until(phi: np.ndarray, psi: np.ndarray, a: int, b: int | None) -> np.ndarray:
    """``phi U[a:b] psi`` (``b=None``: unbounded end) at every sample (module docstring)."""
    n = phi.shape[0]
    v = until_unbounded(phi, psi)
    if b is not None:
        v = np.minimum(v, window(psi, 0, b - a, np.maximum, -INF))
    if a == 0:
        return v
    out = np.full(n, -INF)
    out[: max(n - a, 0)] = v[a:]
    return np.minimum(out, window(phi, 0, a - 1, np.minimum, INF))


def past_window(x: np.ndarray, a: int, b: int, fn: np.ufunc, fill: float) -> np.ndarray:
    """``fn`` over ``x[i-b : i-a+1]`` cut at the start (historically/once[a:b])."""
    return window(x[::-1], a, b, fn, fill)[::-1]


def since(phi: np.ndarray, psi: np.ndarray, a: int, b: int | None) -> np.ndarray:
    """``phi S[a:b] psi``: ``max over m in [i-b, i-a] of min(psi[m], min(phi[m+1..i]))``."""
    return until(phi[::-1], psi[::-1], a, b)[::-1]
