"""``navscenario run`` (scenario files, one subject: each one's outcome, message and metrics; several
files run in batches when the subject implements the batch protocol) and ``navscenario
check-planner`` (check a planner against the protocol).

Exit codes: 0 success / check passed, 1 failing outcome / check found problems, 2 usage or
input error (bad scenario file, subject that cannot be loaded; printed by cli.main).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path
from typing import Any

from ..sim.deadline import DEFAULT_TICK_LIMIT
from ..subjects.loading import BUILTIN_SUBJECTS, DEFAULT_SUBJECT

HUNG_TICK = 10.0   # = harness.conformance.HUNG_TICK (not imported: `run --help` stays light)

_SUBJECT_HELP = (f"planner under test: a built-in name ({', '.join(sorted(BUILTIN_SUBJECTS))}), "
                 f"'package.module:Attribute' (a class or zero-argument factory), "
                 f"'exec:PROGRAM ARGS' (an external process) or a learned policy's model file "
                 f"'path/to/policy.onnx'; default {DEFAULT_SUBJECT}")


def add_arguments_run(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", metavar="SCENARIO.yaml", nargs="+",
                   help="scenario YAML file(s); several run one after the other, in batches when "
                        "the subject implements the batch protocol (see --batch); of several, a file "
                        "that cannot be loaded is reported as that file's error and the others run")
    p.add_argument("--subject", "-s", default=DEFAULT_SUBJECT, metavar="SPEC", help=_SUBJECT_HELP)
    p.add_argument("--seed", type=int, default=None, metavar="N",
                   help="base seed (integer >= 0) mixed with the scenario's simulation.seed "
                        "(default: the scenario's own)")
    p.add_argument("--tick-limit", type=float, default=DEFAULT_TICK_LIMIT, metavar="SECONDS",
                   help=f"a planner tick slower than this is a subject error (default {DEFAULT_TICK_LIMIT:g}, "
                        f"as pytest's --nav-tick-limit, so that run gives a pytest item's outcome; 0: no "
                        f"limit, e.g. to step through act() in a debugger)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object instead of text (several files: a list of them)")
    p.add_argument("--batch", default="auto", metavar="N",
                   help="with several files, episodes run together in lockstep with one planner call a "
                        "tick, when the subject implements the batch protocol (the built-in dwa does): "
                        "auto (default: batches of 16), N (at most N), 1 or off (each alone); the "
                        "results are the same either way")
    p.add_argument("--batch-engine", default="cpu", choices=("cpu", "warp"),
                   help="what steps a batch: cpu (default: MuJoCo in this process, each trajectory "
                        "bit-identical to running it alone) or warp (MuJoCo Warp on the GPU, or Warp's "
                        "CPU kernels without one: the optional extra pytest-navscenario[gpu]; "
                        "trajectories within a tolerance of the CPU's, not bit for bit; scenarios it "
                        "cannot simulate (terrain, bodies that ride the ground, 3D lidars) run alone "
                        "on the CPU, said in the last line); one file with warp is a batch of one on it. "
                        "See docs/how-to/gpu-batches.md")


def _engine(name: str):
    """The batch engine called ``name`` (sim/batching/batch.py); NavScenarioError saying how to install
    the warp engine's extra when it is missing."""
    from ..sim.batching.batch import batch_engine
    try:
        return batch_engine(name)
    except ValueError as exc:
        from ..core.errors import NavScenarioError
        raise NavScenarioError(f"--batch-engine {name}: {exc}") from None


def _batch_size(raw: str) -> int:
    value = str(raw).strip().lower()
    if value in ("", "auto"):
        from ..harness.batch import DEFAULT_BATCH
        return DEFAULT_BATCH
    if value in ("off", "no", "none"):
        return 1
    try:
        n = int(value)
    except ValueError:
        n = 0
    if n < 1:
        from ..core.errors import NavScenarioError
        raise NavScenarioError(f"--batch {raw!r}: expected auto, a whole number of episodes >= 1, or off")
    return n


# what an infinite metric means, in words (the terminal's form; JSON writes null, Python keeps inf)
UNDEFINED = {"min_clearance": "none (no obstacles)", "min_obstacle_gap": "none (fewer than 2 obstacles)"}


