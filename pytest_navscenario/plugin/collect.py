"""Collection: scenario YAML files become pytest items, one item per file, named after the scenario.

A file is collected when its name matches ini ``nav_scenario_glob`` (default ``*.yaml *.yml``) AND
it looks like a scenario (a YAML mapping with ``version`` and ``mission`` keys); any other YAML
file is left alone. Collection only loads and validates the file: nothing is simulated.
A file that looks like a scenario but is invalid becomes a collection error quoting the
ScenarioError (file, line, field, fix); the other files are still collected and run.
"""
from __future__ import annotations

import dataclasses
import fnmatch
import os
import re
import shlex
from pathlib import Path
from typing import Any, Iterator

import pytest

from ..core.errors import NavScenarioError, ScenarioError
from ..core.seeds import repeat_seed
from .state import STATE_KEY, get_state

_TOP_KEY = re.compile(r"^(version|mission)\s*:", re.MULTILINE)


def _fallback_looks_like(data: str | bytes) -> bool:
    text = data.decode("utf-8", "replace") if isinstance(data, bytes) else data
    return {m.group(1) for m in _TOP_KEY.finditer(text)} == {"version", "mission"}


def looks_like_scenario_text(text: str | bytes) -> bool:
    """True if ``text`` is (meant to be) a scenario: the loader's check, or top-level keys."""
    try:
        from ..scenario.loader import looks_like_scenario
    except ImportError:
        return _fallback_looks_like(text)
    try:
        return bool(looks_like_scenario(text))
    except Exception:
        return _fallback_looks_like(text)


def collect_file(file_path: Path, parent: pytest.Collector) -> "ScenarioFile | None":
    """The ``pytest_collect_file`` implementation (called for every file pytest visits)."""
    state = get_state(parent.config)
    name = file_path.name
    if not any(fnmatch.fnmatch(name, g) for g in state.settings.globs):
        return None
    if _named_on_command_line(parent.config, file_path):   # the loader says what is wrong with it
        state.scenario_folders.add(str(file_path.parent))
        return ScenarioFile.from_parent(parent, path=file_path)
    try:
        data = file_path.read_bytes()
    except OSError:
        return None  # unreadable: pytest cannot use it either; nothing suggests it is a scenario
    if not looks_like_scenario_text(data):
        from .skipped import add_skipped, why_not_a_scenario
        reason = why_not_a_scenario(data)
        if reason is not None:
            add_skipped(state, file_path, reason)
        return None
    state.scenario_folders.add(str(file_path.parent))
    return ScenarioFile.from_parent(parent, path=file_path)


_NAMED_KEY = pytest.StashKey[frozenset]()


def _named_on_command_line(config: pytest.Config, path: Path) -> bool:
    """True if ``path`` is a file given on the command line (``pytest s/x.yaml``, or ``::name``)."""
    named = config.stash.get(_NAMED_KEY, None)
    if named is None:        # called for every file pytest visits: the arguments' paths once
        base = config.invocation_params.dir
        named = frozenset(os.path.normcase(os.path.abspath(os.path.join(base, arg.split("::")[0])))
                          for arg in config.args)
        config.stash[_NAMED_KEY] = named
    return os.path.normcase(os.path.abspath(path)) in named


def output_folders(config: pytest.Config) -> list[Path]:
    """The folders this plugin writes in this run: artifacts, plots, bags (issue 15: a copy of a
    failing scenario in the artifacts must not come back as an item in the next ``pytest .``)."""
    state = config.stash.get(STATE_KEY, None)
    if state is None:
        return []
    folders = [state.settings.artifacts] if state.settings.artifacts is not None else []
    from .bags import _STATE as BAG_KEY
    from .reports import DEFAULT_PLOTS_DIR, REPORT_KEY
    bags = config.stash.get(BAG_KEY, None)
    if bags is not None:
        folders.append(bags.folder)
    report = config.stash.get(REPORT_KEY, None)
    if report is not None and report.settings.plots_dir is not None:
        folders.append(report.settings.plots_dir)
    elif state.settings.artifacts is None:
        folders.append(Path(config.rootpath) / DEFAULT_PLOTS_DIR)
    return [Path(os.path.abspath(f)) for f in folders]


