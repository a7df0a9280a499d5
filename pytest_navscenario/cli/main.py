"""The ``navscenario`` console script: the subcommand table, the parser and the dispatcher.

Each subcommand lives in its own module, imported only when that subcommand runs (so
``navscenario --help`` stays fast). A subcommand module has ``add_arguments(parser)`` and
``run(args) -> int`` (or ``add_arguments_<name>`` / ``run_<name>`` when one module serves two).
"""
from __future__ import annotations

import argparse
import importlib
import re
import sys
import textwrap

from ..core.errors import NavScenarioError

DESCRIPTION = ("Test mobile-robot navigation planners on YAML scenarios simulated in MuJoCo: run a "
               "scenario, check a planner, compare two runs, or build scenarios from ROS bags, maps "
               "and other tools' worlds.")
EPILOG = ("Run 'navscenario COMMAND --help' for a command's arguments. Whole suites, the failure "
          "search, plots and reports run under pytest: see the pytest-navscenario groups of "
          "'pytest --help'.")


# name -> (module, one-line purpose for the command list)
SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "run": ("pytest_navscenario.cli.run",
            "run scenario files against a planner; print outcomes and metrics"),
    "check-planner": ("pytest_navscenario.cli.run",
                      "check that a planner keeps the protocol: reset/act signatures, finite "
                      "commands, read-only observations, determinism, tick time"),
    "compare": ("pytest_navscenario.cli.compare",
                "compare two results files (A baseline, B candidate), CI gate"),
    "from-bag": ("pytest_navscenario.cli.from_bag",
                 "build a seed scenario from a ROS 1 / ROS 2 bag"),
    "from-map": ("pytest_navscenario.ros.map_import",
                 "build a seed scenario from a map_server occupancy grid"),
    "import": ("pytest_navscenario.ros.world_import",
               "import an Aerialist test or a Gazebo SDF world as a scenario"),
    "policy-template": ("pytest_navscenario.cli.policy",
                        "write the declaration a learned policy (.onnx) needs beside its model, to edit"),
    "schema": ("pytest_navscenario.cli.schema",
               "write the JSON Schema of the scenario format (editor completion and checks, CI)"),
}

# name -> the description at the top of the subcommand's own --help
DESCRIPTIONS: dict[str, str] = {
    "run": "Run scenario files against a planner in the simulation and print each outcome, the "
           "oracle's message and the metrics (several files: in batches, with one planner call a tick "
           "for all, when the planner implements the batch protocol). Exit status: 0 on success, 1 on "
           "a failing outcome, 2 when a scenario or the planner cannot be loaded (or an episode raised).",
    "check-planner": "Run a planner for a few real ticks and report protocol mistakes in plain words: "
                     "missing or mis-declared reset(scenario) / act(obs), exceptions, act() answers "
                     "that are not three finite numbers (vx, vy, wz), writes into the observation's "
                     "arrays, two fresh instances answering differently to the same observations, "
                     "act() calls that hang. Warnings: commands beyond the robot's limits, sideways "
                     "commands for a differential drive, slow ticks, no name/version attribute. "
                     "Exit status: 0 when no problem was found, 1 otherwise.",
    "compare": "Compare two results files written by 'pytest --nav-results=FILE' (A = baseline, "
               "B = candidate): the scenarios B broke and fixed and the metric changes, per family; "
               "optionally as JUnit XML, a bar chart, an HTML report and side-by-side re-runs. With "
               "--fail-on-regression the exit status is 1 when B fails a scenario A passed.",
    "from-bag": "Build a seed scenario from a recorded ROS 1 or ROS 2 bag: poses in the map frame "
                "when the bag has a localiser's map -> odom (else the odometry frame), the goal the "
                "robot was sent (else the last pose), obstacles fitted to the laser scans or 3D point "
                "clouds, the driven path as waypoints or a reference trajectory; --list-events lists "
                "the moments that went wrong and --at cuts the seed around one.",
    "from-map": "Build a seed scenario from a map_server occupancy grid (the map YAML and the image "
                "beside it): occupied cells become box obstacles; start and goal are poses in the "
                "map frame, e.g. --start -2.25,3,90.",
    "schema": "Write the JSON Schema (draft 2020-12) of the scenario format, generated from the loader's own "
              "declarations: every key with its type, range, allowed values, default, unit and description. "
              "Editors with the YAML language server (VS Code's YAML extension and others) then complete "
              "keys and mark mistakes as they are typed; check-jsonschema checks files in CI. Keep it at "
              ".navscenario/scenario-v1.json in your project: the modeline that starts every scenario "
              "file the tool writes names that path (see docs/reference/scenario-format.md).",
    "policy-template": "Write MODEL.policy.yaml beside an ONNX policy: the declaration of the observation it was "
                       "trained on (lidar beams, target, velocity, previous command; clipping and "
                       "normalisation) and of the action it answers (vx, vy, wz or vx, wz; clipping and "
                       "scaling), with every field explained and a layout that adds up to the model's input "
                       "width. The layout is a guess: edit it to your training environment's, then run "
                       "'navscenario check-planner MODEL.onnx'. Needs the onnx extra (onnxruntime).",
    "import": "Import another tool's world as a scenario: an Aerialist test definition or a Gazebo "
              "SDF world (static boxes, cylinders, polylines and STL/OBJ meshes as obstacles, PNG heightmaps as "
              "terrain; anything not carried over is listed). Poses "
              "are x,y,yaw in metres and degrees, e.g. --start -2.25,3,90.",
}


