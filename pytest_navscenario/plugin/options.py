"""Command-line options and their ini twins, and their parsing into one checked ``Settings``.

Precedence: command line, then the ini file (pytest.ini / pyproject.toml / tox.ini / setup.cfg),
then the default. Relative paths given on the command line are relative to the current folder;
relative paths from the ini file are relative to the rootdir. A bad value raises
pytest.UsageError saying which option and how to fix it.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import pytest

from ..sim.deadline import DEFAULT_TICK_LIMIT  # noqa: F401  (re-exported; light: signal, threading, time)

DEFAULT_GLOB = ["*.yaml", "*.yml"]
DEFAULT_SCENARIO_PATHS = ["scenarios"]
DEFAULT_ARTIFACTS = "nav-artifacts"
DEFAULT_RESET_TIMEOUT = 10.0   # = subjects.external.RESET_TIMEOUT (not imported: plugin load stays light)

# (option, ini name, help); used for --help, the ini registration and the docs (docs/reference/options.md).
OPTIONS = (
    ("--nav-subject", "nav_subject",
     "planner under test: 'package.module:Attribute' (a class or zero-argument factory) or a "
     "built-in name (dwa, potential-field), exec:PROGRAM [ARGS] for an external planner, or the "
     "path of a learned policy's .onnx file (with its declaration NAME.policy.yaml beside it). "
     "Default: the built-in 'dwa'."),
    ("--nav-seed", "nav_seed",
     "base seed (integer >= 0) mixed into each scenario's own noise seed; 0 (default) runs each "
     "scenario with its own seed. Shown in the header."),
    ("--nav-results", "nav_results",
     "write every episode's outcome and metrics to this JSON Lines file (for navscenario compare)."),
    ("--nav-artifacts", "nav_artifacts",
     "folder for failing items' artifacts (scenario as run + trajectory CSV), one subfolder per "
     "item; 'none' disables. Default: nav-artifacts under the rootdir."),
    ("--nav-summary", "nav_summary",
     "print the per-family outcome table at the end: yes (default) or no."),
    ("--nav-tick-limit", "nav_tick_limit",
     "seconds one planner tick (act) may take; a slower or hanging planner ends the episode as a "
     "subject-error and the next item runs. Default 1 (as in navscenario run: a hanging planner "
     "cannot stall the suite; navscenario check-planner allows 10 s to measure slow ticks); 0 or "
     "none: no limit."),
    ("--nav-reset-timeout", "nav_reset_timeout",
     "seconds an external (exec:) planner may take to answer reset, its start-up included; after "
     "one reset timed out, the later items of that planner fail at once with the same message. "
     "Default 10."),
    ("--nav-repeat", "nav_repeat",
     "run each scenario N times with different noise seeds (repeat 0 keeps the run's seed) and "
     "report the scenarios whose outcomes differ (flaky) with per-outcome counts. Default 1."),
    ("--nav-ray", "nav_ray",
     "run the episodes as Ray tasks (needs pip install \"pytest-navscenario[ray]\"): ADDRESS 'auto' "
     "starts a local Ray instance (with -n N: N CPUs, else every core), HOST:PORT joins a running cluster "
     "(`ray start --head` prints the address). Items still report one per scenario in the usual "
     "order, with the same results as a serial run. Every node must have pytest-navscenario and "
     "the subject; this is checked before any episode. Default: none."),
    ("--nav-sensor-model", "nav_sensor_model",
     "give every scenario whose lidar declares no noise model this one (the files stay as they are): "
     "'realistic' (a typical 2D lidar: 2 cm Gaussian range noise, 1 % of beams without a return), "
     "or lidar noise keys as key=value,... (noise_sigma, noise_per_metre, dropout, dropout_at_max, "
     "spurious). Recommended for --navsearch, so that a failure must hold under noise. Default: none."),
    ("--nav-workers", "nav_workers",
     "run the scenario items' episodes on N local worker processes started by this pytest "
     "process ('auto': one per core; 0 or 1: in this process, the default). Collection and "
     "reports stay in this process, so it costs less than pytest-xdist's N pytest workers; "
     "-n N on a run of scenario files only (no Python test files) does the same. Items report "
     "one per scenario in the usual order with the results of a serial run."),
    ("--nav-batch", "nav_batch",
     "episodes run together in lockstep, with one planner call per control tick for all of them, "
     "when the subject implements the batch protocol (reset_batch/act_batch; the built-in dwa does): "
     "a search's generations and shrinks, each worker's share of a suite (--nav-workers, -n, "
     "--nav-ray). 'auto' (default): batches of 16; N: at most N; 1 or off: every episode alone. "
     "Results are the same either way, bit for bit; the summary says how episodes were batched."),
    ("--nav-batch-engine", "nav_batch_engine",
     "what steps the batches of --nav-batch: cpu (default: MuJoCo in the worker, each trajectory "
     "bit-identical to running it alone) or warp (MuJoCo Warp on the GPU, or Warp's CPU kernels "
     "without one; needs the optional extra pytest-navscenario[gpu]; trajectories within a "
     "tolerance of the CPU's, not bit for bit; scenarios it cannot simulate, such as terrain and "
     "3D lidars, run alone on the CPU and the summary says so). See docs/how-to/gpu-batches.md."),
    ("--nav-isolate", "nav_isolate",
     "yes: run the episodes in a worker process even without -n or --nav-workers, so that a "
     "planner that ends its process (os._exit, a crash in C code, the out-of-memory killer) fails "
     "only the item it was running (WorkerDied, after 3 tries) and the run goes on and writes its "
     "results; costs the worker's start, about a second. no (default): a serial run simulates in "
     "this process. With -n N, --nav-workers N or --nav-ray the episodes are isolated anyway."),
)


def _typed_ini_supported() -> bool:
    """pytest >= 8.4 knows the ini types "int" and "float" (older ones only strings, bool, lists)."""
    return tuple(int(x) for x in re.findall(r"\d+", pytest.__version__)[:2]) >= (8, 4)


def ini_type(kind: str) -> str:
    """The addini type for an option whose values are ``kind`` ("int", "float", "bool", "string"):
    declared with its real type so that pytest 9's native ``[tool.pytest]`` TOML table takes
    ``nav_repeat = 2`` or ``nav_summary = false``; "string" on a pytest without int/float types."""
    return kind if kind not in ("int", "float") or _typed_ini_supported() else "string"


def ini_value(config: pytest.Config, name: str, expected: str = "") -> object:
    """``config.getini(name)``, with pytest's conversion errors (a non-number in pytest.ini, a
    wrong TOML type) turned into a usage error that names the option and what it expects."""
    try:
        return config.getini(name)
    except (ValueError, TypeError, pytest.UsageError) as exc:  # pytest >= 9.1 raises UsageError
        hint = f"; expected {expected}" if expected else ""
        raise pytest.UsageError(f"ini option {name}: {exc}{hint}") from None


def ini_is_set(config: pytest.Config, name: str) -> bool:
    """Whether the ini file or ``-o name=...`` sets ``name`` (``getini`` cannot tell a set value
    from the default). pytest 9.2 deprecates ``config.inicfg`` (a PytestRemovedIn10Warning on
    every read); the same mapping is ``config._inicfg`` from pytest 9.0, ``config.inicfg`` before."""
    values = getattr(config, "_inicfg", None)
    if values is None:
        values = config.inicfg                                  # pytest 8
    overrides = getattr(config.option, "override_ini", None) or []
    return name in values or any(str(o).split("=", 1)[0].strip() == name for o in overrides)


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("navscenario", "navigation scenarios (pytest-navscenario)")
    helps = {ini: text for _, ini, text in OPTIONS}
    # a metavar shows the accepted values ({a,b}) or a unit (N, SECONDS, PATH, DIR, SPEC, NAME)
    metavars = {"nav_subject": "SPEC", "nav_seed": "N", "nav_results": "PATH", "nav_artifacts": "DIR",
                "nav_summary": "{yes,no}", "nav_tick_limit": "SECONDS", "nav_repeat": "N",
                "nav_reset_timeout": "SECONDS", "nav_ray": "ADDRESS", "nav_workers": "N",
                "nav_batch": "N", "nav_isolate": "{yes,no}", "nav_batch_engine": "{cpu,warp}",
                "nav_sensor_model": "SPEC"}
    for opt, ini, text in OPTIONS:
        group.addoption(opt, dest=ini, default=None, metavar=metavars[ini],   # argparse %-formats help
                        help=(text + f" [ini: {ini}]").replace("%", "%%"))
    parser.addini("nav_subject", helps["nav_subject"], default="")
    parser.addini("nav_seed", helps["nav_seed"], type=ini_type("int"), default=0)
    parser.addini("nav_results", helps["nav_results"], default="")
    parser.addini("nav_artifacts", helps["nav_artifacts"], default=DEFAULT_ARTIFACTS)
    parser.addini("nav_summary", helps["nav_summary"], type="bool", default=True)
    parser.addini("nav_tick_limit", helps["nav_tick_limit"], type=ini_type("float"),
                  default=DEFAULT_TICK_LIMIT)
    parser.addini("nav_repeat", helps["nav_repeat"], type=ini_type("int"), default=1)
    parser.addini("nav_reset_timeout", helps["nav_reset_timeout"], type=ini_type("float"),
                  default=DEFAULT_RESET_TIMEOUT)
    parser.addini("nav_ray", helps["nav_ray"], default="")
    parser.addini("nav_workers", helps["nav_workers"], default="")
    parser.addini("nav_batch", helps["nav_batch"], default="auto")
    parser.addini("nav_batch_engine", helps["nav_batch_engine"], default="cpu")
    parser.addini("nav_isolate", helps["nav_isolate"], type="bool", default=False)
    parser.addini("nav_sensor_model", helps["nav_sensor_model"], default="")
    parser.addini("nav_scenario_glob",
                  "file name patterns of scenario files (space separated); files matching them are "
                  "collected when they are a YAML mapping with 'version' and 'mission' keys "
                  "(default: *.yaml *.yml)", type="args", default=DEFAULT_GLOB)
    parser.addini("nav_scenario_paths",
                  "folders (relative to the rootdir) where seed scenarios are looked up by name, "
                  "e.g. by --navsearch (default: scenarios)", type="linelist",
                  default=DEFAULT_SCENARIO_PATHS)


@dataclass(frozen=True)
class Settings:
    subject_spec: str | None          # None: not configured (hook or built-in default decide)
    seed: int
    results: Path | None
    artifacts: Path | None
    summary: bool
    tick_limit: float | None          # s per planner tick; None: no limit
    repeat: int                       # episodes per scenario (>= 1)
    globs: tuple[str, ...]
    scenario_paths: tuple[Path, ...]
    reset_timeout: float = DEFAULT_RESET_TIMEOUT   # s an exec: planner may take to answer reset
    ray: str | None = None            # --nav-ray: "auto" or "HOST:PORT"; None: no Ray
    sensor_model: "dict[str, float] | None" = None   # --nav-sensor-model: lidar noise keys; None: off
    batch: int = 16                   # --nav-batch: episodes a batch at most (1: no batches)
    batch_engine: str = "cpu"         # --nav-batch-engine: "cpu" or "warp" (sim/batching/batch.py)


_EXPECTED = {"nav_seed": "a whole number >= 0", "nav_summary": "yes or no (true or false)",
             "nav_isolate": "yes or no (true or false)",
             "nav_tick_limit": "seconds >= 0 (0: no limit)",
             "nav_repeat": "a whole number of runs per scenario from 1 to 10000",
             "nav_reset_timeout": "seconds > 0",
             "nav_batch": "auto, a whole number of episodes >= 1, or off",
             "nav_batch_engine": "cpu or warp"}


def option_value(config: pytest.Config, name: str, expected: str = "") -> tuple[str, str, Path]:
    """(value as text, where it came from, base folder for relative paths): the command line first,
    then the ini file. An ini value of a real type (a TOML number or boolean) comes back as its
    text: "3", "2.5", "no". Shared by every feature plugin's option reading."""
    cli = config.getoption(name)
    if cli is not None:
        return str(cli).strip(), f"--{name.replace('_', '-')}", Path(config.invocation_params.dir)
    raw = ini_value(config, name, expected)
    text = ("yes" if raw else "no") if isinstance(raw, bool) else str(raw)
    return text.strip(), f"ini option {name}", Path(config.rootpath)


