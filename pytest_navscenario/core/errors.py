"""The project's own exceptions: each says what is wrong, where, and how to fix it."""
from __future__ import annotations


class NavScenarioError(Exception):
    """Base class of every error this package raises on purpose."""


class ScenarioError(NavScenarioError):
    """A scenario file (or mapping) is invalid.

    Carries the file, the 1-based line, the dotted field path and a fix hint so that
    the message reads ``boxes1.yaml:12: obstacles[0].length: must be > 0, got -1.0 (fix: ...)``.
    """

    def __init__(self, message: str, *, path: str | None = None, line: int | None = None,
                 field: str | None = None, hint: str | None = None):
        self.message = message
        self.path = path
        self.line = line
        self.field = field
        self.hint = hint
        super().__init__(self.format())

    def format(self) -> str:
        where = ""
        if self.path:
            where = str(self.path) + (f":{self.line}" if self.line else "") + ": "
        elif self.line:
            where = f"line {self.line}: "
        field = f"{self.field}: " if self.field else ""
        hint = f" (fix: {self.hint})" if self.hint else ""
        return f"{where}{field}{self.message}{hint}"


class ScenarioErrors(ScenarioError):
    """Several mistakes in one scenario file, each a ScenarioError with its file:line, field and
    fix, in file order; ``line``, ``field`` and ``hint`` are the first's. ``stopped``: the number
    of mistakes after which the loader stopped looking (0: it read the whole file)."""

    def __init__(self, errors: list[ScenarioError], *, stopped: int = 0):
        self.errors = sorted(errors, key=lambda e: (e.line or 0))
        self.stopped = stopped
        first = self.errors[0]
        super().__init__(first.message, path=first.path, line=first.line, field=first.field, hint=first.hint)

    def format(self) -> str:
        errors = getattr(self, "errors", None)
        if not errors:
            return super().format()
        stopped = getattr(self, "stopped", 0)
        more = f" (it stops looking at {stopped}: fix these and load it again)" if stopped else ""
        where = f"{errors[0].path}: " if errors[0].path else ""
        return f"{where}{len(errors)} mistakes{more}:\n" + "\n".join(f"  {e.format()}" for e in errors)


class SubjectLoadError(NavScenarioError):
    """A planner ('subject') spec such as ``pkg.mod:Planner`` cannot be loaded or fails the protocol."""


class PlannerProtocolError(NavScenarioError):
    """A planner broke the protocol during an episode (raised, NaN, wrong type/shape, too slow)."""

    def __init__(self, message: str, *, tick: int | None = None, time: float | None = None,
                 planner_traceback: str | None = None):
        self.message = message
        self.tick = tick
        self.time = time
        self.planner_traceback = planner_traceback
        where = f" at tick {tick} (t={time:.2f} s)" if tick is not None and time is not None else ""
        super().__init__(f"{message}{where}")


class SimulationDivergedError(NavScenarioError):
    """MuJoCo produced NaN/inf state or warnings: the physics cannot be trusted."""


class SimulationFatalError(NavScenarioError):
    """MuJoCo stopped an episode with a fatal error (mju_error: e.g. its memory arena overflowed):
    the model cannot be simulated as it is. Ends that episode as an error, not the run."""


class ImpassableScenarioError(NavScenarioError):
    """No planner can pass the scenario (its goal cannot be reached), or it passes without one:
    a defect of the scenario, reported before any episode runs, never a planner failure."""
