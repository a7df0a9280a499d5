"""``navscenario schema``: write the JSON Schema of the scenario format (scenario/json_schema.py)."""
from __future__ import annotations

import argparse
import sys


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("-o", "--output", metavar="FILE", default=None,
                   help="write the schema to FILE (its folder is created), e.g. .navscenario/scenario-v1.json, "
                        "the path the modeline of written scenarios names; default: print it")


def run(args: argparse.Namespace) -> int:
    from ..core.files import atomic_write_text
    from ..scenario.json_schema import schema_text
    from ..scenario.model import SCHEMA_VERSION

    text = schema_text()
    if args.output is None:
        sys.stdout.write(text)
        return 0
    atomic_write_text(args.output, text)
    print(f"navscenario: wrote the scenario schema (format version {SCHEMA_VERSION}) to {args.output}")
    return 0