def resolve_path(raw: str, base: Path) -> Path:
    """A user's path: ``~`` expanded, relative to ``base`` (the invocation folder for the command
    line, the rootdir for the ini file) unless absolute."""
    path = Path(os.path.expanduser(raw))
    return path if path.is_absolute() else base / path


def _value(config: pytest.Config, name: str) -> tuple[str, str, Path]:
    return option_value(config, name, _EXPECTED.get(name, ""))


def read_settings(config: pytest.Config) -> Settings:
    """Parse and check every option; pytest.UsageError on a bad value."""
    subject, _, _ = _value(config, "nav_subject")
    subject = subject.strip() or None

    raw, where, _ = _value(config, "nav_seed")
    try:
        seed = int(raw.strip())
    except ValueError:
        raise pytest.UsageError(f"{where}: seed must be a whole number >= 0, got {raw!r} "
                                f"(e.g. --nav-seed=0, the default)") from None
    if seed < 0 or seed >= 2**63:
        raise pytest.UsageError(f"{where}: seed must be between 0 and 2**63-1, got {seed}")

    raw, where, base = _value(config, "nav_results")
    results = resolve_path(raw.strip(), base) if raw.strip() else None
    if results is not None and results.is_dir():
        raise pytest.UsageError(f"{where}: {raw!r} is a folder; give a file name such as results.jsonl")

    raw, where, base = _value(config, "nav_artifacts")
    raw = raw.strip()
    if raw.lower() in ("none", "no", "off", ""):
        artifacts = None
    else:
        artifacts = resolve_path(raw, base)
        if artifacts.exists() and not artifacts.is_dir():
            raise pytest.UsageError(f"{where}: {raw!r} exists and is not a folder; give a folder "
                                    f"(created if missing) or 'none' to disable artifacts")

    summary = read_yes_no(config, "nav_summary")

    raw, where, _ = _value(config, "nav_tick_limit")
    if raw.strip().lower() in ("none", "off", "no", ""):
        tick_limit = None
    else:
        try:
            tick_limit = float(raw)
        except ValueError:
            tick_limit = -1.0
        if not tick_limit >= 0 or tick_limit == float("inf"):
            raise pytest.UsageError(f"{where}: expected seconds >= 0 (0 or none: no limit), got {raw!r}")
        tick_limit = tick_limit or None

    globs = tuple(g for g in config.getini("nav_scenario_glob") if g.strip())
    if not globs:
        raise pytest.UsageError("ini option nav_scenario_glob is empty; give file name patterns "
                                "such as '*.yaml *.yml'")
    paths = tuple(resolve_path(p.strip(), Path(config.rootpath))
                  for p in config.getini("nav_scenario_paths") if p.strip())
    raw, where, _ = _value(config, "nav_repeat")
    try:
        repeat = int(raw.strip())
    except ValueError:
        repeat = 0
    if not 1 <= repeat <= 10_000:
        raise pytest.UsageError(f"{where}: expected a whole number of runs per scenario from 1 to "
                                f"10000, got {raw!r} (e.g. --nav-repeat=10)")
    raw, where, _ = _value(config, "nav_reset_timeout")
    try:
        reset_timeout = float(raw.strip())
    except ValueError:
        reset_timeout = -1.0
    if not 0 < reset_timeout < float("inf"):
        raise pytest.UsageError(f"{where}: expected seconds > 0 for an external planner to answer "
                                f"reset, got {raw!r} (e.g. --nav-reset-timeout=30)")
    return Settings(subject_spec=subject, seed=seed, results=results, artifacts=artifacts,
                    summary=summary, tick_limit=tick_limit, repeat=repeat, globs=globs,
                    scenario_paths=paths, reset_timeout=reset_timeout, ray=read_ray_address(config),
                    sensor_model=read_sensor_model(config), batch=read_batch(config),
                    batch_engine=read_batch_engine(config))