# A value such as -2.25,3,90 (a pose), -1.5 or -1e-3: numbers separated by commas, the first one
# negative. argparse's own pattern only knows a single -N or -N.N, so it takes "-2.25,3,90" for
# an option and fails with "expected one argument".
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
NEGATIVE_NUMBERS = re.compile(rf"^-(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?:\s*,\s*{_NUMBER})*$")


class _HelpFormatter(argparse.HelpFormatter):
    """argparse's formatter, but lines never break inside a hyphenated word (--laser-pose,
    potential-field stay whole, so they can be copied from the help)."""

    def _split_lines(self, text: str, width: int) -> list[str]:
        return textwrap.wrap(" ".join(text.split()), width, break_on_hyphens=False)

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        return textwrap.fill(" ".join(text.split()), width, initial_indent=indent,
                             subsequent_indent=indent, break_on_hyphens=False)


class NavArgumentParser(argparse.ArgumentParser):
    """An ArgumentParser (and, through add_subparsers, every subcommand parser) that reads a
    number list starting with a minus sign as a value, never as an option: ``--start
    -2.25,3,90`` works as a robotics user types it. Real options are unaffected, as none of
    ours looks like a number (argparse would then refuse negative values altogether)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _HelpFormatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBERS


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The whole parser; with ``only``, only that subcommand's arguments are added (and only its
    module is imported); ``only=""`` adds none (enough for the top-level --help)."""
    from .. import __version__
    from ..core.versions import mujoco_version
    parser = NavArgumentParser(prog="navscenario", description=DESCRIPTION, epilog=EPILOG)
    parser.add_argument("--version", action="version",
                        version=f"%(prog)s {__version__} (MuJoCo {mujoco_version()})")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", title="commands")
    for name, (module_name, purpose) in SUBCOMMANDS.items():
        p = sub.add_parser(name, help=purpose, description=DESCRIPTIONS[name])
        if only is None or name == only:
            module = importlib.import_module(module_name)
            adder = getattr(module, f"add_arguments_{name.replace('-', '_')}", None) or module.add_arguments
            adder(p)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    command = next((a for a in argv if not a.startswith("-")), None)
    parser = build_parser(only=command if command in SUBCOMMANDS else "")
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    module = importlib.import_module(SUBCOMMANDS[args.command][0])
    runner = getattr(module, f"run_{args.command.replace('-', '_')}", None) or module.run
    from ..core import interrupts
    restore = interrupts.install(sigterm=False)   # a planner's or controller's own KeyboardInterrupt is its error
    try:
        return int(runner(args) or 0)
    except NavScenarioError as exc:
        print(f"navscenario {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"navscenario {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into e.g. `head`, which closed early: not an error
        sys.stderr.close()
        return 0
    finally:
        if restore is not None:
            restore()


if __name__ == "__main__":
    sys.exit(main())
