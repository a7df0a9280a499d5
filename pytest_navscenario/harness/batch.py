"""Many episodes of one subject in batches: ``run_batch(scenarios, planner, ...)`` gives each
scenario the EpisodeResult that ``run_scenario`` gives it alone (wall times aside), running the
episodes it can in lockstep with one planner call per tick for a batch (sim/batching/batch.py).

Which episodes are batched: with a subject that answers the batch protocol (reset_batch /
act_batch, subjects/protocol.py) and ``batch`` > 1, consecutive episodes that the engine supports
and that share a tick limit form batches of up to ``batch``, each with one fresh planner made by
the subject's factory. The others run alone, one fresh planner each, exactly as ``run_scenario``
runs them: every episode of a subject without the batch protocol, and episodes the engine cannot
batch (its ``unsupported`` reason, e.g. a robot body that rides the ground). ``Batching`` counts
what happened, for the summary line.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Iterator, Sequence

from ..scenario.model import Scenario
from ..subjects.loading import make_planner, subject_identity
from ..subjects.protocol import SingleFromBatch, is_batch_planner
from ..verdict.result import EpisodeResult
from ..scenario.perturb import perturbed
from .runner import effective_seed, run_scenario, verdict

DEFAULT_BATCH = 16     # episodes a batch: the two generations of 8 a search has in flight
NO_PROTOCOL = "the subject does not implement the batch protocol (reset_batch/act_batch)"


@dataclass
class Batching:
    """How episodes ran: in how many batches, how many alone and why (reason -> episodes)."""
    batched: int = 0
    batches: int = 0
    alone: int = 0
    why_alone: dict[str, int] = field(default_factory=dict)

    def add(self, other: "Batching") -> None:
        self.batched += other.batched
        self.batches += other.batches
        self.alone += other.alone
        for why, n in other.why_alone.items():
            self.why_alone[why] = self.why_alone.get(why, 0) + n

    def note_alone(self, why: str, n: int = 1) -> None:
        self.alone += n
        self.why_alone[why] = self.why_alone.get(why, 0) + n

    def describe(self) -> str:
        """One line: "120 episodes in 15 batches (8 at most), 3 alone: <why>"."""
        parts = []
        if self.batched:
            parts.append(f"{self.batched} episode(s) in {self.batches} batch(es)")
        if self.alone:
            whys = "; ".join(f"{n}: {why}" for why, n in sorted(self.why_alone.items(), key=lambda kv: -kv[1]))
            parts.append(f"{self.alone} alone ({whys})" if whys else f"{self.alone} alone")
        return ", ".join(parts) or "no episodes"


def batch_planner_of(instance: Any) -> Any | None:
    """The object that answers the batch protocol for ``instance`` (a planner made by a subject's
    factory), or None."""
    inner = instance.planner if isinstance(instance, SingleFromBatch) else instance
    return inner if is_batch_planner(inner) else None


def run_batch(scenarios: Sequence[Scenario], planner: Any = None, **kw: Any) -> list[EpisodeResult | Exception]:
    """Each scenario's EpisodeResult (or the exception its episode raised, e.g. a divergence or a
    subject that cannot be made), in order: ``run_scenario(scenarios[i], planner, seed=seeds[i],
    ...)`` for each, with the episodes that can be batched run ``batch`` at a time (see the
    module docstring). The keyword arguments are ``iter_batch``'s."""
    return list(iter_batch(scenarios, planner, **kw))


