"""The ``navscenario`` console script. Each subcommand lives in its own module, imported only
when that subcommand runs (so ``navscenario --help`` stays fast). A subcommand module has
``add_arguments(parser)`` and ``run(args) -> int``."""
from __future__ import annotations

import argparse
import importlib
import sys

from ..core.errors import NavScenarioError

# name -> (module, one-line help)
SUBCOMMANDS: dict[str, tuple[str, str]] = {
    "run": ("pytest_navscenario.cli.run", "run one scenario file against a subject and print the outcome and metrics"),
    "check-planner": ("pytest_navscenario.cli.run", "check a planner against the protocol (see check_planner)"),
    "compare": ("pytest_navscenario.cli.compare", "compare two --nav-results files (planner A vs B)"),
    "from-bag": ("pytest_navscenario.ros.bag_import", "build a seed scenario from a ROS 1 / ROS 2 bag"),
    "from-map": ("pytest_navscenario.ros.map_import", "build a seed scenario from a map_server occupancy grid"),
    "import": ("pytest_navscenario.ros.world_import", "import another tool's world: aerialist test YAML or Gazebo SDF"),
}


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    from .. import __version__
    parser = argparse.ArgumentParser(prog="navscenario", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module_name, help_text) in SUBCOMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
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


if __name__ == "__main__":
    sys.exit(main())
