"""``navscenario compare A.jsonl B.jsonl``: planner A (baseline) against planner B (candidate).

Exit status: 0, or 1 with ``--fail-on-regression`` when B broke a scenario A passed or when
nothing could be compared (B empty, no scenario in common: the reason is printed); 2 when a file
cannot be read (the error names the file and line), or when ``--side-by-side`` could make none of
the plots it was due to (e.g. no ``--nav-subject`` spec to re-run a side by: the reason is printed).
"""
from __future__ import annotations

import argparse
import sys

from ..core.files import atomic_write_text


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("a", metavar="A.jsonl", help="baseline results file (pytest --nav-results=A.jsonl)")
    p.add_argument("b", metavar="B.jsonl", help="candidate results file, same suite, other subject/version")
    p.add_argument("--junit", metavar="OUT.xml",
                   help="write the comparison as JUnit XML: one test case per scenario, failing where B broke what A passed")
    p.add_argument("--plot", metavar="OUT.png",
                   help="write the two-sided bar chart (success up, failures by outcome down, per family, A beside B)")
    p.add_argument("--html", metavar="OUT.html",
                   help="write a self-contained HTML report: the comparison, the bar chart and B's runs")
    p.add_argument("--fail-on-regression", action="store_true",
                   help="exit with status 1 when B fails a scenario that A passed, or when nothing could be "
                        "compared (B empty, no scenario in common) (a CI gate)")
    p.add_argument("--max-listed", type=int, default=50, metavar="N",
                   help="list at most N scenarios per list (default 50)")
    p.add_argument("--side-by-side", metavar="DIR",
                   help="re-run the scenarios B broke (then those it fixed) with both subjects and write "
                        "one side-by-side trajectory plot per scenario into DIR (exit status 2 when none "
                        "can be made, e.g. a subject with no spec to re-run it by)")
    p.add_argument("--max-plots", type=int, default=10, metavar="N",
                   help="at most N side-by-side plots (default 10; 0 = no limit): each re-runs one "
                        "scenario with both subjects; the scenarios B broke come first, then those it fixed")
    p.add_argument("--a-subject", metavar="SPEC",
                   help="subject to re-run A with (default: the --nav-subject spec A's records carry, "
                        "subject_spec; needed when A's subject came from a conftest hook)")
    p.add_argument("--b-subject", metavar="SPEC",
                   help="subject to re-run B with (default: the --nav-subject spec B's records carry, "
                        "subject_spec; needed when B's subject came from a conftest hook)")
    p.add_argument("--root", default=".", metavar="DIR",
                   help="folder the records' scenario paths are relative to (the pytest rootdir; default .)")


def run(args: argparse.Namespace) -> int:
    from ..report.compare import compare_files, format_comparison, to_junit_xml

    cmp = compare_files(args.a, args.b)
    print(format_comparison(cmp, max_listed=args.max_listed))
    if args.junit:
        atomic_write_text(args.junit, to_junit_xml(cmp))
        print(f"JUnit XML written to {args.junit}")
    if args.plot:
        from ..report.plots import save_bars
        save_bars(cmp, args.plot)
        print(f"bar chart written to {args.plot}")
    if args.html:
        from ..report.html import Entry, write_html
        from ..report.plots import bars_figure, png_bytes
        b_records = [p.b for p in cmp.pairs] + [u.record for u in cmp.only_b + cmp.not_comparable
                                                 if u.record is not None]
        entries = [Entry(record=r, reproduce=cmp.record_command(r)) for r in b_records]
        bars = png_bytes(bars_figure(cmp)) if cmp.pairs else None
        write_html(args.html, entries, template="compare_report.html.j2", title=f"navscenario compare: {cmp.a_subject} → {cmp.b_subject}",
                   comparison=cmp, bars_png=bars, info=[f"A: {args.a}", f"B: {args.b}"])
        print(f"HTML report written to {args.html}")
    failed_side_by_side = False
    if args.side_by_side:
        failed_side_by_side = _side_by_side(cmp, args)
    why = cmp.nothing_compared()
    if why is not None:
        verdict = "FAILED the gate" if args.fail_on_regression else "warning"
        print(f"navscenario compare: {verdict}: nothing was compared: {why}", file=sys.stderr)
    if failed_side_by_side:
        return 2
    if args.fail_on_regression and (cmp.has_regressions or why is not None):
        return 1
    return 0


def _side_by_side(cmp, args: argparse.Namespace) -> bool:
    """Re-run what B broke and fixed for side-by-side plots; True when plots were due and none
    could be made (the reasons printed: e.g. a subject with no spec to re-run it by)."""
    import os

    from ..report.rerun import rerun_side_by_side

    changed = cmp.broke + cmp.fixed
    limit = args.max_plots if args.max_plots > 0 else len(changed)
    due = changed[:limit]
    if not due:
        print("no side-by-side plots: B neither broke nor fixed a scenario A ran (nothing to show)")
        return False
    written, problems = rerun_side_by_side(cmp, args.side_by_side, root=args.root, limit=limit,
                                           a_subject=args.a_subject, b_subject=args.b_subject,
                                           project=[os.getcwd()])
    for line in problems:
        print(f"side-by-side: {line}", file=sys.stderr)
    if not written:
        print(f"navscenario compare: error: --side-by-side {args.side_by_side}: none of the {len(due)} "
              f"side-by-side plot(s) could be made (see above)", file=sys.stderr)
        return True
    print(f"{len(written)} of {len(due)} side-by-side plot(s) written to {args.side_by_side}")
    if len(due) < len(changed):
        print(f"side-by-side: B broke or fixed {len(changed)} scenarios; plotted the first {len(due)} "
              f"(--max-plots {args.max_plots}, default 10: broken ones first); --max-plots {len(changed)} "
              f"or 0 plots them all")
    return False

