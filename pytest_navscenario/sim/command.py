"""From the planner to the actuators: the one place the planner's code is called (under the optional
per-tick deadline), the check of what it answered, and the drive that turns a valid command into
the velocity setpoint (clipped to the drive's limits, rate-limited by its accelerations).
"""
from __future__ import annotations

import math
import os
import traceback
from typing import Any, Callable

import numpy as np

from ..core.interrupts import PlannerExit, from_the_user
from ..scenario.model import Robot
from ..subjects.protocol import Command
from .deadline import PlannerTimeout, TickDeadline

_SIM_DIR = os.path.dirname(os.path.abspath(__file__))


def call_planner(fn: Callable[[Any], Any], arg: Any, deadline: TickDeadline | None) -> Any:
    """The ONE place the planner's code is called (reset or act), under the optional tick limit.
    SystemExit/KeyboardInterrupt raised by the planner's own code become PlannerExit (an ordinary
    subject error with the planner's frames); a user's Ctrl-C passes (core/interrupts.py)."""
    try:
        if deadline is None:
            return fn(arg)
        deadline.arm()
        try:
            out = fn(arg)
        except BaseException:
            try:
                deadline.disarm()
            except PlannerTimeout:
                pass
            raise
        deadline.disarm()  # raises PlannerTimeout when the tick took longer than the limit
        return out
    except (SystemExit, KeyboardInterrupt, GeneratorExit) as exc:
        if from_the_user(exc):
            raise
        raise PlannerExit(exc).with_traceback(exc.__traceback__) from None


def planner_traceback(exc: BaseException) -> str:
    """The planner's own traceback: the harness's frames (the episode, call_planner) are dropped."""
    tb = exc.__traceback__
    while (tb is not None and tb.tb_next is not None
           and os.path.dirname(os.path.abspath(tb.tb_frame.f_code.co_filename)) == _SIM_DIR):
        tb = tb.tb_next
    return "".join(traceback.format_exception(type(exc), exc, tb))


def _describe(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def validate_command(cmd: Any) -> tuple[float, float, float] | str:
    """(vx, vy, wz) as floats, or a plain-words message saying what is wrong with ``cmd``. An
    exception instance (a batch planner's answer for an episode it cannot serve) reads as if
    ``act`` had raised it, so that episode ends with the message it gets alone."""
    expected = "expected a Command(vx, vy, wz) or a sequence of 3 finite floats"
    if (type(cmd) is Command or type(cmd) is tuple) and len(cmd) == 3:   # the common case, fast
        try:
            vx, vy, wz = float(cmd[0]), float(cmd[1]), float(cmd[2])
        except (TypeError, ValueError):
            pass
        else:
            if math.isfinite(vx + vy + wz):
                return vx, vy, wz
    if isinstance(cmd, Exception):   # a batch planner's answer for one episode it cannot serve
        return f"planner.act raised {type(cmd).__name__}: {cmd}"
    if type(cmd) is Command or type(cmd) is tuple:
        items = cmd
    elif isinstance(cmd, np.ndarray):
        if cmd.shape != (3,):
            return f"planner.act returned an array of shape {cmd.shape}, expected shape (3,) (vx, vy, wz)"
        items = cmd.tolist()
    elif isinstance(cmd, (str, bytes, dict)) or cmd is None or not hasattr(cmd, "__len__"):
        return f"planner.act returned {type(cmd).__name__} {_describe(cmd)}; {expected}"
    else:
        items = cmd
    try:
        n = len(items)
    except TypeError:
        return f"planner.act returned {type(cmd).__name__} {_describe(cmd)}; {expected}"
    if n != 3:
        return (f"planner.act returned a {type(cmd).__name__} of length {n} ({_describe(cmd)}); "
                f"{expected}")
    try:
        vx, vy, wz = (float(v) for v in items)
    except (TypeError, ValueError):
        types = ", ".join(type(v).__name__ for v in items)
        return f"planner.act returned a {type(cmd).__name__} of ({types}) {_describe(cmd)}; {expected}"
    if not (math.isfinite(vx) and math.isfinite(vy) and math.isfinite(wz)):
        return f"planner.act returned a non-finite command (vx={vx}, vy={vy}, wz={wz}); {expected}"
    return vx, vy, wz


class Drive:
    """The robot's drive: each tick it clips the command to the drive's speed limits (a diff drive
    has no lateral speed) and moves the velocity setpoint towards it by no more than the
    accelerations allow in one tick. The actuators then track the setpoint (sim/world.py)."""

    def __init__(self, robot: Robot, tick_dt: float):
        limits = robot.limits
        # (max vx, max vy, max wz, largest setpoint change per tick in v, in wz): one tuple, read
        # with one attribute load per tick
        self.limits = (limits.max_speed, limits.max_lateral_speed if robot.drive == "omni" else 0.0,
                       math.radians(limits.max_yaw_rate), limits.max_accel * tick_dt,
                       math.radians(limits.max_yaw_accel) * tick_dt)
        self.current = (0.0, 0.0, 0.0)     # the setpoint (vx, vy, wz), robot frame

    def setpoint(self, vx: float, vy: float, wz: float) -> tuple[float, float, float]:
        """The new setpoint for the command (vx, vy, wz)."""
        max_v, max_vy, max_w, dv, dw = self.limits
        vx = max_v if vx > max_v else (-max_v if vx < -max_v else vx)
        vy = max_vy if vy > max_vy else (-max_vy if vy < -max_vy else vy)
        wz = max_w if wz > max_w else (-max_w if wz < -max_w else wz)
        sp_vx, sp_vy, sp_wz = self.current
        self.current = sp = (sp_vx + min(dv, max(-dv, vx - sp_vx)), sp_vy + min(dv, max(-dv, vy - sp_vy)),
                             sp_wz + min(dw, max(-dw, wz - sp_wz)))
        return sp
