"""MuJoCo's built-in profiler off while episodes run (alone or in a batch).

MuJoCo's Python bindings install a timer callback (``mjcb_time``) so that every ``mj_step``
records how long each of its stages took in ``MjData.timer``: a clock read at the start and end
of every stage, about thirty a step. For the small planar worlds of a scenario that is a third
of a physics step (boxes1: 1.70 against 1.10 us a step, ``benchmarks/bench_batch.py physics``).
Nothing in this package reads those timings, so while an episode or a batch runs the C global
``mjcb_time`` is set to NULL (MuJoCo's own "no profiler" state: ``timer[].number`` still
counts, the durations stay 0) and put back when the last running one ends. The timer never
feeds the physics: every trajectory is the same bit for bit.

The global is written through ctypes in MuJoCo's shared library (the one the bindings loaded);
where it cannot be found (another platform's file name, a build without the symbol) episodes
run with the profiler on, as before.
"""
from __future__ import annotations

import glob
import os
import threading
from contextlib import contextmanager
from typing import Any, Iterator

_LOCK = threading.Lock()
_state: dict[str, Any] = {"slot": None, "running": 0, "saved": None}


def _slot() -> Any:
    """The ctypes view of MuJoCo's ``mjcb_time`` global, or False when it cannot be had."""
    slot = _state["slot"]
    if slot is None:
        try:
            import ctypes

            import mujoco
            folder = os.path.dirname(mujoco.__file__)
            names = sorted(glob.glob(os.path.join(folder, "libmujoco.so*")) + glob.glob(
                os.path.join(folder, "libmujoco*.dylib")) + glob.glob(os.path.join(folder, "mujoco.dll")))
            slot = ctypes.c_void_p.in_dll(ctypes.CDLL(names[0]), "mjcb_time")
        except (ImportError, OSError, IndexError, ValueError, AttributeError):
            slot = False
        _state["slot"] = slot
    return slot


@contextmanager
def profiler_off() -> Iterator[None]:
    """MuJoCo's profiler off for the ``with`` block (threads may overlap: the first one in turns
    it off, the last one out puts back what was there)."""
    slot = _slot()
    if slot is False:
        yield
        return
    with _LOCK:
        if _state["running"] == 0:
            _state["saved"] = slot.value
            slot.value = None
        _state["running"] += 1
    try:
        yield
    finally:
        with _LOCK:
            _state["running"] -= 1
            if _state["running"] == 0:
                slot.value = _state["saved"]
