"""The CPU batch engine's loop (sim/batching/batch.py): a batch's episodes, each an ``Episode`` with its own
MuJoCo data, lidar and records, advanced tick by tick together; one planner call a tick for the
episodes still running.

Each tick: every running episode observes (ending at its goal, its time limit, a terrain or stuck
check) and passes the safety layer; the planner gets one ``act_batch`` call for those still
running; each answer is validated and limited by the episode's drive, recorded, and its physics
stepped. Every per-episode step is the ``Episode``'s own method, so each trajectory is the bits
``episode.simulate`` gives alone; MuJoCo's warnings are attributed to the episode whose steps
raised them (the list is cleared before each episode's physics).
"""
from __future__ import annotations

from time import perf_counter
from typing import AbstractSet, Any, Mapping, Sequence

import mujoco

from ...core.errors import SimulationDivergedError, SimulationFatalError
from ..command import call_planner, planner_traceback, validate_command
from ..deadline import PlannerTimeout, TickDeadline
from ..episode import Episode, EpisodeOver, SimResult
from ..profiler import profiler_off
from ..trajectory import SubjectFailure
from ..world import MUJOCO_WARNINGS, divergence_message, fatal_message


def _tick_limit(requests: Sequence[Any]) -> float | None:
    limits = {r.tick_limit or None for r in requests}
    if len(limits) > 1:
        raise ValueError(f"the episodes of one batch must share their tick limit, got {sorted(limits, key=str)}")
    return limits.pop() if limits else None


COHORTS = True     # episodes that can observe and step together do (cohort.py); False: each its own steps


def _short(value: Any) -> str:
    """repr(value) cut to 60 characters (a repr that raises: its type)."""
    try:
        return f"{value!r:.60}"
    except Exception:
        return f"<{type(value).__name__}>"


class _Failed:
    """What every episode of a failed planner call gets instead of a command."""

    def __init__(self, message: str, traceback: str | None = None):
        self.message, self.traceback = message, traceback


