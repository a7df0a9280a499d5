"""Compare two results files (planner A = baseline, planner B = candidate) scenario by scenario.

Pairing: records are paired by ``(nodeid, repeat)``. When a scenario ran several times, every
repeat index is its own paired observation (repeat r of A against repeat r of B); nothing is
averaged away. A pair whose ``scenario_hash`` differs is *not comparable* (the layout changed
between the runs) and is listed as such, never counted. Records only in A or only in B are listed too.

Rates and the McNemar test are computed over the comparable pairs only, so A and B are always
measured on exactly the same scenarios. Pure data and text: no matplotlib here.
"""
from __future__ import annotations

import math
import os
import shlex
import statistics
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, Iterable, Sequence

from .results_file import OUTCOMES, ResultsFileError, read_results
from .stats import mcnemar_exact, rate_with_interval

RATE_OUTCOMES = ("success", "safety-stop", "timeout", "collision", "fall", "requirement", "subject-error")
# compared over the pairs both subjects passed: (record metrics key, label)
METRICS = (("path_efficiency", "path efficiency"), ("duration", "duration (s)"),
           ("mean_speed", "mean speed (m/s)"), ("min_clearance", "min clearance (m)"))


@dataclass(frozen=True)
class Pair:
    """The same scenario (nodeid, repeat) run by A and by B."""
    nodeid: str
    repeat: int
    family: str
    a: dict[str, Any]
    b: dict[str, Any]

    @property
    def label(self) -> str:
        return self.nodeid if not self.repeat else f"{self.nodeid} (repeat {self.repeat})"


@dataclass(frozen=True)
class Unpaired:
    """A record that has no comparable partner, and why."""
    nodeid: str
    repeat: int
    family: str
    reason: str
    record: dict[str, Any] | None = field(default=None, compare=False, repr=False)  # B's (A's if only in A)

    @property
    def label(self) -> str:
        return self.nodeid if not self.repeat else f"{self.nodeid} (repeat {self.repeat})"


@dataclass(frozen=True)
class Rate:
    count: int
    n: int
    rate: float
    low: float
    high: float

    @classmethod
    def of(cls, count: int, n: int) -> "Rate":
        return cls(count, n, *rate_with_interval(count, n))


@dataclass(frozen=True)
class FamilyComparison:
    """One family's (or the whole set's) rates under A and B, over the same paired scenarios."""
    family: str
    n: int
    a: dict[str, Rate]              # outcome -> rate, for every outcome in RATE_OUTCOMES
    b: dict[str, Rate]
    broke: int                      # A passed, B failed (discordant)
    fixed: int                      # A failed, B passed (discordant)
    mcnemar_p: float                # exact McNemar p on success
    # metric -> (median under A, median under B, pairs): over the pairs that BOTH passed, so the
    # figures describe the same successful drives (NaN when there are none)
    metrics: dict[str, tuple[float, float, int]] = field(default_factory=dict)

    @property
    def success_change(self) -> float:
        """B's success rate minus A's (fraction; NaN with no pairs)."""
        return self.b["success"].rate - self.a["success"].rate


