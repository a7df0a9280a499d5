"""A run-level lidar noise model for scenarios that declare none (``--nav-sensor-model``).

The shipped seeds, like the paper's, have a noise-free lidar: a failure found there may hold only
for one exact scan, and nothing is there to confirm it against. ``--nav-sensor-model realistic``
gives every scenario whose lidar declares no noise model (all of ``noise_sigma``,
``noise_per_metre``, ``dropout``, ``dropout_at_max`` and ``spurious`` at their defaults) a typical
2D lidar's: 2 cm Gaussian range noise (sigma) and 1 % of beams without a return (the model of the
measurements in issue 29). Scenarios that declare their own keep it; the files stay as they are
(the scenario as run carries the model, so a frozen failure found under it is written with it).
"""
from __future__ import annotations

import dataclasses
import math
from typing import Mapping

from .model import LIDAR, Lidar, Scenario

NOISE_KEYS = ("noise_sigma", "noise_per_metre", "dropout", "dropout_at_max", "spurious")
MODELS: dict[str, dict[str, float]] = {
    "realistic": {"noise_sigma": 0.02, "dropout": 0.01},
}


def parse_sensor_model(text: str) -> dict[str, float] | None:
    """``none`` (None), a model's name (MODELS) or ``key=value,...`` over NOISE_KEYS, each within
    the range the scenario format allows. ValueError saying what is accepted otherwise."""
    value = text.strip()
    if value.lower() in ("", "none", "off", "no"):
        return None
    if value.lower() in MODELS:
        return dict(MODELS[value.lower()])
    if "=" not in value:
        raise ValueError(f"unknown sensor model {text!r}: give {' or '.join(MODELS)}, none, or lidar noise "
                         f"keys as key=value,... (e.g. noise_sigma=0.03,dropout=0.02; keys: {', '.join(NOISE_KEYS)})")
    model: dict[str, float] = {}
    for part in value.split(","):
        key, _, raw = (p.strip() for p in part.partition("="))
        if key not in NOISE_KEYS:
            raise ValueError(f"sensor model {text!r}: unknown lidar noise key {key!r}; use {', '.join(NOISE_KEYS)}")
        try:
            number = float(raw)
        except ValueError:
            number = math.nan
        lo, hi = LIDAR[key].span
        if not math.isfinite(number) or not lo <= number <= hi:
            raise ValueError(f"sensor model {text!r}: {key} must be a number from {lo:g} to {hi:g}, got {raw!r}")
        model[key] = number
    return model


def declares_noise(lidar: Lidar) -> bool:
    """Whether a lidar has a noise model of its own (any noise key away from its default)."""
    return any(getattr(lidar, k) != LIDAR[k].default for k in NOISE_KEYS)


def with_sensor_model(scenario: Scenario, model: Mapping[str, float] | None) -> Scenario:
    """``scenario`` with ``model`` as its lidar's noise when it declares none (else itself)."""
    if not model or declares_noise(scenario.robot.lidar):
        return scenario
    lidar = dataclasses.replace(scenario.robot.lidar, **model)
    return dataclasses.replace(scenario, robot=dataclasses.replace(scenario.robot, lidar=lidar))
