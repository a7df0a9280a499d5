"""Checking an episode against its requirements (issue 34): every signal a formula names is
computed once (``signals.py``), each formula's robustness over the whole trace is array work
(``pytest_navscenario.stl``), and each requirement gets a ``RequirementResult``: its robustness at
t = 0 (the verdict: < 0 violated), the first time it was violated and the unit of its signals.

The end of a trace: an episode that ends early (goal, collision, fall) is judged on what was
recorded, as RTAMT's offline evaluator does: a bounded ``eventually`` whose window runs past the
end reads only what is left, so "reach the dock within 60 s" fails when the episode ended earlier
without reaching it.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..scenario.model import Scenario
from ..sim.trajectory import Trajectory
from .signals import episode_signals, samples, signal_unit


@dataclass(frozen=True)
class RequirementResult:
    """One requirement's verdict on one episode. ``robustness`` is in ``unit`` (the formula's
    signals' common unit; "" when they differ); ``first_violation`` in s (None when it held);
    ``scale`` the declared scale (None: none declared); ``span``: the range of its signals' values
    in this episode (the search's default scale)."""
    name: str
    spec: str
    robustness: float
    first_violation: float | None
    unit: str = ""
    scale: float | None = None
    span: float = float("nan")

    @property
    def violated(self) -> bool:
        return self.robustness < 0

    def as_dict(self) -> dict:
        return {"name": self.name, "spec": self.spec, "robustness": self.robustness,
                "violated": self.violated, "first_violation": self.first_violation, "unit": self.unit,
                "scale": self.scale, "span": self.span}

    @classmethod
    def from_dict(cls, data: dict) -> "RequirementResult":
        return cls(data["name"], data["spec"], float(data["robustness"]), data.get("first_violation"),
                   data.get("unit", ""), data.get("scale"), float(data.get("span", float("nan"))))


@functools.lru_cache(maxsize=1024)
def _parsed(spec: str):
    from ..stl import parse
    return parse(spec)


def check_requirements(scenario: Scenario, trajectory: Trajectory) -> tuple[RequirementResult, ...]:
    """Each of the scenario's requirements checked on the recorded trajectory (empty without any)."""
    if not scenario.requirements:
        return ()
    from ..stl import evaluate

    formulas = [_parsed(r.spec) for r in scenario.requirements]
    names = sorted(set().union(*(f.signals for f in formulas)))
    at = samples(scenario, trajectory)
    values = episode_signals(scenario, trajectory, names, at)
    out = []
    for req, formula in zip(scenario.requirements, formulas):
        used = sorted(formula.signals)
        units = {signal_unit(scenario, n) for n in used if n != "time"}
        spans = [float(np.ptp(values[n][np.isfinite(values[n])])) for n in used
                 if n != "time" and np.isfinite(values[n]).any()]
        if not len(at.times):
            out.append(RequirementResult(req.name, req.spec, float("nan"), None, "", req.scale))
            continue
        ev = evaluate(formula, {n: values[n] for n in used}, at.dt)
        rho = float(ev.robustness)
        first = ev.first_violation_time if rho < 0 else None
        out.append(RequirementResult(req.name, req.spec, rho, None if first is None else float(first),
                                     units.pop() if len(units) == 1 else "", req.scale,
                                     max(spans) if spans else float("nan")))
    return tuple(out)


def violation_message(violated: Sequence[RequirementResult]) -> str:
    """One line: the requirement violated first (then the others by name)."""
    first = min(violated, key=lambda r: (r.first_violation if r.first_violation is not None else 0.0,
                                         r.robustness))
    unit = f" {first.unit}" if first.unit else ""
    when = f" first at t={first.first_violation:.2f} s" if first.first_violation is not None else ""
    text = (f"requirement '{first.name}' violated: {first.spec}{when}, robustness "
            f"{first.robustness:.3g}{unit}")
    others = [r.name for r in violated if r is not first]
    if others:
        text += f" (also violated: {', '.join(others)})"
    return text