@dataclass
class Comparison:
    a_name: str
    b_name: str
    a_subject: str
    b_subject: str
    pairs: list[Pair]
    only_a: list[Unpaired]
    only_b: list[Unpaired]
    not_comparable: list[Unpaired]
    families: list[FamilyComparison]
    overall: FamilyComparison
    warnings: list[str] = field(default_factory=list)
    # How to name each side's subject in reproduce commands: the --nav-subject spec when known
    # (records carry the planner's name, which need not be importable), plus extra options.
    subject_specs: dict[str, str] = field(default_factory=dict)
    extra_args: str = ""
    command_prefix: str = ""        # e.g. "cd /rootdir && "
    # requirement_compare.RequirementComparison per requirement both sides checked (issue 34)
    requirements: list = field(default_factory=list)

    @property
    def broke_requirements(self) -> list[tuple[str, str]]:
        """(pair label, requirement): A kept the requirement, B violated it."""
        return [(label, r.name) for r in self.requirements for label in r.broke]

    @property
    def broke(self) -> list[Pair]:
        """Regressions: A passed, B did not."""
        return [p for p in self.pairs if _passed(p.a) and not _passed(p.b)]

    @property
    def fixed(self) -> list[Pair]:
        """Improvements: A did not pass, B did."""
        return [p for p in self.pairs if not _passed(p.a) and _passed(p.b)]

    @property
    def has_regressions(self) -> bool:
        return bool(self.broke) or bool(self.broke_requirements)

    def nothing_compared(self) -> str | None:
        """Why not a single pair was compared, or None when one was. Nothing compared is no
        evidence of "no regression" (a candidate run that crashed before writing its results,
        another suite): regression gates fail on it, with this reason."""
        if self.pairs:
            return None
        shared = len(self.not_comparable)
        n_a, n_b = len(self.only_a) + shared, len(self.only_b) + shared
        if not n_a and not n_b:
            return f"A ({self.a_name}) and B ({self.b_name}) have no records"
        if not n_b:
            return f"B ({self.b_name}) has no records, A has {n_a} (did the run stop before writing its results?)"
        if not n_a:
            return f"A ({self.a_name}) has no records, B has {n_b}"
        if shared:
            return (f"the {shared} scenario run(s) A and B share changed between the runs (another "
                    f"scenario_hash), {len(self.only_a)} only in A, {len(self.only_b)} only in B")
        return (f"A and B share no scenario ({len(self.only_a)} only in A, {len(self.only_b)} only in B): "
                f"were both runs made on the same suite?")

    def reproduce_command(self, pair: Pair, side: str = "b") -> str:
        """The command that re-runs this one scenario with B's (or A's) subject."""
        return self.record_command(pair.b if side == "b" else pair.a, side)

    def record_command(self, rec: dict[str, Any], side: str = "b") -> str:
        """The command that re-runs the scenario of one record with that side's subject: the
        ``--nav-subject`` spec given for that side, else the one the record carries
        (``subject_spec``), never the planner's display name (``subject``), which need not be
        importable. Without a spec the command says why in a comment (see ``spec_note``)."""
        spec = self.subject_specs.get(side) or rec.get("subject_spec")
        cmd = f"{self.command_prefix}pytest {shlex.quote(rec['nodeid'])}"
        if spec:
            cmd += f" {shlex.quote(f'--nav-subject={spec}')}"
        if self.extra_args:
            cmd += f" {self.extra_args}"
        notes = [] if spec else [spec_note(rec)]
        if rec.get("repeat"):
            notes.append(f"repeat {rec['repeat']}, episode seed {rec.get('seed')}")
        return cmd + (f"  # {'; '.join(notes)}" if notes else "")


def spec_note(rec: dict[str, Any]) -> str:
    """Why a record names no ``--nav-subject`` spec: a conftest hook made the subject (the
    project's hook makes it again), or the file predates the ``subject_spec`` field."""
    name = rec.get("subject") or "?"
    if "subject_spec" in rec:
        return f"subject {name} from the project's pytest_navscenario_make_subject hook"
    return (f"subject {name}: its --nav-subject spec is unknown (the results file does not record "
            f"it); add --nav-subject=SPEC")


def _passed(rec: dict[str, Any]) -> bool:
    return rec["outcome"] == "success"


def _key(rec: dict[str, Any]) -> tuple[str, int]:
    return rec["nodeid"], int(rec.get("repeat") or 0)


def _index(records: Iterable[dict[str, Any]], name: str) -> dict[tuple[str, int], dict[str, Any]]:
    out: dict[tuple[str, int], dict[str, Any]] = {}
    for rec in records:
        key = _key(rec)
        if key in out:
            raise ResultsFileError(
                f"{name}: two records for {key[0]!r} repeat {key[1]} (were two results files "
                f"concatenated? write one file per run with --nav-results)")
        out[key] = rec
    return out