def read_sensor_model(config: pytest.Config) -> "dict[str, float] | None":
    """--nav-sensor-model / ini nav_sensor_model: lidar noise keys and values, None when off."""
    raw, where, _ = _value(config, "nav_sensor_model")
    if raw.strip().lower() in ("", "none", "off", "no"):
        return None
    from ..scenario.sensor_model import parse_sensor_model   # light: the scenario model only
    try:
        return parse_sensor_model(raw)
    except ValueError as exc:
        raise pytest.UsageError(f"{where}: {exc}") from None


DEFAULT_BATCH = 16   # = harness.batch.DEFAULT_BATCH (not imported: plugin load stays light)


def read_batch(config: pytest.Config) -> int:
    """--nav-batch / ini nav_batch: episodes a batch at most (``auto``: DEFAULT_BATCH; 1 or off: no
    batches). UsageError otherwise."""
    raw, where, _ = _value(config, "nav_batch")
    value = raw.strip().lower()
    if value in ("", "auto"):
        return DEFAULT_BATCH
    if value in ("off", "no", "none", "false"):
        return 1
    try:
        n = int(value)
    except ValueError:
        n = 0
    if not 1 <= n <= 100_000:
        raise pytest.UsageError(f"{where}: expected auto, a whole number of episodes per batch >= 1, or off "
                                f"(1 and off: every episode alone), got {raw!r} (e.g. --nav-batch=32)")
    return n


