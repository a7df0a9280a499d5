"""``navscenario policy-template MODEL.onnx``: write the declaration a learned policy needs beside its
model (subjects/policies/template.py), to edit into what the policy was trained on."""
from __future__ import annotations

import argparse
import sys


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("model", metavar="MODEL.onnx", help="the policy's ONNX model file")
    p.add_argument("--print", action="store_true", dest="print_only",
                   help="print the template instead of writing MODEL.policy.yaml")
    p.add_argument("--force", action="store_true", help="overwrite MODEL.policy.yaml if it exists")


def run(args: argparse.Namespace) -> int:
    import os

    from ..core.errors import SubjectLoadError
    from ..subjects.policies.template import template_text, write_template

    if not os.path.isfile(args.model):
        what = "is not a regular model file" if os.path.exists(args.model) else "no such model file"
        raise SubjectLoadError(f"{what} {args.model!r}" if what.startswith("no") else f"{args.model!r} {what}")
    if args.print_only:
        sys.stdout.write(template_text(args.model))
        return 0
    written = write_template(args.model, force=args.force)
    print(f"navscenario: wrote {written}: its observation layout is a guess that adds up to the model's "
          f"input; edit it to what the policy was trained on, then check it with: navscenario "
          f"check-planner {args.model}")
    return 0
