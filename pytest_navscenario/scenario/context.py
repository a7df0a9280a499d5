"""Where the reading of a scenario is: the source file (for messages), the line of every field
read, the element names seen so far, and the mistakes found so far. With ``collect`` a part of the
file that has a mistake is recorded and skipped and the reading goes on (``attempt``), so that one
pass reports every mistake it can find, up to MAX_REPORTED (issue 32); ``finish`` raises them.
"""
from __future__ import annotations

from typing import Any

from ..core.errors import ScenarioError, ScenarioErrors

MAX_REPORTED = 20   # mistakes of one file reported in one pass (then: fix these and load again)


class Recorded(Exception):
    """A part of the file (a key, a section, a list item) could not be read; its mistakes are in
    ``_Ctx.errors`` and the reader goes on with the next part (issue 32)."""


BROKEN = object()   # the value of a key that could not be read (its mistake is recorded)


class _Ctx:
    """Where we are: the source file (for messages) and the line of every field read; with
    ``collect``, the mistakes found so far (each part of the file that has one is skipped and
    the reading goes on, so one pass reports them all, up to MAX_REPORTED)."""

    def __init__(self, source: str | None, *, collect: bool = False):
        self.source = source
        self.lines: dict[str, int | None] = {}
        #: names of the typed lists read so far (obstacles, then terrain) -> "obstacles[i]": one
        #: name space, so that a name (in ``search: frozen``, a message) means one thing
        self.element_names: dict[str, str] = {}
        self.collect = collect
        self.errors: list[ScenarioError] = []

    def fail(self, message: str, field: str | None, line: int | None, hint: str | None = None) -> ScenarioError:
        return ScenarioError(message, path=self.source, line=line, field=field, hint=hint)

    def note(self, exc: ScenarioError) -> None:
        """Keep ``exc`` and go on (collecting), or raise it (not collecting); at MAX_REPORTED
        mistakes, stop with all of them."""
        if not self.collect:
            raise exc
        self.errors.append(exc)
        if len(self.errors) >= MAX_REPORTED:
            raise ScenarioErrors(self.errors, stopped=MAX_REPORTED)

    def attempt(self, read: Any, *args: Any) -> Any:
        """``read(*args)``, or BROKEN when it found a mistake (recorded: see ``note``)."""
        try:
            return read(*args)
        except Recorded:
            return BROKEN
        except ScenarioErrors:
            raise
        except ScenarioError as exc:
            self.note(exc)
            return BROKEN

    def finish(self) -> None:
        """Raise what was recorded: the one mistake as itself, several as ScenarioErrors."""
        if len(self.errors) == 1:
            raise self.errors[0]
        if self.errors:
            raise ScenarioErrors(self.errors)
