"""``navscenario from-bag``: the importer (ros/bag_import) plus, at the end, the seed's picture
beside the recorded path (report/seed_plot), which the ros layer may not draw itself."""
from __future__ import annotations

import argparse

from ..ros.bag_import import add_arguments as _bag_arguments
from ..ros.bag_import.cli import _list_events, import_bag


def add_arguments(p: argparse.ArgumentParser) -> None:
    _bag_arguments(p)
    p.add_argument("--no-plot", action="store_true",
                   help="do not draw the seed beside the recorded path (default: OUT.png beside the seed)")


def run(args: argparse.Namespace) -> int:
    if args.list_events:
        return _list_events(args)
    seed, out = import_bag(args)
    if not args.no_plot:
        from ..report.seed_plot import save_seed_figure
        png = save_seed_figure(seed.scenario, seed.path, out.with_suffix(".png"))
        print(f"navscenario from-bag: the seed beside the recorded path: {png}")
    return 0
