"""Re-running a compared pair: replay one record of a results file against its subject, and
draw two runs of the same scenario side by side."""
from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, Sequence

if TYPE_CHECKING:
    from .compare import Comparison


def rerun_spec(rec: dict[str, Any], subject: str | None, side: str = "", option: str | None = None) -> str:
    """The ``--nav-subject`` spec to re-run a record with: ``subject`` when given, else the spec
    the record carries (``subject_spec``), never the planner's display name. NavScenarioError
    saying what to give (``option``, default --a-subject / --b-subject) when there is none."""
    from ..core.errors import NavScenarioError

    spec = subject or rec.get("subject_spec")
    if spec:
        return spec
    why = ("it came from a conftest pytest_navscenario_make_subject hook" if "subject_spec" in rec
           else "the file was written before results recorded it")
    option = option or (f"--{side.lower()}-subject" if side else "--a-subject / --b-subject")
    raise NavScenarioError(f"cannot re-run {side + ' ' if side else ''}(subject {rec.get('subject') or '?'!r}): "
                           f"its results file records no --nav-subject spec ({why}); give it with "
                           f"{option} SPEC")


def rerun_record(rec: dict[str, Any], subject: str | None = None, *, root: str | os.PathLike = ".",
                 side: str = "", project: Sequence[str | os.PathLike] = ()) -> Any:
    """Run a record's scenario again, as it was run: the file at ``root/rec["path"]`` (refused if
    its content hash differs from the record's), the record's episode seed, and ``subject`` (default:
    the spec the record carries, ``rerun_spec``; its module also looked up in ``root`` and the
    ``project`` folders). Returns the EpisodeResult. Raises NavScenarioError in plain words."""
    import dataclasses
    from pathlib import Path

    from ..core.errors import NavScenarioError
    from ..scenario.loader import load_scenario
    from ..harness.runner import run_scenario
    from ..scenario.model import content_hash
    from ..subjects.loading import locate_subject

    spec = rerun_spec(rec, subject, side)
    path = Path(root) / rec.get("path", "")
    if not rec.get("path") or not path.is_file():
        raise NavScenarioError(f"{rec['nodeid']}: scenario file {str(path)!r} not found (give the pytest "
                               f"rootdir of that run with --root)")
    scenario = load_scenario(path)
    if content_hash(scenario) != rec["scenario_hash"]:
        raise NavScenarioError(f"{rec['nodeid']}: {path} changed since the run (scenario_hash "
                               f"{content_hash(scenario)}, the record has {rec['scenario_hash']}); "
                               f"cannot re-run it as it was")
    # the record's effective seed as the scenario's own seed: run_scenario then uses exactly it
    scenario = dataclasses.replace(scenario, simulation=dataclasses.replace(scenario.simulation,
                                                                            seed=int(rec.get("seed") or 0)))
    locate_subject(spec, [root, *project])
    try:
        return run_scenario(scenario, spec)
    except NavScenarioError as exc:
        raise NavScenarioError(f"{rec['nodeid']}: cannot re-run {side + ' ' if side else ''}with subject "
                               f"{spec!r}: {exc}") from None


def rerun_side_by_side(cmp: Comparison, folder: str | os.PathLike, *, root: str | os.PathLike = ".",
                       limit: int = 10, a_subject: str | None = None,
                       b_subject: str | None = None,
                       project: Sequence[str | os.PathLike] = ()) -> tuple[list[str], list[str]]:
    """Re-run the scenarios B broke (then those it fixed) under A and B and write one side-by-side
    plot per scenario into ``folder``. Returns (files written, problems: one line each, the same
    problem said once)."""
    from pathlib import Path

    from ..core.files import folder_name
    from ..core.errors import NavScenarioError
    from .plots import save_comparison

    written: list[str] = []
    problems: list[str] = []
    for pair in (cmp.broke + cmp.fixed)[:max(0, limit)]:
        try:
            ra = rerun_record(pair.a, a_subject, root=root, side="A", project=project)
            rb = rerun_record(pair.b, b_subject, root=root, side="B", project=project)
        except NavScenarioError as exc:
            problems.append(str(exc))
            continue
        for side, rec, res in (("A", pair.a, ra), ("B", pair.b, rb)):
            if res.outcome.value != rec["outcome"]:
                problems.append(f"{pair.label}: {side} re-run gave {res.outcome.value}, the results file says "
                                f"{rec['outcome']} (another planner version, or a nondeterministic planner?)")
        name = folder_name(pair.nodeid) + (f"-r{pair.repeat}" if pair.repeat else "") + ".png"
        out = save_comparison(ra, rb, Path(folder) / name,
                              labels=(f"A ({a_subject or pair.a.get('subject')})",
                                      f"B ({b_subject or pair.b.get('subject')})"))
        written.append(str(out))
    return written, list(dict.fromkeys(problems))
