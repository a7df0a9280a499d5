"""The live progress line of a search run in this process (``pytest --navsearch``)."""
from __future__ import annotations

import math
from typing import Any

import pytest


class _Progress:
    """Live progress in a serial run, written through the terminal reporter with pytest's
    capture suspended (else it would be swallowed): one line rewritten in place on a terminal,
    else a plain line per tenth of the budget and on each new distinct failure (a CI log)."""

    def __init__(self, config: pytest.Config, name: str, budget: int):
        self.tr = config.pluginmanager.get_plugin("terminalreporter")
        self.capman = config.pluginmanager.get_plugin("capturemanager")
        self.name, self.budget = name, budget
        self.step = max(1, budget // 10)
        self.last_failures = 0
        self.last_sims = -1
        self.tty = bool(self.tr is not None and getattr(self.tr, "isatty", False))
        self.started = False

    def line(self, report: Any) -> str:
        n, nf = report.sims_used, len(report.failures)
        out = f"navsearch {self.name}: {n}/{self.budget} sims, {nf} distinct failure(s)"
        if report.under_test or report.rejected:
            out += f" ({report.under_test} being confirmed, {len(report.rejected)} did not hold)"
        if math.isfinite(report.best_clearance):
            out += f", lowest clearance so far {report.best_clearance:.3f} m"
        rob = report.best_robustness
        if math.isfinite(rob) and not nf:
            out += f", closest to failing {rob:.2f}"
        if report.shrink_sims:
            out += f", shrinking ({report.shrink_sims} sims)"
        return out

    def __call__(self, report: Any) -> None:
        if self.tr is None:
            return
        n, nf = report.sims_used, len(report.failures)
        due = self.tty or nf != self.last_failures or (n % self.step == 0 and n != self.last_sims
                                                        and not report.shrink_sims)
        self.last_failures, self.last_sims = nf, n
        if not due:
            return
        with self._uncaptured():
            if self.tty:
                if not self.started:
                    self.tr.write_line("")
                    self.started = True
                self.tr.rewrite(self.line(report), erase=True)
            else:
                self.tr.ensure_newline()
                self.tr.write_line(self.line(report))
            if hasattr(self.tr, "flush"):
                self.tr.flush()

    def _uncaptured(self) -> Any:
        import contextlib
        if self.capman is None:
            return contextlib.nullcontext()
        return self.capman.global_and_fixture_disabled()
