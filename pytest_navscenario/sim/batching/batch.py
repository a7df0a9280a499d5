"""Episodes in batches: many episodes stepped in lockstep in this process, one planner call per
control tick for all the episodes still running (the batch protocol, subjects/protocol.py), each
episode's trajectory and ending bit-identical to running it alone (``episode.simulate``).

In: ``BatchEpisode`` requests (scenario, seed, limits) and one planner that answers the batch
protocol. Out: per request a ``SimResult``, or the exception that episode raises alone (a
divergence): one episode's error never fails another.

``BatchEngine`` is the interface: ``unsupported(scenario)`` says why the engine cannot run a
scenario (such episodes run alone), ``run(requests, planner)`` runs a batch. ``LockstepEngine`` is
the CPU engine: each episode keeps its own ``Episode`` (its MuJoCo data, lidar, records), the
harness's per-tick work runs for the whole batch in ``lockstep.py``, and the planner is called once
a tick. A GPU engine (MuJoCo Warp, many worlds in one call) can go behind the same interface.

What a planner call's failure means (docs/reference/planner-protocol.md): ``reset_batch`` raising
fails every episode that started; ``act_batch`` raising, overrunning the tick limit (the limit
times the call's episodes) or answering the wrong number of commands fails the episodes of that
call at that tick; one bad command fails its own episode.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol, Sequence

from ...scenario.model import Scenario
from ..episode import SimResult


@dataclass(frozen=True)
class BatchEpisode:
    """One episode of a batch: ``episode.simulate(scenario, planner, seed, max_ticks,
    tick_limit=..., stuck_after=...)`` without the planner (the batch has one)."""
    scenario: Scenario
    seed: int
    max_ticks: int | None = None
    tick_limit: float | None = None
    stuck_after: float | None = None


class BatchEngine(Protocol):
    """Runs batches of episodes against one batch planner."""

    name: str

    def unsupported(self, scenario: Scenario) -> str | None:
        """Why this engine cannot run ``scenario`` in a batch (it runs alone then), or None."""

    def run(self, requests: Sequence[BatchEpisode], planner: Any) -> list[SimResult | Exception]:
        """Each request's SimResult (or the exception it raised), in request order."""


class LockstepEngine:
    """The CPU engine: the episodes' MuJoCo data stepped one after the other within each tick, the
    harness's per-tick work for the whole batch, one planner call per tick (see lockstep.py)."""

    name = "cpu"

    def unsupported(self, scenario: Scenario) -> str | None:
        from ..body_world import rides_the_ground
        if rides_the_ground(scenario):
            return f"its robot body ({scenario.robot.body.kind}) rides the ground, which the CPU batch engine does not step yet"
        return None

    def run(self, requests: Sequence[BatchEpisode], planner: Any) -> list[SimResult | Exception]:
        from .lockstep import Lockstep
        return Lockstep(requests, planner).run()


_ENGINES: dict[str, Any] = {}


ENGINE_NAMES = ("cpu", "warp")


def batch_engine(name: str = "cpu") -> BatchEngine:
    """The engine called ``name``: "cpu" (``LockstepEngine``) or "warp" (MuJoCo Warp on the default
    Warp device, sim/batching/warp_engine.py; ValueError saying how to install it when it is missing)."""
    engine = _ENGINES.get(name)
    if engine is None:
        if name == "cpu":
            engine = LockstepEngine()
        elif name == "warp":
            from .warp_engine import WarpEngine, missing
            why = missing()
            if why is not None:
                raise ValueError(f"the warp batch engine cannot run: {why}")
            engine = WarpEngine()
        else:
            raise ValueError(f"unknown batch engine {name!r}; available: {', '.join(ENGINE_NAMES)}")
        _ENGINES[name] = engine
    return engine


def simulate_batch(requests: Sequence[BatchEpisode], planner: Any,
                   engine: BatchEngine | None = None) -> list[SimResult | Exception]:
    """Run ``requests`` as one batch against ``planner`` (an object with ``reset_batch`` and
    ``act_batch``); see the module docstring."""
    return (engine or batch_engine()).run(requests, planner)