_OUTPUTS_KEY = pytest.StashKey[list]()


def ignore_output_folder(collection_path: Path, config: pytest.Config) -> bool | None:
    """``pytest_ignore_collect``: True for an output folder of the plugin, None (no opinion) else.

    Never ignored: a folder holding the rootdir, the current folder or a path named on the command
    line (``--nav-artifacts=.`` must not hide the project; ``pytest nav-artifacts/x/scenario.yaml``
    runs that file), nor one holding or inside the frozen regressions' folder (--navsearch-out)."""
    folders = config.stash.get(_OUTPUTS_KEY, None)
    if folders is None:       # called for every path pytest visits: work the folders out once
        folders = output_folders(config)
        if config.stash.get(STATE_KEY, None) is not None:
            config.stash[_OUTPUTS_KEY] = folders
    path = Path(os.path.abspath(collection_path))
    if path not in folders:
        return None
    regressions = _regressions_folder(config)
    named = [Path(os.path.abspath(Path(config.invocation_params.dir) / a.split("::")[0]))
             for a in config.args]
    keep = [Path(config.rootpath), Path(config.invocation_params.dir), regressions, *named]
    if any(k == path or path in k.parents for k in keep):
        return None
    return True


def _regressions_folder(config: pytest.Config) -> Path:
    """--navsearch-out, else its ini twin (either name), else the default folder."""
    from .search import DEFAULT_OUT
    names = ("navsearch_out", "nav_regressions_dir")
    for name in names:
        cli = config.getoption(name, None)
        if cli:
            return Path(os.path.abspath(Path(config.invocation_params.dir) / os.path.expanduser(str(cli))))
    for name in names:
        try:
            raw = str(config.getini(name) or "").strip()
        except ValueError:     # not an ini option in this version
            continue
        if raw:
            return Path(os.path.abspath(Path(config.rootpath) / os.path.expanduser(raw)))
    return Path(os.path.abspath(Path(config.rootpath) / DEFAULT_OUT))


def rel_path(config: pytest.Config, path: Path) -> str:
    """``path`` relative to the rootdir with posix separators (absolute if outside it)."""
    text, root = str(path), str(config.rootpath)
    if text.startswith(root) and text[len(root):len(root) + 1] == os.sep and ".." not in text:
        return text[len(root) + 1:].replace(os.sep, "/")    # the common case, without pathlib
    try:
        return path.relative_to(config.rootpath).as_posix()
    except ValueError:
        return path.as_posix()


class ScenarioFile(pytest.File):
    """One scenario YAML file; yields exactly one ScenarioItem."""

    def collect(self) -> Iterator["ScenarioItem"]:
        from ..scenario.loader import load_scenario

        try:
            scenario = load_scenario(self.path, family="")  # "": the YAML has no family of its own
        except BaseException:
            get_state(self.config).bad_scenario_files += 1
            raise
        name = scenario.name or self.path.stem
        if "::" in name or not name.strip():
            get_state(self.config).bad_scenario_files += 1
            raise ScenarioError(f"scenario name {name!r} cannot be a pytest item name ('::' separates "
                                f"node ids)", path=str(self.path), field="name",
                                hint="use letters, digits, '-', '_' or '.', e.g. boxes1-narrow")
        family_from_folder = not scenario.family
        if family_from_folder:  # may become the folder's path: see separate_families
            scenario = dataclasses.replace(scenario, family=self.path.parent.name)
        shared = get_state(self.config).settings.requirements
        if shared is not None:  # --nav-requirements: the suite's requirements beside the scenario's own
            from ..scenario.requirement_reading import with_shared
            scenario = with_shared(scenario, shared)
        model = get_state(self.config).settings.sensor_model
        if model:   # --nav-sensor-model: a lidar noise model for scenarios that declare none
            from ..scenario.sensor_model import with_sensor_model
            scenario = with_sensor_model(scenario, model)
        repeats = get_state(self.config).settings.repeat
        provenance = scenario.provenance or {}
        _warn_other_subject(provenance, get_state(self.config).subject)
        if repeats > 1 and "confirmation" in provenance:   # a frozen failure: does it still hold?
            get_state(self.config).frozen[(rel_path(self.config, self.path), name)] = dict(provenance)
        for repeat in range(repeats):
            item = ScenarioItem.from_parent(self, name=name if repeats == 1 else f"{name}[r{repeat}]",
                                            scenario=scenario, repeat=repeat)
            item.family_from_folder = family_from_folder
            for mark in scenario.marks:
                item.add_marker(getattr(pytest.mark, mark.name)(*mark.args, **dict(mark.kwargs)))
            if scenario.family:
                item.extra_keyword_matches.add(scenario.family)
            yield item

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> Any:
        exc = excinfo.value
        if isinstance(exc, ScenarioError):
            where = "" if exc.path else f"{rel_path(self.config, self.path)}: "
            return f"invalid scenario file: {where}{exc}"
        if isinstance(exc, (NavScenarioError, OSError, UnicodeDecodeError)):
            return f"cannot load scenario file {rel_path(self.config, self.path)}: {exc}"
        return super().repr_failure(excinfo)