def _metrics_lines(metrics: Any) -> list[str]:
    units = {"min_clearance": "m", "min_clearance_time": "s", "min_clearance_x": "m",
             "min_clearance_y": "m", "min_obstacle_gap": "m", "path_length": "m",
             "shortest_path_length": "m", "max_deviation": "m", "mean_deviation": "m",
             "duration": "s", "mean_speed": "m/s", "goal_position_error": "m",
             "goal_yaw_error": "deg", "smoothness": "m/s^3", "angular_smoothness": "rad/s^2",
             "reference_mean_deviation": "m", "reference_max_deviation": "m", "max_pitch": "deg",
             "max_roll": "deg", "climb": "m"}
    rows = []
    for key, value in metrics.as_dict().items():
        if isinstance(value, float):
            if math.isnan(value) and key.startswith("reference_"):
                continue
            if math.isfinite(value):
                rows.append(f"  {key:24s} {value:.3f} {units.get(key, '')}".rstrip())
            else:   # the terminal's one form of an empty or undefined value (outcomes-metrics.md)
                rows.append(f"  {key:24s} {UNDEFINED.get(key, 'n/a') if value > 0 else 'n/a'}")
        else:
            rows.append(f"  {key:24s} {value}")
    return rows


def _json_safe(value: Any) -> Any:
    """Strict JSON, as the results file writes it: every non-finite float (an empty minimum
    clearance's inf as much as an undefined NaN) becomes null (docs/reference/outcomes-metrics.md)."""
    from ..core.files import json_safe
    return json_safe(value)


def look_in_current_folder(spec: str) -> None:
    """Load a subject's module now, looked up on sys.path, then in the current folder, as
    ``python -m`` would find it (an installed module of the same name wins: core/user_code.py).
    SubjectLoadError (exit 2) when it cannot be found; an ``exec:`` program is left to the run."""
    from ..subjects.loading import load_subject
    if not spec.strip().startswith("exec:"):
        load_subject(spec, project=[os.getcwd()])


def run_run(args: argparse.Namespace) -> int:
    """The files' episodes (``_run_files``); then the processes the planner or the body
    controller started and left running are ended and named on stderr, as pytest does
    (core/processes.py), whether the run ended, failed or was interrupted."""
    try:
        return _run_files(args)
    finally:
        _end_left_running()


def _end_left_running() -> None:
    processes = sys.modules.get("pytest_navscenario.core.processes")   # loaded once an episode ran
    ended = processes.end_left_behind() if processes is not None else []
    if ended:
        shown = [f"pid {p.pid}: {p.command} after {p.episode}" for p in ended[:5]] + (["..."] if len(ended) > 5 else [])
        print(f"navscenario run: ended {len(ended)} process(es) the planner or controller had left running "
              f"({'; '.join(shown)})", file=sys.stderr)


def _run_files(args: argparse.Namespace) -> int:
    from ..scenario.loader import load_scenario
    from ..harness.runner import run_scenario

    files = list(args.scenario)
    batch = _batch_size(args.batch)
    # One file runs alone, unless another engine than the CPU's was asked for: then it is a batch of
    # one on that engine (it was run on the CPU without a word).
    alone = len(files) == 1 and args.batch_engine == "cpu"
    if alone:
        scenarios = [load_scenario(files[0])]
    else:   # each file that cannot load is that file's error; the others run
        scenarios = [_load_or_error(load_scenario, path) for path in files]
    look_in_current_folder(args.subject)
    tick_limit = args.tick_limit or None
    if alone:
        result = run_scenario(scenarios[0], args.subject, seed=args.seed, tick_limit=tick_limit)
        if args.json:
            print(json.dumps(_record(scenarios[0], files[0], result), indent=2, allow_nan=False))
        else:
            _print_result(scenarios[0], files[0], result)
        return 0 if result.passed else 1
    from ..harness.batch import Batching, run_batch

    batching = Batching()
    loaded = [s for s in scenarios if not isinstance(s, Exception)]
    ran = iter(run_batch(loaded, args.subject, seeds=[args.seed] * len(loaded), tick_limit=tick_limit,
                         batch=batch, batching=batching, engine=_engine(args.batch_engine)) if loaded else [])
    results = [s if isinstance(s, Exception) else next(ran) for s in scenarios]
    failed = errors = 0
    records = []
    for scenario, path, result in zip(scenarios, files, results):
        if isinstance(result, Exception):
            errors += 1
            name = Path(path).stem if isinstance(scenario, Exception) else scenario.name
            if args.json:
                records.append({"scenario": name, "file": path, "error": f"{type(result).__name__}: {result}"})
            else:
                print(f"{name} ({path}): error: {result}\n")
            continue
        failed += not result.passed
        if args.json:
            records.append(_record(scenario, path, result))
        else:
            _print_result(scenario, path, result)
            print()
    if args.json:   # one file: its record, as when it runs alone
        print(json.dumps(records[0] if len(files) == 1 else records, indent=2, allow_nan=False))
    else:
        passed = len(files) - failed - errors
        print(f"{len(files)} scenario(s): {passed} passed, {failed} failed" + (f", {errors} error(s)" if errors else "")
              + f"; batches (--batch {args.batch}"
              + (f", --batch-engine {args.batch_engine}" if args.batch_engine != "cpu" else "")
              + f"): {batching.describe()}")
    return 2 if errors else (1 if failed else 0)