def _subject_label(records: Sequence[dict[str, Any]], name: str, warnings: list[str]) -> str:
    labels = sorted({
        (r.get("subject") or "?") + (f" {r['subject_version']}" if r.get("subject_version") else "")
        for r in records})
    if len(labels) > 1:
        warnings.append(f"{name} mixes subjects: {', '.join(labels)}")
    return ", ".join(labels) if labels else "(empty)"


def _family_comparison(family: str, pairs: Sequence[Pair]) -> FamilyComparison:
    n = len(pairs)
    ca = Counter(p.a["outcome"] for p in pairs)
    cb = Counter(p.b["outcome"] for p in pairs)
    broke = sum(1 for p in pairs if _passed(p.a) and not _passed(p.b))
    fixed = sum(1 for p in pairs if not _passed(p.a) and _passed(p.b))
    both = [p for p in pairs if _passed(p.a) and _passed(p.b)]
    metrics = {}
    for key, _label in METRICS:
        va = [(p.a.get("metrics") or {}).get(key) for p in both]
        vb = [(p.b.get("metrics") or {}).get(key) for p in both]
        ok = [(x, y) for x, y in zip(va, vb) if isinstance(x, (int, float)) and isinstance(y, (int, float))]
        metrics[key] = ((statistics.median(x for x, _ in ok), statistics.median(y for _, y in ok), len(ok))
                        if ok else (math.nan, math.nan, 0))
    return FamilyComparison(
        family=family, n=n,
        a={o: Rate.of(ca[o], n) for o in RATE_OUTCOMES},
        b={o: Rate.of(cb[o], n) for o in RATE_OUTCOMES},
        broke=broke, fixed=fixed, mcnemar_p=mcnemar_exact(broke, fixed), metrics=metrics)


def compare_records(a: Sequence[dict[str, Any]], b: Sequence[dict[str, Any]], *,
                    a_name: str = "A", b_name: str = "B") -> Comparison:
    """Pair two lists of results records (see ``results.py``) and compute the comparison."""
    warnings: list[str] = []
    ia, ib = _index(a, a_name), _index(b, b_name)
    pairs: list[Pair] = []
    only_a: list[Unpaired] = []
    only_b: list[Unpaired] = []
    not_comparable: list[Unpaired] = []
    for key in sorted(set(ia) | set(ib)):
        ra, rb = ia.get(key), ib.get(key)
        if rb is None:
            only_a.append(Unpaired(key[0], key[1], ra["family"], f"only in {a_name}", ra))
        elif ra is None:
            only_b.append(Unpaired(key[0], key[1], rb["family"], f"only in {b_name}", rb))
        elif ra["scenario_hash"] != rb["scenario_hash"]:
            not_comparable.append(Unpaired(
                key[0], key[1], ra["family"],
                f"scenario changed between the runs (scenario_hash {ra['scenario_hash']} in {a_name}, "
                f"{rb['scenario_hash']} in {b_name}): re-run both subjects on the same file", rb))
        else:
            if ra["family"] != rb["family"]:
                warnings.append(f"{key[0]}: family {ra['family']!r} in {a_name}, {rb['family']!r} in "
                                f"{b_name}; counted under {ra['family']!r}")
            pairs.append(Pair(key[0], key[1], ra["family"], ra, rb))
    by_family: dict[str, list[Pair]] = {}
    for p in pairs:
        by_family.setdefault(p.family, []).append(p)
    families = [_family_comparison(f, by_family[f]) for f in sorted(by_family)]
    if ia and ib and not pairs:
        warnings.append(f"no scenario of {a_name} could be paired with one of {b_name}: "
                        f"were both runs made on the same suite?")
    from .requirement_compare import compare_requirements
    return Comparison(
        requirements=compare_requirements(pairs),
        a_name=a_name, b_name=b_name,
        a_subject=_subject_label(list(ia.values()), a_name, warnings),
        b_subject=_subject_label(list(ib.values()), b_name, warnings),
        pairs=pairs, only_a=only_a, only_b=only_b, not_comparable=not_comparable,
        families=families, overall=_family_comparison("(all)", pairs), warnings=warnings)