def iter_batch(scenarios: Sequence[Scenario], planner: Any = None, *, seeds: Sequence[int | None] | None = None,
               tick_limit: float | None = None, reset_timeout: float | None = None,
               stuck_after: float | None = None, batch: int = DEFAULT_BATCH, engine: Any = None,
               batching: Batching | None = None, call_factory: bool = False) -> Iterator[EpisodeResult | Exception]:
    """``run_batch``'s results, in order, each as soon as it is known: an episode run alone right
    after it ran, a batch's once the batch ended (so that what an interrupt cuts short loses no
    finished episode).

    ``planner`` as for run_scenario (a spec, a class or factory, an object), or with
    ``call_factory`` a zero-argument factory whose planners are passed as objects, as the search
    does (``run_scenario(scenario, factory())``). ``seeds``: each episode's base seed (None: the
    scenario's own). ``engine``: a ``sim.batching.batch.BatchEngine`` or its name ("cpu", "warp"; None:
    "cpu"). ``batching`` (if given) is added to."""
    from ..sim.batching.batch import batch_engine

    n = len(scenarios)
    seeds = list(seeds) if seeds is not None else [None] * n
    report = batching if batching is not None else Batching()
    if not n:
        return
    try:
        first = _make(planner, call_factory)
    except Exception as exc:
        yield from [exc] * n
        return
    bp = batch_planner_of(first[0]) if batch > 1 else None
    if bp is None:
        report.note_alone(NO_PROTOCOL if batch > 1 else "batches are off (batch size 1)", n)
        for i, sc in enumerate(scenarios):
            made = first[0] if i == 0 else None
            yield _alone(sc, planner, call_factory, made, seeds[i], tick_limit, reset_timeout, stuck_after)
        return
    eng = batch_engine(engine) if isinstance(engine, str) else (engine or batch_engine())
    out: dict[int, Any] = {}
    chunk: list[int] = []
    spare = [first]          # the planner made to look at the subject serves the first batch
    done = 0                 # results given out so far

    for i, sc in enumerate(scenarios):
        why = eng.unsupported(sc)
        if why is not None:
            report.note_alone(why)
            out[i] = _alone(sc, planner, call_factory, None, seeds[i], tick_limit, reset_timeout, stuck_after)
        else:
            chunk.append(i)
            if len(chunk) >= batch:
                _run_chunk(chunk, scenarios, seeds, planner, call_factory, spare, eng, tick_limit, stuck_after,
                           out, report)
                chunk = []
        while done in out:
            yield out.pop(done)
            done += 1
    if chunk:
        _run_chunk(chunk, scenarios, seeds, planner, call_factory, spare, eng, tick_limit, stuck_after, out, report)
    while done in out:
        yield out.pop(done)
        done += 1


def _make(planner: Any, call_factory: bool) -> tuple[Any, str]:
    """(a fresh planner, the spec that names it) as run_scenario would make it."""
    return make_planner(planner() if call_factory else planner)


def _alone(scenario: Scenario, planner: Any, call_factory: bool, made: Any, seed: int | None, tick_limit,
           reset_timeout, stuck_after) -> Any:
    """run_scenario as the caller runs an episode alone (the planner ``made`` already, if any)."""
    try:
        if made is None:
            made = planner() if call_factory else planner
        elif not call_factory and not _is_object(planner):
            made = planner           # a spec or factory: run_scenario makes (and names) its own
        return run_scenario(scenario, made, seed=seed, tick_limit=tick_limit, reset_timeout=reset_timeout,
                            stuck_after=stuck_after)
    except Exception as exc:
        return exc


def _is_object(planner: Any) -> bool:
    return planner is not None and not isinstance(planner, (str, type)) and hasattr(planner, "act")


def _run_chunk(chunk, scenarios, seeds, planner, call_factory, spare, engine, tick_limit, stuck_after, out,
               report) -> None:
    """One batch: a fresh planner (the subject's factory, or the object given), the engine, the
    verdict of each episode."""
    from ..sim.batching.batch import BatchEpisode

    from ..core import processes
    from ..subjects.external import running_pids

    t0 = time.perf_counter()
    before = processes.children()
    try:
        instance, spec = spare.pop() if spare else _make(planner, call_factory)
    except Exception as exc:
        for i in chunk:
            out[i] = exc
        return
    bp = batch_planner_of(instance)
    ep_seeds = [effective_seed(scenarios[i].simulation.seed, seeds[i]) for i in chunk]
    ran = [perturbed(scenarios[i], s) for i, s in zip(chunk, ep_seeds)]   # simulation.perturb, as run_scenario
    requests = [BatchEpisode(r, s, tick_limit=tick_limit, stuck_after=stuck_after) for r, s in zip(ran, ep_seeds)]
    facts = engine.run(requests, bp)
    name, version = subject_identity(instance, spec)     # after reset: a planner may name itself there
    del instance, bp    # a planner that ends its helpers when it is dropped has done so before the check
    # processes the batch's planner left running: reported once, with the batch's first episode
    left = processes.note_left_behind(before, f"the batch of {scenarios[chunk[0]].name or 'episodes'}",
                                      ours=running_pids())
    share = (time.perf_counter() - t0) / len(chunk)
    for i, s, f, r in zip(chunk, ep_seeds, facts, ran):
        if isinstance(f, Exception):
            out[i] = f
            continue
        out[i] = verdict(scenarios[i], f, s, name, version, stuck_after, time.perf_counter() - share, left, ran=r)
        left = ()
    report.batched += len(chunk)
    report.batches += 1