def _load_or_error(load: Any, path: str) -> Any:
    """The scenario of ``path``, or the ScenarioError saying why it cannot be loaded."""
    from ..core.errors import ScenarioError
    try:
        return load(path)
    except ScenarioError as exc:
        return exc


def _record(scenario: Any, path: str, result: Any) -> dict[str, Any]:
    record = {
        "scenario": scenario.name, "file": path, "subject": result.subject,
        "subject_version": result.subject_version, "seed": result.seed,
        "outcome": result.outcome.value, "passed": result.passed, "message": result.message,
        "metrics": _json_safe(result.metrics.as_dict()),
        "wall_time": result.wall_time, "timings": result.timings,
    }
    if result.subject_failure is not None and result.subject_failure.traceback:
        record["traceback"] = result.subject_failure.traceback
    return record


def _print_result(scenario: Any, path: str, result: Any) -> None:
    version = f" {result.subject_version}" if result.subject_version else ""
    print(f"{scenario.name} ({path}) with {result.subject}{version}, seed {result.seed}")
    print(f"outcome: {result.outcome.value}")
    print(f"message: {result.message}")
    if result.subject_failure is not None and result.subject_failure.traceback:
        print("planner traceback:\n" + result.subject_failure.traceback.rstrip())
    print("metrics:")
    print("\n".join(_metrics_lines(result.metrics)))
    print(f"wall time: {result.wall_time * 1e3:.1f} ms")


def add_arguments_check_planner(p: argparse.ArgumentParser) -> None:
    p.add_argument("subject", metavar="SPEC", help=_SUBJECT_HELP.replace("; default " + DEFAULT_SUBJECT, ""))
    p.add_argument("--scenario", default=None, metavar="SCENARIO.yaml",
                   help="scenario YAML to check on (default: a short built-in scenario)")
    p.add_argument("--ticks", type=int, default=20, metavar="N",
                   help="control ticks to run, at least 1 (default 20)")
    p.add_argument("--seed", type=int, default=0, metavar="N", help="lidar noise seed (default 0)")
    p.add_argument("--tick-limit", type=float, default=HUNG_TICK, metavar="SECONDS",
                   help=f"stop and report an act() call that takes longer (default {HUNG_TICK:g}, longer "
                        f"than the {DEFAULT_TICK_LIMIT:g} s pytest and navscenario run allow, so that a slow "
                        f"tick is measured and reported, with a warning when it is over {DEFAULT_TICK_LIMIT:g} "
                        f"s, rather than cut short; 0: no limit)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")


def run_check_planner(args: argparse.Namespace) -> int:
    from ..harness.conformance import check_planner

    scenario = None
    if args.scenario:
        from ..scenario.loader import load_scenario
        scenario = load_scenario(args.scenario)
    if args.ticks < 1:
        print("navscenario check-planner: error: --ticks must be at least 1", file=sys.stderr)
        return 2
    look_in_current_folder(args.subject)
    check = check_planner(args.subject, scenario, ticks=args.ticks, seed=args.seed,
                          tick_limit=args.tick_limit if args.tick_limit > 0 else None)
    if args.json:
        print(json.dumps(_json_safe({
            "subject": check.subject, "ok": check.ok, "problems": check.problems,
            "warnings": check.warnings, "ticks": check.ticks,
            "max_tick_time": check.max_tick_time, "median_tick_time": check.median_tick_time}),
            indent=2))
    else:
        print(check)
    return 0 if check.ok else 1