def compare_files(a_path: str | os.PathLike, b_path: str | os.PathLike) -> Comparison:
    """Read and compare two ``--nav-results`` files; ResultsFileError names a bad file and line."""
    return compare_records(read_results(a_path), read_results(b_path),
                           a_name=str(a_path), b_name=str(b_path))


# ----------------------------------------------------------------------------------- text output

def _pct(r: Rate) -> str:
    if r.n == 0:
        return "   -   "
    return f"{100 * r.rate:5.1f}% [{100 * r.low:.0f}-{100 * r.high:.0f}]"


def _arrow(a: float, b: float) -> str:
    if math.isnan(a) or math.isnan(b):
        return "-"
    digits = 1 if max(abs(a), abs(b)) >= 10 else 2
    return f"{a:.{digits}f} -> {b:.{digits}f}"


def _p(p: float) -> str:
    return "<0.001" if p < 0.001 else f"{p:.3f}"


OPTIONAL_OUTCOMES = ("subject-error", "fall", "requirement")   # a column only when some episode had it
SHORT = {"success": "success", "safety-stop": "safety-stop", "timeout": "timeout",
         "collision": "collision", "fall": "fall", "requirement": "requirement", "subject-error": "error"}


def format_comparison(cmp: Comparison, *, max_listed: int = 50, max_unpaired: int | None = None,
                      only_a_note: str = "not compared") -> str:
    """The comparison as plain text (for the terminal and the CLI). ``max_listed`` scenarios per
    list (``max_unpaired`` for the only-in-A / only-in-B lists, default the same)."""
    lines = [f"A = {cmp.a_name}: {cmp.a_subject}", f"B = {cmp.b_name}: {cmp.b_subject}",
             f"{len(cmp.pairs)} paired scenario runs (same nodeid and repeat index); rates over these pairs",
             "with 95 % Wilson intervals; change = B - A success; p = exact McNemar test on success"]
    outcomes = [o for o in RATE_OUTCOMES        # errors and falls get a column when there are any
                if o not in OPTIONAL_OUTCOMES or cmp.overall.a[o].count or cmp.overall.b[o].count]
    fw = max([14] + [len(f.family) for f in cmp.families])
    header = f"{'family':<{fw}} {'n':>4}  {'':2}" + "".join(f" {SHORT[o]:>15}" for o in outcomes) \
        + f" {'change':>8} {'broke':>5} {'fixed':>5} {'p':>6}"
    lines += ["", header]
    rows = cmp.families + ([cmp.overall] if len(cmp.families) != 1 else [])
    for fam in rows:
        for side in ("a", "b"):
            rates = getattr(fam, side)
            cells = "".join(f" {_pct(rates[o]):>15}" for o in outcomes)
            if side == "a":
                lines.append(f"{fam.family:<{fw}} {fam.n:>4}  A " + cells)
            else:
                change = fam.success_change
                ch = "   -" if fam.n == 0 else f"{100 * change:+7.1f}pp"
                lines.append(f"{'':<{fw}} {'':>4}  B " + cells
                             + f" {ch:>8} {fam.broke:>5} {fam.fixed:>5} {_p(fam.mcnemar_p):>6}")
    if any(fam.metrics.get(k, (0, 0, 0))[2] for fam in rows for k, _ in METRICS):
        lines += ["", "metrics over the pairs both passed, median A -> B:",
                  f"{'family':<{fw}} {'n':>4}  " + "".join(f" {label:>19}" for _, label in METRICS)]
        for fam in rows:
            n_both = max(fam.metrics[k][2] for k, _ in METRICS)
            cells = "".join(f" {_arrow(*fam.metrics[k][:2]):>19}" for k, _ in METRICS)
            lines.append(f"{fam.family:<{fw}} {n_both:>4}  " + cells)
    broke, fixed = cmp.broke, cmp.fixed

    def listing(title: str, items: Sequence[Any], render, limit: int = max_listed) -> None:
        if not items:
            return
        lines.extend(["", f"{title} ({len(items)}):"])
        for item in items[:limit]:
            lines.extend(render(item))
        if len(items) > limit:
            lines.append(f"  ... and {len(items) - limit} more")

    def pair_lines(p: Pair) -> list[str]:
        return [f"  {p.label}: A {p.a['outcome']}, B {p.b['outcome']}"
                + (f" ({p.b.get('message')})" if p.b.get("message") and not _passed(p.b) else ""),
                f"    reproduce: {cmp.reproduce_command(p)}"]

    from .requirement_compare import format_requirements
    lines += format_requirements(cmp.requirements, max_listed)
    listing("B broke (regressions: A passed, B failed)", broke, pair_lines)
    listing("B fixed (A failed, B passed)", fixed, pair_lines)
    listing("not comparable", cmp.not_comparable, lambda u: [f"  {u.label}: {u.reason}"])
    few = max_listed if max_unpaired is None else max_unpaired
    listing(f"only in A ({cmp.a_name}), {only_a_note}", cmp.only_a, lambda u: [f"  {u.label}"], few)
    listing(f"only in B ({cmp.b_name}), not compared", cmp.only_b, lambda u: [f"  {u.label}"], few)
    for w in cmp.warnings:
        lines.append(f"warning: {w}")
    lines.append("")
    verdict = (f"{len(broke)} regression(s), {len(fixed)} fix(es)" if cmp.pairs
               else "nothing to compare")
    if cmp.broke_requirements:
        verdict += f", {len(cmp.broke_requirements)} requirement(s) A kept that B violates"
    lines.append(f"result: {verdict}; {len(cmp.not_comparable)} not comparable, "
                 f"{len(cmp.only_a)} only in A, {len(cmp.only_b)} only in B")
    return "\n".join(lines)