def separate_families(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Keep families from different folders of the same name apart.

    A scenario without ``family:`` in its YAML belongs to the family named after its folder. When
    the collected items come from two or more folders of the same name (``scenarios/`` and
    ``examples/scenarios/``), each of those families is named by its folder's path relative to
    the rootdir instead ("scenarios", "examples/scenarios"), so that the summary, the results
    file and comparisons do not merge them. Called before ``-k``/``-m`` deselect items, so the
    names do not depend on them (they do depend on which folders were collected together).
    """
    folders: dict[str, set[Path]] = {}
    ours = [item for item in items if isinstance(item, ScenarioItem) and item.family_from_folder]
    for item in ours:
        folders.setdefault(item.scenario.family, set()).add(item.path.parent)
    shared = {name for name, paths in folders.items() if len(paths) > 1}
    for item in ours:
        if item.scenario.family in shared:
            family = rel_path(config, item.path.parent)
            if family == ".":
                family = item.path.parent.name
            item.scenario = dataclasses.replace(item.scenario, family=family)
            item.extra_keyword_matches.add(family)


class ScenarioFailed(Exception):
    """Raised by ScenarioItem.runtest when the outcome is not success (carries the result)."""

    def __init__(self, result: Any):
        from ..verdict.result import headline
        super().__init__(headline(result.outcome, result.message))
        self.result = result


def _fmt(value: Any, unit: str = "", digits: int = 3) -> str:
    if value is None:
        return "n/a"
    try:
        value = float(value)
    except (TypeError, ValueError):
        return str(value)
    if value != value or value in (float("inf"), float("-inf")):
        return "n/a"
    return f"{value:.{digits}f}{unit}"


def _culprit_line(result: Any) -> list[str]:
    """The clearance that explains the outcome, when the minimum is to another obstacle: a robot
    stopped for a person that passed nearer a wall (metrics.culprit_clearance)."""
    if not len(result.trajectory.t):
        return []
    from ..verdict.metrics import culprit_clearance
    found = culprit_clearance(result)
    if found is None:
        return []
    name, dist, time = found
    why = "the safety stop was for it" if result.safety_stop is not None else "the collision was with it"
    return [f"  clearance to {name!r}: {_fmt(dist, ' m')} at t={_fmt(time, ' s', 2)} ({why}; the minimum "
            f"above is to another obstacle)"]


def _field_line(scenario: Any, field: str) -> int | None:
    """The line of ``field`` in the scenario's file (read again only for this error), or None."""
    from ..scenario.yaml_tree import field_line

    try:
        with open(scenario.source, encoding="utf-8") as fh:
            return field_line(fh.read(), field)
    except (OSError, TypeError, UnicodeDecodeError):
        return None


class OtherSubjectWarning(UserWarning):
    """A frozen failure runs against another subject than the one its provenance names."""


def _warn_other_subject(provenance: dict, subject: Any) -> None:
    """A pytest warning (shown with the file in the warnings summary; the same text for every file,
    so pytest lists them under one message) when a frozen failure of the search runs against
    another subject than the one it was found against: against that one it is only a layout,
    which it may well pass, and a run that looks like a fixed regression may be no such thing."""
    import warnings

    found = provenance.get("subject")
    if not found or "outcome" not in provenance or subject.spec is None or str(found) == subject.spec:
        return
    warnings.warn(OtherSubjectWarning(
        f"frozen failure found against subject {found!r} runs against {subject.spec!r} (from "
        f"{subject.origin}): against another subject it is only a layout, which it may pass; to re-run "
        f"the failure as found, add --nav-subject={found}"), stacklevel=2)


def _warn_left_running(where: str, left: tuple[str, ...]) -> None:
    """A pytest warning (shown with the item in the warnings summary) for the processes the
    planner started in this episode and left running."""
    import warnings

    from ..core.processes import LeftRunningWarning
    warnings.warn(LeftRunningWarning(
        f"{where}: the planner left {len(left)} process(es) running after its episode ({'; '.join(left)}); "
        f"they are ended when the run ends. A planner should end what it starts (e.g. in __del__ or an "
        f"atexit handler), or keep one helper for all its episodes."), stacklevel=2)


class ScenarioItem(pytest.Item):
    """One episode of one scenario against the session's subject; passes iff the outcome is success."""

    def __init__(self, *, scenario: Any, repeat: int = 0, **kwargs: Any):
        super().__init__(**kwargs)
        self.scenario = scenario
        self.repeat = repeat          # --nav-repeat index: 0 .. N-1
        self.family_from_folder = False  # the family is the folder's (no family: in the YAML)
        self.nav_result: Any = None   # the EpisodeResult, until the call report has taken it
        self.nav_pending: Any = None  # with an executor: the submitted episode (dispatch.Pending)
        self.nav_checked = 0.0        # s the feasibility check took at setup (counted in the episode's)

    @property
    def rel_path(self) -> str:
        return rel_path(self.config, self.path)

    def setup(self) -> None:
        """A scenario no planner can pass (or that passes without one) is an error of this item,
        not a failure of the planner (issue 15): verdict/feasibility.py. Its shortest path is the
        one the metrics need (cached), so its time is counted in the episode's. With an executor
        the job asked the worker (``check_feasible``): this waits for what came back."""
        pending = self.nav_pending
        if pending is not None:
            from ..dispatch.jobs import Impassable
            outcome = pending.outcome()
            reason, field = (outcome.reason, outcome.field) if isinstance(outcome, Impassable) else (None, None)
        else:
            from ..harness.runner import check_feasibility
            found, self.nav_checked = check_feasibility(self.scenario)
            reason, field = (str(found), found.field) if found is not None else (None, None)
        if reason is not None:
            self.nav_pending = None
            from ..core.errors import ImpassableScenarioError
            line = _field_line(self.scenario, field) if field else None
            raise ImpassableScenarioError(f"{self.rel_path}{f':{line}' if line else ''}: {reason}")

    def episode_job(self, keep_trajectory: str) -> Any:
        """This item's episode as a dispatch job (what runtest runs in place without an
        executor), its feasibility checked by whoever runs it."""
        import os

        from ..dispatch.jobs import EpisodeJob

        state = get_state(self.config)
        return EpisodeJob(self.scenario, state.subject.runner_arg,
                          seed=repeat_seed(state.settings.seed, self.repeat),
                          tick_limit=state.settings.tick_limit, keep_trajectory=keep_trajectory,
                          cwd=os.getcwd(), reset_timeout=state.settings.reset_timeout, check_feasible=True)

    def runtest(self) -> None:
        try:
            result = self._episode()
        except Exception as exc:
            # The episode never finished (its worker died 3 times, ...): the item still gets a
            # record (subject-error, ``error`` says what ended it) and counts in the rates; the
            # exception stays the item's failure.
            from ..harness.runner import effective_seed, unfinished_result

            state = get_state(self.config)
            seed = effective_seed(self.scenario.simulation.seed, repeat_seed(state.settings.seed, self.repeat))
            self.nav_result = unfinished_result(self.scenario, exc, seed=seed,
                                                subject=state.subject.spec or state.subject.label)
            raise
        self.nav_result = result
        if result.left_running:
            _warn_left_running(self.rel_path, result.left_running)
        m = result.metrics
        self.user_properties.extend([
            ("nav_outcome", result.outcome.value),
            ("nav_message", result.message),
            ("nav_min_clearance", _fmt(m.min_clearance, digits=4)),
            ("nav_min_clearance_obstacle", m.min_clearance_obstacle),
            ("nav_path_efficiency", _fmt(m.path_efficiency, digits=4)),
            ("nav_path_length", _fmt(m.path_length, digits=4)),
            ("nav_duration", _fmt(m.duration, digits=3)),
            ("nav_subject", result.subject),
            ("nav_seed", str(result.seed)),
            ("nav_repeat", str(self.repeat)),
        ])
        for req in result.requirements:     # issue 34: each requirement's robustness (< 0: violated)
            self.user_properties.append((f"nav_requirement_{req.name}", _fmt(req.robustness, digits=4)))
        if not result.passed:
            raise ScenarioFailed(result)

    def _episode(self) -> Any:
        """This item's EpisodeResult: from its executor, or run here."""
        pending, self.nav_pending = self.nav_pending, None
        if pending is not None:   # submitted at the start of the run loop (an executor)
            return pending.result()
        from ..harness.runner import add_check_time, run_scenario

        state = get_state(self.config)
        result = add_check_time(run_scenario(self.scenario, state.subject.runner_arg,
                                             seed=repeat_seed(state.settings.seed, self.repeat),
                                             tick_limit=state.settings.tick_limit,
                                             reset_timeout=state.settings.reset_timeout), self.nav_checked)
        self.nav_checked = 0.0
        return result

    def reproduce_command(self) -> str:
        """The command line that re-runs exactly this item with the same subject and seed."""
        state = get_state(self.config)
        parts = ["pytest", shlex.quote(self.nodeid)]
        if state.subject.spec is not None and state.subject.origin != "built-in default":
            parts.append(shlex.quote(f"--nav-subject={state.subject.spec}"))
        parts.append(f"--nav-seed={state.settings.seed}")
        if state.settings.repeat > 1:
            parts.append(f"--nav-repeat={state.settings.repeat}")
        cmd = " ".join(parts)
        if Path(self.config.invocation_params.dir) != Path(self.config.rootpath):
            cmd = f"cd {shlex.quote(str(self.config.rootpath))} && {cmd}"
        return cmd

    def _repr_failure_py(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> Any:
        """An error of ours at setup (a scenario no planner can pass) reads as its message, as one
        in the call does (pytest reports setup errors through this, not ``repr_failure``), not as a
        traceback through pytest's and pluggy's frames."""
        if isinstance(excinfo.value, NavScenarioError) and not isinstance(excinfo.value, ScenarioFailed):
            return self.repr_failure(excinfo, style)
        return super()._repr_failure_py(excinfo, style)

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> Any:
        exc = excinfo.value
        if isinstance(exc, ScenarioFailed):
            return self._describe(exc.result)
        if isinstance(exc, NavScenarioError):
            return f"{type(exc).__name__}: {exc}\nreproduce: {self.reproduce_command()}"
        return super().repr_failure(excinfo, style="short")

    def _describe(self, r: Any) -> str:
        m = r.metrics
        from ..verdict.result import headline
        lines = [headline(r.outcome, r.message)]
        if r.collision is not None:
            c = r.collision
            lines.append(f"  collision:     obstacle {c.obstacle!r} at t={_fmt(c.time, ' s', 2)}, contact "
                         f"({_fmt(c.x, '', 2)}, {_fmt(c.y, '', 2)}), depth {_fmt(c.depth, ' m', 4)}")
        if r.safety_stop is not None:
            s = r.safety_stop
            from ..verdict.gaps import is_terrain_face
            from ..verdict.oracle import stop_motion
            what = f"the face of {s.obstacle}" if is_terrain_face(r.scenario, s.obstacle) else f"obstacle {s.obstacle!r}"
            lines.append(f"  safety stop:   predicted hit of {what} at t="
                         f"{_fmt(s.time, ' s', 2)}, "
                         + (f"speed {_fmt(s.speed, ' m/s', 2)}" if not s.speed < 0.005 else stop_motion(s)))
        if r.subject_failure is not None:
            f = r.subject_failure
            lines.append(f"  planner error: {f.message} (tick {f.tick}, t={_fmt(f.time, ' s', 2)})")
        for q in r.requirements:     # issue 34: every requirement, kept or not, with its robustness
            unit = f" {q.unit}" if q.unit else ""
            state = (f"violated first at t={_fmt(q.first_violation, ' s', 2)}" if q.violated and
                     q.first_violation is not None else ("violated" if q.violated else "kept"))
            lines.append(f"  requirement:   {q.name}: {q.spec}: robustness {q.robustness:+.3g}{unit}, {state}")
        obstacle = f" to {m.min_clearance_obstacle!r}" if m.min_clearance_obstacle else ""
        if m.min_clearance == float("inf"):   # one form in the terminal (outcomes-metrics.md)
            lines.append("  min clearance: none (no obstacles)")
        else:
            lines.append(f"  min clearance: {_fmt(m.min_clearance, ' m')}{obstacle} at t="
                         f"{_fmt(m.min_clearance_time, ' s', 2)}, robot at ({_fmt(m.min_clearance_x, '', 2)}, "
                         f"{_fmt(m.min_clearance_y, '', 2)})")
        lines += _culprit_line(r)
        lines.append(f"  duration:      {_fmt(m.duration, ' s', 2)} (timeout "
                     f"{_fmt(r.scenario.mission.timeout, ' s', 1)}), path {_fmt(m.path_length, ' m', 2)}, "
                     f"efficiency {_fmt(m.path_efficiency, '', 2)}, goal error "
                     f"{_fmt(m.goal_position_error, ' m', 2)}")
        version = f" {r.subject_version}" if r.subject_version else ""
        lines.append(f"  subject:       {r.subject}{version}, episode seed {r.seed}")
        lines.append(f"  scenario:      {self.rel_path}")
        lines += _unreproduced(r)
        from .artifacts import item_dir
        folder = item_dir(self.config, self.nodeid)
        if folder is not None:
            lines.append(f"  artifacts:     {folder}")
        lines.append(f"reproduce: {self.reproduce_command()}")
        if r.subject_failure is not None and r.subject_failure.traceback:
            lines.append("planner traceback:")
            lines.append(r.subject_failure.traceback.rstrip())
        return "\n".join(lines)

    def reportinfo(self) -> tuple[Path, int, str]:
        # line 0 (shown as 1): pytest needs a line for skip reports
        return self.path, 0, f"scenario {self.name} ({self.scenario.family or 'no family'})"


def _unreproduced(r: Any) -> list[str]:
    """For a frozen failure whose outcome or message is not the one its provenance recorded: what
    was recorded, and the MuJoCo release it was recorded under when that is not this run's."""
    from ..core.versions import other_mujoco

    prov = r.scenario.provenance or {}
    if "outcome" not in prov or (prov.get("outcome") == r.outcome.value and prov.get("message") == r.message):
        return []
    lines = [f"  recorded:      {prov.get('outcome')}: {prov.get('message') or ''} (its provenance; this run "
             f"did not reproduce it)"]
    note = other_mujoco(prov.get("mujoco_version"))
    if note:
        lines.append(f"  MuJoCo:        {note}; re-run its search to record it under this release")
    return lines
