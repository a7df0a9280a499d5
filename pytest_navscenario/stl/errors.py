"""The errors of the requirements language: each says what is wrong, where (the column of the
formula) and how to fix it, like every other error of the package (``core.errors``)."""
from __future__ import annotations

from ..core.errors import NavScenarioError


class StlError(NavScenarioError):
    """A formula cannot be read or evaluated. ``message`` says what, ``hint`` how to fix it."""

    def __init__(self, message: str, hint: str | None = None):
        self.message = message
        self.hint = hint
        super().__init__(self.format())

    def format(self) -> str:
        return self.message + (f" (fix: {self.hint})" if self.hint else "")


class StlSyntaxError(StlError):
    """A formula does not parse: ``column`` is 1-based in ``text``, the formula as written.

    ``str(err)`` reads ``column 12: unknown operator '&&' (fix: write 'and')``; ``pointer()``
    gives the formula with a caret under the column, for a report spanning two lines.
    """

    def __init__(self, message: str, column: int, hint: str | None = None, text: str = ""):
        self.column = column
        self.text = text
        super().__init__(message, hint)

    def format(self) -> str:
        return f"column {self.column}: " + super().format()

    def pointer(self) -> str:
        """The formula and a caret under the offending column (two lines)."""
        return f"{self.text}\n{' ' * (self.column - 1)}^"


class StlEvaluationError(StlError):
    """A formula cannot be evaluated on the signals given: a signal is missing or has the wrong
    shape, or an interval is not a whole number of sampling periods."""