# ----------------------------------------------------------------------------------- re-runs


# ----------------------------------------------------------------------------------- JUnit output

def to_junit_xml(cmp: Comparison) -> str:
    """The comparison as JUnit XML: one test case per scenario run; a case fails where B broke
    what A passed, is skipped where it could not be compared, and passes otherwise."""
    from junit_xml import TestCase, TestSuite, to_xml_report_string

    cases = []
    for p in cmp.pairs:
        tc = TestCase(name=p.label, classname=f"navscenario.compare.{p.family or 'default'}",
                      elapsed_sec=float(p.b.get("wall_time") or 0.0),
                      stdout=f"A ({cmp.a_subject}): {p.a['outcome']}\nB ({cmp.b_subject}): {p.b['outcome']}")
        if _passed(p.a) and not _passed(p.b):
            tc.add_failure_info(
                message=f"regression: A {p.a['outcome']}, B {p.b['outcome']}",
                output=f"{p.b.get('message') or ''}\nreproduce: {cmp.reproduce_command(p)}")
        cases.append(tc)
    for u in cmp.not_comparable + cmp.only_a + cmp.only_b:
        tc = TestCase(name=u.label, classname=f"navscenario.compare.{u.family or 'default'}")
        tc.add_skipped_info(message=u.reason)
        cases.append(tc)
    suite = TestSuite(f"navscenario compare: {cmp.a_subject} -> {cmp.b_subject}", cases)
    return to_xml_report_string([suite])


__all__ = ["Comparison", "FamilyComparison", "OUTCOMES", "Pair", "Rate", "Unpaired",
           "compare_files", "compare_records", "format_comparison", "to_junit_xml"]
