"""The two self-contained HTML reports: the run report (``pytest --nav-html=report.html``) and the
compare report (``navscenario compare A.jsonl B.jsonl --html=OUT.html``). Each opens from disk, no
server, no internet: images are embedded as base64 PNG, CSS and the few lines of JavaScript inline.

The markup lives in Jinja2 templates (``templates/``, autoescaped): ``run_report.html.j2`` and
``compare_report.html.j2`` extend ``_page.html.j2`` and include one template per section;
``report.css`` and ``report.js`` are inlined. To change a page, edit the templates; this module
only prepares the numbers (and imports Jinja2 only when a report is written).

Contents: the run's summary per family (rates with 95 % Wilson intervals), the comparison with a
baseline when one was given (table, bar chart, regressions with their reproduce commands), a table
of every scenario run (click a column header to sort, e.g. by family or outcome), and one entry per
failure with its message, reproduce command, main metrics and trajectory plot.
"""
from __future__ import annotations

import base64
import datetime as _dt
import functools
import os
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from ..core.files import atomic_write_text

if TYPE_CHECKING:  # pragma: no cover
    from .compare import Comparison

OUTCOMES = ("success", "safety-stop", "timeout", "collision", "fall", "subject-error")
METRICS = (("min_clearance", "min clearance (m)", 2), ("min_obstacle_gap", "narrowest gap (m)", 2),
           ("path_efficiency", "path efficiency", 2), ("duration", "duration (s)", 1),
           ("mean_speed", "mean speed (m/s)", 2))


@dataclass
class Entry:
    """One scenario run in the report: its results record, plus its plot when one was made."""
    record: dict[str, Any]
    plot_png: bytes | None = None
    reproduce: str = ""
    view: dict[str, Any] | None = None   # view_data(result): the interactive time-slider view
    compare_png: bytes | None = None     # a regression: the scenario under the baseline | this run
    xfail_reason: str | None = None      # marked xfail and failed as expected (pytest's wasxfail)

    @property
    def failed(self) -> bool:
        """The outcome is not success (expected or not)."""
        return self.record["outcome"] != "success"

    @property
    def expected_failure(self) -> bool:
        """A failure pytest counted as xfailed: shown apart, not counted among the failures."""
        return self.failed and self.xfail_reason is not None

    @property
    def anchor(self) -> str:
        """The id of this run's failure section (stable: from node id and repeat)."""
        return _anchor(self.record)

    @property
    def subject(self) -> str:
        r = self.record
        return (r.get("subject") or "") + (f" {r['subject_version']}" if r.get("subject_version") else "")


def _fixed(value: Any, digits: int) -> str | None:
    """A number with ``digits`` decimals; None for a missing or NaN value (the page shows a dash)."""
    if value is None or (isinstance(value, float) and value != value):
        return None
    try:
        return f"{float(value):.{digits}f}"
    except (TypeError, ValueError):
        return str(value)


def _rate_parts(k: int, n: int) -> dict[str, str] | None:
    """A rate and its 95 % Wilson interval as percentages (texts), or None when n is 0."""
    from .stats import rate_with_interval
    if n == 0:
        return None
    r, lo, hi = rate_with_interval(k, n)
    return {"rate": f"{100 * r:.1f}", "low": f"{100 * lo:.0f}", "high": f"{100 * hi:.0f}"}