class Lockstep:
    """One batch: ``run()`` returns each request's SimResult or exception, in request order."""

    def __init__(self, requests: Sequence[Any], planner: Any):
        self.requests = list(requests)
        self.planner = planner
        self.limit = _tick_limit(self.requests)
        self.results: list[SimResult | Exception | None] = [None] * len(self.requests)
        self.episodes: list[Episode | None] = [None] * len(self.requests)
        self.ids: dict[int, int] = {}          # episode index -> its id for the planner
        self._deadline: TickDeadline | None = None

    # ------------------------------------------------------------ the batch

    def run(self) -> list[SimResult | Exception]:
        """The batch, MuJoCo's profiler off (profiler.py)."""
        with profiler_off():
            return self._run()

    def _run(self) -> list[SimResult | Exception]:
        deadline = self._deadline = TickDeadline(self.limit) if self.limit else None
        if deadline is not None:
            deadline.__enter__()
        try:
            running = self._start()
            steps = {i: self.episodes[i].steps() for i in running}
            self._form_cohorts(running)
            while running:
                running = self._tick(running, steps, deadline)
        finally:
            if deadline is not None:
                deadline.__exit__(None, None, None)
            for i, ep in enumerate(self.episodes):     # an interrupt: give every data back
                if ep is not None and self.results[i] is None:
                    ep.world.give_back(ep.data)
        return self.results     # type: ignore[return-value]

    def _start(self) -> list[int]:
        """Each episode built and placed (a collision at the start pose ends it before the planner
        sees it), then one ``reset_batch`` for those that started; their indexes."""
        started = []
        for i, req in enumerate(self.requests):
            try:
                ep = Episode(req.scenario, None, req.seed, req.max_ticks, stuck_after=req.stuck_after)
            except Exception as exc:
                self.results[i] = exc
                continue
            self.episodes[i] = ep
            if self._goes_on(i, ep.place):
                started.append(i)
        if not started:
            return []
        self.ids = {i: k for k, i in enumerate(started)}
        t0 = perf_counter()
        try:
            call_planner(self.planner.reset_batch, [self.episodes[i].scenario for i in started], None)
        except (Exception, PlannerTimeout) as exc:
            share = (perf_counter() - t0) / len(started)
            for i in started:
                ep = self.episodes[i]
                ep.t_planner += share
                ep.failure = SubjectFailure(f"planner.reset_batch raised {type(exc).__name__}: {exc}", 0, 0.0,
                                            planner_traceback(exc))
                self._finish(i, "subject-error")
            return []
        share = (perf_counter() - t0) / len(started)
        for i in started:
            self.episodes[i].t_planner += share
        return started

    def _form_cohorts(self, running: list[int]) -> None:
        """Group the started episodes that can observe together (cohort.py); the rest observe alone."""
        from .cohort import Cohort, cohort_key

        groups: dict[tuple, list[int]] = {}
        self.alone: set[int] = set()
        for i in running:
            key = cohort_key(self.episodes[i]) if COHORTS else None
            if key is None:
                self.alone.add(i)
            else:
                groups.setdefault(key, []).append(i)
        self.cohorts = []
        self.cohort_of: dict[int, tuple[int, int]] = {}     # batch index -> (cohort number, position)
        for members in groups.values():
            if len(members) == 1:
                self.alone.update(members)
                continue
            self.cohorts.append((Cohort(members, [self.episodes[i] for i in members]),
                                 {i: j for j, i in enumerate(members)}))
            for j, i in enumerate(members):
                self.cohort_of[i] = (len(self.cohorts) - 1, j)

    def _tick(self, running: list[int], steps: dict, deadline: TickDeadline | None) -> list[int]:
        """One control tick of the running episodes; those still running after it."""
        seen: list[tuple[int, tuple, Any]] = []
        now = set(running)
        for cohort, position in self.cohorts:
            mine = [position[i] for i in cohort.members if i in now]
            if mine:
                seen += cohort.observe(mine, self._finish, self._fail)
        for i in running:
            if i in self.alone:
                item = self._observe(i, steps)
                if item is not None:
                    seen.append(item)
        if not seen:
            return []
        seen.sort(key=lambda item: item[0])
        live = [i for i, _, _ in seen]
        answers = self._act(live, [obs for _, _, obs in seen])
        still = []
        physics: dict[int, list] = {}       # cohort number -> (position, setpoint) to step together
        for (i, state, obs), answer in zip(seen, answers):
            setpoint = self._setpoint(i, answer, state, obs)
            if setpoint is None:
                continue
            where = self.cohort_of.get(i)
            if where is not None:
                physics.setdefault(where[0], []).append((where[1], setpoint))
                continue
            MUJOCO_WARNINGS.clear()
            if self._goes_on(i, steps[i][2], setpoint):
                still.append(i)
        for c, items in physics.items():
            still += self.cohorts[c][0].step(items, self._finish, self._fail)
        still.sort()
        return still

    def _observe(self, i: int, steps: dict) -> tuple[int, tuple, Any] | None:
        """Episode ``i`` observes on its own (``Episode.observe``, its faults, its safety check):
        (i, true state, what the planner sees), or None when that ended it."""
        ep = self.episodes[i]
        try:
            state, obs = ep.observe()
            if ep.faults is not None:
                obs = ep.faults.observation(ep.tick, state, obs)
            steps[i][0](state)
        except EpisodeOver as over:
            self._finish(i, over.reason)
            return None
        except Exception as exc:
            self._fail(i, exc)
            return None
        return i, state, obs

    def _setpoint(self, i: int, answer: Any, state: tuple, obs: Any) -> tuple[float, float, float] | None:
        """Episode ``i``'s actuator setpoint from the planner's ``answer`` (validated, within its
        drive's limits, through its command faults), recorded; None when the answer ended it."""
        ep = self.episodes[i]
        try:
            if type(answer) is _Failed:       # the call failed: every episode of it
                ep._planner_failed(obs, answer.message, answer.traceback)
            cmd = validate_command(answer)
            if type(cmd) is str:
                ep._planner_failed(obs, cmd.replace("planner.act returned", "planner.act_batch returned "
                                                    "for this episode", 1))
            setpoint = ep.drive.setpoint(*cmd)
            if ep.faults is not None:
                setpoint = ep.faults.applied(setpoint)
            ep.record(state[0], setpoint)
        except EpisodeOver as over:
            self._finish(i, over.reason)
            return None
        except Exception as exc:
            self._fail(i, exc)
            return None
        return setpoint

    def _act(self, live: list[int], observations: list[Any]) -> list[Any]:
        """One ``act_batch`` call under the deadline (the limit times the call's episodes): the
        answers, or for every episode of the call (message, traceback) when the call failed."""
        ids = [self.ids[i] for i in live]
        planner = self.planner
        deadline = self._deadline
        t0 = perf_counter()
        failed: _Failed | None = None
        try:
            if deadline is not None:
                deadline.scale = len(live)
            answers = call_planner(lambda args: planner.act_batch(*args), (ids, observations), deadline)
        except (Exception, PlannerTimeout) as exc:
            failed = _Failed(f"planner.act_batch raised {type(exc).__name__}: {exc}", planner_traceback(exc))
        share = (perf_counter() - t0) / len(live)
        for i in live:
            self.episodes[i].t_planner += share
        if failed is None:
            unordered = isinstance(answers, (Mapping, AbstractSet, str, bytes))   # listing a dict gives its keys
            try:
                n = -1 if unordered else len(answers)
            except Exception:
                n = -1
            if n != len(live):
                got = f"{n} commands" if n >= 0 else f"{type(answers).__name__} {_short(answers)}"
                failed = _Failed(f"planner.act_batch returned {got} for {len(live)} episodes; expected "
                                 f"{'a list of ' if unordered else ''}one command per id, in the order of ids")
        if failed is None:
            try:
                return list(answers)
            except Exception as exc:
                failed = _Failed(f"planner.act_batch's answer cannot be read as a list: {type(exc).__name__}: "
                                 f"{exc}", planner_traceback(exc))
        return [failed] * len(live)

    # ------------------------------------------------------------ an episode ends

    def _goes_on(self, i: int, step: Any, *args: Any) -> bool:
        """Run ``step(*args)`` for episode ``i``: False when it ended the episode (its EpisodeOver
        finishes it, any other exception fails it alone), True when the episode goes on."""
        try:
            step(*args)
        except EpisodeOver as over:
            self._finish(i, over.reason)
            return False
        except Exception as exc:
            self._fail(i, exc)
            return False
        return True

    def _finish(self, i: int, reason: str) -> None:
        ep = self.episodes[i]
        ep.end = reason
        try:
            if ep.warn_count.any():   # the authoritative per-data counters, as Episode.run
                raise SimulationDivergedError(divergence_message(ep.scenario, ep.data, ep.i * ep.dt))
        except Exception as exc:
            self.results[i] = exc
        finally:
            ep.world.give_back(ep.data)
        if self.results[i] is None:
            self.results[i] = ep.result()

    def _fail(self, i: int, exc: Exception) -> None:
        ep = self.episodes[i]
        if isinstance(exc, mujoco.FatalError):   # as Episode.run: the cause and the fix; the data dropped
            self.results[i] = SimulationFatalError(fatal_message(ep.scenario, ep.model, exc, ep.i * ep.dt))
            return
        self.results[i] = exc
        ep.world.give_back(ep.data)
