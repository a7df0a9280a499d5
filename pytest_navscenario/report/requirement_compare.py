"""Requirements across two results files (issue 34): per requirement, its violation rate under A
and under B with 95 % Wilson intervals over the pairs where both checked it, the pairs where A kept
it and B violated it (a regression the gate fails on, even when A failed otherwise), those B
fixed, and the exact McNemar test on them. Pure data and text, like compare.py."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

from .stats import mcnemar_exact, rate_with_interval


@dataclass(frozen=True)
class RequirementComparison:
    name: str
    n: int                          # pairs where both runs checked it
    a: tuple[int, float, float, float]    # (violations, rate, low, high) under A
    b: tuple[int, float, float, float]
    broke: tuple[str, ...]          # pair labels: A kept it, B violated it
    fixed: tuple[str, ...]          # A violated it, B kept it
    mcnemar_p: float


def _checked(record: dict[str, Any]) -> dict[str, bool]:
    """requirement name -> violated, of one record (records without the field: none)."""
    return {r["name"]: bool(r.get("violated")) for r in record.get("requirements") or ()}


def compare_requirements(pairs: Sequence[Any]) -> list[RequirementComparison]:
    """One row per requirement any pair checked on both sides, by name."""
    rows: dict[str, list[tuple[str, bool, bool]]] = {}
    for p in pairs:
        a, b = _checked(p.a), _checked(p.b)
        for name in sorted(set(a) & set(b)):
            rows.setdefault(name, []).append((p.label, a[name], b[name]))
    out = []
    for name, seen in sorted(rows.items()):
        n = len(seen)
        va, vb = sum(a for _, a, _ in seen), sum(b for _, _, b in seen)
        broke = tuple(label for label, a, b in seen if not a and b)
        fixed = tuple(label for label, a, b in seen if a and not b)
        out.append(RequirementComparison(name, n, (va, *rate_with_interval(va, n)), (vb, *rate_with_interval(vb, n)),
                                         broke, fixed, mcnemar_exact(len(broke), len(fixed))))
    return out


def _pct(cell: tuple[int, float, float, float]) -> str:
    count, rate, low, high = cell
    return f"{count:>3} {100 * rate:5.1f}% [{100 * low:.0f}-{100 * high:.0f}]"


def format_requirements(rows: Sequence[RequirementComparison], max_listed: int = 20) -> list[str]:
    """The requirements' table and their regressions as text lines ([] without requirements)."""
    if not rows:
        return []
    width = max(12, *(len(r.name) for r in rows))
    lines = ["", "requirements: violations with 95 % Wilson intervals; broke = A kept it, B violated it; "
             "p = exact McNemar",
             f"{'requirement':<{width}} {'n':>4} {'A violated':>20} {'B violated':>20} {'broke':>5} "
             f"{'fixed':>5} {'p':>6}"]
    for r in rows:
        p = "<0.001" if r.mcnemar_p < 0.001 else f"{r.mcnemar_p:.3f}"
        lines.append(f"{r.name:<{width}} {r.n:>4} {_pct(r.a):>20} {_pct(r.b):>20} {len(r.broke):>5} "
                     f"{len(r.fixed):>5} {p:>6}")
    broke = [(r.name, label) for r in rows for label in r.broke]
    if broke:
        lines += ["", f"B violates a requirement A kept ({len(broke)}):"]
        lines += [f"  {label}: {name}" for name, label in broke[:max_listed]]
        if len(broke) > max_listed:
            lines.append(f"  ... and {len(broke) - max_listed} more")
    return lines