def read_batch_engine(config: pytest.Config) -> str:
    """--nav-batch-engine / ini nav_batch_engine: "cpu" or "warp"; UsageError for another name, or
    for warp without its packages (found without importing them: the plugin's load stays light)."""
    raw, where, _ = _value(config, "nav_batch_engine")
    name = raw.strip().lower() or "cpu"
    if name not in ("cpu", "warp"):
        raise pytest.UsageError(f"{where}: expected cpu or warp, got {raw!r} (e.g. --nav-batch-engine=warp)")
    if name == "warp":
        import importlib.util
        absent = [dist for dist, module in (("warp-lang", "warp"), ("mujoco-warp", "mujoco_warp"))
                  if importlib.util.find_spec(module) is None]
        if absent:
            raise pytest.UsageError(f"{where}: the warp batch engine needs {' and '.join(absent)}: "
                                    f'pip install "pytest-navscenario[gpu]" (docs/how-to/gpu-batches.md)')
    return name


def read_yes_no(config: pytest.Config, name: str) -> bool:
    """A yes/no option (true/false, on/off, 1/0 too); UsageError otherwise."""
    raw, where, _ = _value(config, name)
    flag = raw.strip().lower()
    if flag in ("yes", "true", "on", "1"):
        return True
    if flag in ("no", "false", "off", "0"):
        return False
    raise pytest.UsageError(f"{where}: expected yes or no, got {raw!r}")


_HOST_PORT = re.compile(r"^(ray://)?[A-Za-z0-9_.\-]+:[0-9]{1,5}$|^(ray://)?\[[0-9A-Fa-f:]+\]:[0-9]{1,5}$")


def read_ray_address(config: pytest.Config) -> str | None:
    """--nav-ray / ini nav_ray: "auto", "HOST:PORT" or None (off). UsageError otherwise."""
    raw, where, _ = _value(config, "nav_ray")
    value = raw.strip()
    if value.lower() in ("", "none", "no", "off"):
        return None
    if value.lower() == "auto":
        return "auto"
    if not _HOST_PORT.match(value):
        raise pytest.UsageError(f"{where}: expected 'auto' (start a local Ray instance) or the address "
                                f"of a running Ray cluster as HOST:PORT (e.g. 10.0.0.5:6379, printed by "
                                f"`ray start --head`), got {raw!r}")
    return value