def _data_uri(png: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _view_json(view: dict[str, Any]) -> Any:
    """The viewer's data as JSON that is safe inside a <script> element; None when it has
    NaN/inf (a diverged run: the static plot still shows it)."""
    import json

    from markupsafe import Markup
    try:
        return Markup(json.dumps(view, separators=(",", ":"), allow_nan=False).replace("</", "<\\/"))
    except ValueError:
        return None


def _anchor(rec: dict[str, Any]) -> str:
    import hashlib
    key = f"{rec['nodeid']}#{rec.get('repeat', 0)}"
    return hashlib.sha1(key.encode()).hexdigest()[:12]


def view_data(result: Any, max_points: int = 400) -> dict[str, Any] | None:
    """A compact, JSON-able picture of one episode for the report's interactive viewer: obstacle
    outlines, footprint, goal, and the poses and speeds at up to ``max_points`` instants; moving
    obstacles (``mov``: index into ``obs``, offsets dx/dy at the same instants) move with the slider;
    on terrain the ground's shading, the elements' outlines, the base's height and pitch and where
    it fell or tipped over (``_terrain_view``)."""
    import numpy as np

    from ..scenario.geometry import obstacle_polygon
    from ..scenario.motion import displacement, tracks

    traj = result.trajectory
    n = len(traj.t)
    if n < 2:
        return None
    idx = np.unique(np.linspace(0, n - 1, min(max_points, n)).round().astype(int))
    pose = np.asarray(traj.pose, dtype=float)[idx]
    vel = np.asarray(traj.velocity, dtype=float)[idx]
    s = result.scenario
    fp = s.robot.footprint
    times = np.asarray(traj.t, dtype=float)[idx]
    mov = []
    for j, track in tracks(s.obstacles).items():
        off = displacement(track, times)
        mov.append({"i": j, "dx": np.round(off[:, 0], 3).tolist(), "dy": np.round(off[:, 1], 3).tolist()})
    out = {
        "mov": mov,
        "t": np.round(np.asarray(traj.t, dtype=float)[idx], 2).tolist(),
        "x": np.round(pose[:, 0], 3).tolist(), "y": np.round(pose[:, 1], 3).tolist(),
        "yaw": np.round(pose[:, 2], 3).tolist(), "v": np.round(np.hypot(vel[:, 0], vel[:, 1]), 2).tolist(),
        "obs": [np.round(np.asarray(obstacle_polygon(o).exterior.coords), 3).tolist() for o in s.obstacles],
        "fp": {"shape": fp.shape, "length": fp.length, "width": fp.width, "radius": fp.radius},
        "goal": [s.mission.goal.x, s.mission.goal.y, s.mission.goal_tolerance.position],
        "vmax": max(0.1, float(s.robot.limits.max_speed)),
    }
    if getattr(s, "terrain", ()):
        out.update(_terrain_view(result, idx, pose))
    return out


def _terrain_view(result: Any, idx: Any, pose: Any) -> dict[str, Any]:
    """The view's terrain: the ground's shading (a PNG over ``gnd``'s extent), the elements'
    outlines, the base's height and pitch at the view's instants, where it fell or tipped over."""
    import numpy as np

    from ..scenario.ground import surface as ground
    from .terrain_plot import shading_png, terrain_extent

    s, traj = result.scenario, result.trajectory
    tx, ty = terrain_extent(s)
    x0 = min(tx + pose[:, 0].tolist() + [s.mission.goal.x]) - 1.0
    x1 = max(tx + pose[:, 0].tolist() + [s.mission.goal.x]) + 1.0
    y0 = min(ty + pose[:, 1].tolist() + [s.mission.goal.y]) - 1.0
    y1 = max(ty + pose[:, 1].tolist() + [s.mission.goal.y]) + 1.0
    out: dict[str, Any] = {
        "gnd": {"png": shading_png(s, (x0, x1, y0, y1)), "ext": [round(v, 3) for v in (x0, x1, y0, y1)]},
        "ter": [np.round(ground.outline(el), 3).tolist() for el in s.terrain],
    }
    if getattr(traj, "z", None) is not None and getattr(traj, "pitch", None) is not None:
        out["z"] = np.round(np.asarray(traj.z, dtype=float)[idx], 3).tolist()
        out["pitch"] = np.round(-np.degrees(np.asarray(traj.pitch, dtype=float)[idx]), 1).tolist()
    event = getattr(result, "terrain_event", None)
    if event is not None:
        out["ev"] = {"x": round(event.x, 3), "y": round(event.y, 3), "t": round(event.time - 0.005, 2),
                     "kind": event.kind}       # t rounded down: the view's last instant shows it
    return out


@functools.lru_cache(maxsize=1)
def _environment() -> Any:
    """The Jinja2 environment of the report templates (imported here, when a report is written:
    loading the plugin stays cheap). Autoescaping is on for every template."""
    import jinja2

    env = jinja2.Environment(loader=jinja2.PackageLoader("pytest_navscenario.report", "templates"),
                             autoescape=True, undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True)
    env.filters.update(fixed=_fixed, data_uri=_data_uri, view_json=_view_json, sig3=lambda p: f"{p:.3g}")
    env.globals.update(rate_parts=_rate_parts)
    return env


def _summary(records: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The summary table: outcome columns, one row per family (and 'all' when there are several)."""
    families: dict[str, list[dict[str, Any]]] = {}
    for rec in records:
        families.setdefault(rec.get("family") or "(no family)", []).append(rec)
    groups = sorted(families.items())
    if len(groups) > 1:
        groups.append(("all", list(records)))
    outcomes = [o for o in OUTCOMES if o not in ("subject-error", "fall") or any(r["outcome"] == o for r in records)]
    rows = [{"family": fam, "n": len(recs), "counts": Counter(r["outcome"] for r in recs)} for fam, recs in groups]
    return {"outcomes": outcomes, "rows": rows}


def _comparison(cmp: "Comparison | None") -> dict[str, Any] | None:
    """What the comparison section shows besides the Comparison itself."""
    if cmp is None:
        return None
    from .compare import METRICS as CMP_METRICS
    from .compare import RATE_OUTCOMES

    fams = cmp.families + ([cmp.overall] if len(cmp.families) > 1 else [])
    return {
        "outcomes": [o for o in RATE_OUTCOMES if o not in ("subject-error", "fall")
                     or cmp.overall.a[o].count or cmp.overall.b[o].count],
        "families": fams,
        "metrics": CMP_METRICS,
        "show_metrics": any(f.metrics.get(k, (0, 0, 0))[2] for f in fams for k, _ in CMP_METRICS),
        "metric_pairs": lambda f: max(f.metrics[k][2] for k, _ in CMP_METRICS),
    }


def build_html(entries: Sequence[Entry], *, title: str = "navscenario report",
               comparison: "Comparison | None" = None, bars_png: bytes | None = None,
               info: Sequence[str] = (), template: str = "run_report.html.j2") -> str:
    """The whole report as one HTML string, rendered from ``templates/<template>``
    (``run_report.html.j2``, or ``compare_report.html.j2`` for ``navscenario compare --html``)."""
    records = [e.record for e in entries]
    counts = Counter(r["outcome"] for r in records)
    expected = [e for e in entries if e.expected_failure]
    overview = ", ".join(f"{counts[o]} {o}" for o in OUTCOMES if counts[o]) or "no scenario ran"
    if expected:
        overview += f" ({len(expected)} expected to fail: xfail)"
    return _environment().get_template(template).render(
        title=title, info=list(info), records=records, entries=list(entries),
        stamp=_dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"), overview=overview,
        summary=_summary(records), cmp=comparison, comparison=_comparison(comparison), bars_png=bars_png,
        metrics=METRICS, failures=[e for e in entries if e.failed and not e.expected_failure],
        expected=expected, passing=[e for e in entries if not e.failed and e.plot_png])


def write_html(path: str | os.PathLike, entries: Sequence[Entry], **kwargs: Any) -> Path:
    """Write the report atomically; return its path."""
    path = Path(path)
    atomic_write_text(path, build_html(entries, **kwargs))
    return path
