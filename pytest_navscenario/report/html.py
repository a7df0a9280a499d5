"""One self-contained HTML report (``--nav-html=report.html``): opens from disk, no server, no
internet. Images are embedded as base64 PNG, CSS and the few lines of sorting JavaScript inline.

Contents: the run's summary per family (rates with 95 % Wilson intervals), the comparison with a
baseline when one was given (table, bar chart, regressions with their reproduce commands), a table
of every scenario run (click a column header to sort, e.g. by family or outcome), and one entry per
failure with its message, reproduce command, main metrics and trajectory plot.
"""
from __future__ import annotations

import base64
import datetime as _dt
import html
import os
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from ..core.files import atomic_write_text

if TYPE_CHECKING:  # pragma: no cover
    from .compare import Comparison

OUTCOMES = ("success", "safety-stop", "timeout", "collision", "subject-error")
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


    @property
    def failed(self) -> bool:
        return self.record["outcome"] != "success"


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _num(value: Any, digits: int) -> str:
    if value is None or (isinstance(value, float) and value != value):
        return "&ndash;"
    try:
        return f"{float(value):.{digits}f}"
    except (TypeError, ValueError):
        return _e(value)


def _img(png: bytes | None, alt: str) -> str:
    if not png:
        return ('<p class="muted">(no plot: no trajectory was kept for this run; pytest --nav-html plots '
                'every failure, navscenario compare --side-by-side re-runs regressions)</p>')
    data = base64.b64encode(png).decode("ascii")
    return f'<img alt="{_e(alt)}" src="data:image/png;base64,{data}">'


def _badge(outcome: str) -> str:
    return f'<span class="badge o-{_e(outcome)}">{_e(outcome)}</span>'


def _rate(k: int, n: int) -> str:
    from .stats import rate_with_interval
    if n == 0:
        return "&ndash;"
    r, lo, hi = rate_with_interval(k, n)
    return f"{100 * r:.1f}% <small>[{100 * lo:.0f}&ndash;{100 * hi:.0f}]</small>"


def _summary_table(records: Sequence[dict[str, Any]]) -> str:
    families: dict[str, list[dict[str, Any]]] = {}
    for rec in records:
        families.setdefault(rec.get("family") or "(no family)", []).append(rec)
    rows = sorted(families.items())
    if len(rows) > 1:
        rows.append(("all", list(records)))
    outcomes = [o for o in OUTCOMES if o != "subject-error" or any(r["outcome"] == o for r in records)]
    head = "".join(f"<th>{_e(o)}</th>" for o in outcomes)
    body = []
    for fam, recs in rows:
        counts = Counter(r["outcome"] for r in recs)
        cells = "".join(f"<td>{_rate(counts[o], len(recs))}</td>" for o in outcomes)
        body.append(f"<tr><td>{_e(fam)}</td><td>{len(recs)}</td>{cells}</tr>")
    return (f'<table class="summary"><thead><tr><th>family</th><th>n</th>{head}</tr></thead>'
            f"<tbody>{''.join(body)}</tbody></table>")


def _comparison_section(cmp: "Comparison", bars_png: bytes | None) -> str:
    from .compare import RATE_OUTCOMES

    outs = [o for o in RATE_OUTCOMES if o != "subject-error"
            or cmp.overall.a[o].count or cmp.overall.b[o].count]
    head = "".join(f"<th>{_e(o)}</th>" for o in outs)
    rows = []
    for fam in cmp.families + ([cmp.overall] if len(cmp.families) > 1 else []):
        for side in ("a", "b"):
            rates = getattr(fam, side)
            cells = "".join(f"<td>{_rate(rates[o].count, rates[o].n)}</td>" for o in outs)
            if side == "a":
                rows.append(f'<tr><td rowspan="2">{_e(fam.family)}</td><td rowspan="2">{fam.n}</td>'
                            f"<td>A</td>{cells}<td rowspan=\"2\">{_change(fam)}</td>"
                            f'<td rowspan="2">{fam.broke}</td><td rowspan="2">{fam.fixed}</td>'
                            f'<td rowspan="2">{fam.mcnemar_p:.3g}</td></tr>')
            else:
                rows.append(f"<tr><td>B</td>{cells}</tr>")
    parts = [
        "<section id=\"comparison\"><h2>Comparison with the baseline</h2>",
        f"<p>A = <code>{_e(cmp.a_name)}</code> ({_e(cmp.a_subject)}), "
        f"B = <code>{_e(cmp.b_name)}</code> ({_e(cmp.b_subject)}). {len(cmp.pairs)} paired scenario runs (by node id and "
        f"repeat index); rates over these pairs with 95 % Wilson intervals; p = exact McNemar test.</p>",
        f'<table class="summary"><thead><tr><th>family</th><th>n</th><th></th>{head}<th>change</th>'
        f"<th>broke</th><th>fixed</th><th>p</th></tr></thead><tbody>{''.join(rows)}</tbody></table>",
    ]
    from .compare import METRICS as CMP_METRICS
    fams = cmp.families + ([cmp.overall] if len(cmp.families) > 1 else [])
    if any(f.metrics.get(k, (0, 0, 0))[2] for f in fams for k, _ in CMP_METRICS):
        mhead = "".join(f"<th>{_e(label)}</th>" for _, label in CMP_METRICS)
        mrows = "".join(
            f"<tr><td>{_e(f.family)}</td><td>{max(f.metrics[k][2] for k, _ in CMP_METRICS)}</td>"
            + "".join(f"<td>{_num(f.metrics[k][0], 2)} &rarr; {_num(f.metrics[k][1], 2)}</td>"
                      for k, _ in CMP_METRICS) + "</tr>" for f in fams)
        parts.append(f"<p>Metrics over the pairs both passed (median A &rarr; B):</p>"
                     f'<table class="summary"><thead><tr><th>family</th><th>n</th>{mhead}</tr></thead>'
                     f"<tbody>{mrows}</tbody></table>")
    if bars_png:
        parts.append(f'<div class="plot">{_img(bars_png, "success and safety-stop rates, A vs B")}</div>')
    for title, items, cls in (("B broke (A passed, B failed)", cmp.broke, "bad"),
                              ("B fixed (A failed, B passed)", cmp.fixed, "good")):
        if items:
            lis = "".join(
                f"<li><code>{_e(p.label)}</code>: A {_badge(p.a['outcome'])} &rarr; B {_badge(p.b['outcome'])}"
                f"<br><code class=\"cmd\">{_e(cmp.reproduce_command(p))}</code></li>" for p in items)
            parts.append(f'<h3 class="{cls}">{_e(title)} ({len(items)})</h3><ul>{lis}</ul>')
    unpaired = cmp.not_comparable + cmp.only_a + cmp.only_b
    if unpaired:
        lis = "".join(f"<li><code>{_e(u.label)}</code>: {_e(u.reason)}</li>" for u in unpaired)
        parts.append(f"<h3>Not compared ({len(unpaired)})</h3><ul>{lis}</ul>")
    for w in cmp.warnings:
        parts.append(f'<p class="bad">warning: {_e(w)}</p>')
    parts.append("</section>")
    return "".join(parts)


def _change(fam: Any) -> str:
    if fam.n == 0:
        return "&ndash;"
    return f"{100 * fam.success_change:+.1f} pp"


def _runs_table(entries: Sequence[Entry]) -> str:
    head = ("<th data-type=\"text\">scenario</th><th data-type=\"text\">family</th>"
            "<th data-type=\"text\">outcome</th>"
            + "".join(f'<th data-type="num">{_e(label)}</th>' for _, label, _ in METRICS)
            + '<th data-type="text">message</th>')
    rows = []
    for e in entries:
        r = e.record
        m = r.get("metrics") or {}
        link = (f'<a href="#f-{_anchor(r)}">{_e(r["nodeid"])}</a>' if e.failed else _e(r["nodeid"]))
        cells = "".join(f'<td data-v="{_e(m.get(k) if m.get(k) is not None else "")}">{_num(m.get(k), d)}</td>'
                        for k, _, d in METRICS)
        rows.append(f'<tr><td>{link}</td><td>{_e(r.get("family", ""))}</td>'
                    f'<td data-v="{_e(r["outcome"])}">{_badge(r["outcome"])}</td>{cells}'
                    f'<td class="msg">{_e(r.get("message", ""))}</td></tr>')
    return (f'<table class="sortable" id="runs"><thead><tr>{head}</tr></thead>'
            f"<tbody>{''.join(rows)}</tbody></table>")


def _anchor(rec: dict[str, Any]) -> str:
    import hashlib
    key = f"{rec['nodeid']}#{rec.get('repeat', 0)}"
    return hashlib.sha1(key.encode()).hexdigest()[:12]


def view_data(result: Any, max_points: int = 400) -> dict[str, Any] | None:
    """A compact, JSON-able picture of one episode for the report's interactive viewer: obstacle
    outlines, footprint, goal, and the poses and speeds at up to ``max_points`` instants."""
    import numpy as np

    from ..scenario.geometry import obstacle_polygon

    traj = result.trajectory
    n = len(traj.t)
    if n < 2:
        return None
    idx = np.unique(np.linspace(0, n - 1, min(max_points, n)).round().astype(int))
    pose = np.asarray(traj.pose, dtype=float)[idx]
    vel = np.asarray(traj.velocity, dtype=float)[idx]
    s = result.scenario
    fp = s.robot.footprint
    return {
        "t": np.round(np.asarray(traj.t, dtype=float)[idx], 2).tolist(),
        "x": np.round(pose[:, 0], 3).tolist(), "y": np.round(pose[:, 1], 3).tolist(),
        "yaw": np.round(pose[:, 2], 3).tolist(), "v": np.round(np.hypot(vel[:, 0], vel[:, 1]), 2).tolist(),
        "obs": [np.round(np.asarray(obstacle_polygon(o).exterior.coords), 3).tolist() for o in s.obstacles],
        "fp": {"shape": fp.shape, "length": fp.length, "width": fp.width, "radius": fp.radius},
        "goal": [s.mission.goal.x, s.mission.goal.y, s.mission.goal_tolerance.position],
        "vmax": max(0.1, float(s.robot.limits.max_speed)),
    }


def _viewer(view: dict[str, Any] | None) -> str:
    if not view:
        return ""
    import json
    try:
        data = json.dumps(view, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    except ValueError:  # NaN/inf in a diverged run: the static plot still shows it
        return ""
    return ('<div class="viewer"><canvas width="420" height="420"></canvas><br>'
            '<input type="range" min="0" step="1" aria-label="time"> <span class="t"></span>'
            f'<script type="application/json" class="nav-view">{data}</script></div>')


def _failure(e: Entry) -> str:
    r = e.record
    m = r.get("metrics") or {}
    facts = "".join(f"<dt>{_e(label)}</dt><dd>{_num(m.get(k), d)}</dd>" for k, label, d in METRICS)
    subject = (r.get("subject") or "") + (f" {r['subject_version']}" if r.get("subject_version") else "")
    cmd = f'<p>reproduce: <code class="cmd">{_e(e.reproduce)}</code></p>' if e.reproduce else ""
    return (f'<section class="failure" id="f-{_anchor(r)}" data-family="{_e(r.get("family", ""))}" '
            f'data-outcome="{_e(r["outcome"])}" data-nodeid="{_e(r["nodeid"])}">'
            f"<h3>{_badge(r['outcome'])} <code>{_e(r['nodeid'])}</code></h3>"
            f"<p>{_e(r.get('message', ''))}</p>"
            f"<p class=\"muted\">family {_e(r.get('family', ''))} &middot; subject {_e(subject)} "
            f"&middot; seed {_e(r.get('seed'))} &middot; repeat {_e(r.get('repeat', 0))}</p>{cmd}"
            f'<div class="facts"><dl>{facts}</dl><div class="plot">{_img(e.plot_png, r["nodeid"])}</div>'
            f"{_viewer(e.view)}</div>"
            + (f'<p>The same scenario under the baseline and now:</p><div class="plot">'
               f'{_img(e.compare_png, r["nodeid"] + " side by side")}</div>' if e.compare_png else "")
            + "</section>")


def _passing_plots(entries: Sequence[Entry]) -> str:
    """Plots of passing runs (with --nav-plots=all), folded away below the failures."""
    if not entries:
        return ""
    items = "".join(
        f'<section class="passed"><h3>{_badge(e.record["outcome"])} <code>{_e(e.record["nodeid"])}</code></h3>'
        f'<div class="plot">{_img(e.plot_png, e.record["nodeid"])}</div></section>' for e in entries)
    return (f"<h2>Passing runs with a plot ({len(entries)})</h2>"
            f"<details><summary>show the plots</summary>{items}</details>")


CSS = """
body{font:14px/1.4 system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:1.5em auto;max-width:1280px;padding:0 1em;color:#212121}
h1{font-size:1.5em}h2{border-bottom:1px solid #ddd;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0}th,td{border:1px solid #ddd;padding:3px 8px;text-align:right;vertical-align:top}
th{background:#f5f5f5}td:first-child,th:first-child,td.msg{text-align:left}
table.sortable th{cursor:pointer;user-select:none}table.sortable th:after{content:" \\2195";color:#aaa}
.badge{display:inline-block;padding:0 .5em;border-radius:.7em;color:#fff;font-size:.85em;font-weight:600}
.o-success{background:#2e7d32}.o-collision{background:#c62828}.o-safety-stop{background:#ef6c00}
.o-timeout{background:#6a1b9a}.o-subject-error{background:#37474f}
.muted{color:#757575}.bad{color:#c62828}.good{color:#2e7d32}code.cmd{background:#f5f5f5;padding:1px 4px}
section.failure{border:1px solid #e0e0e0;border-radius:6px;padding:.4em 1em;margin:1em 0}
.facts{display:flex;gap:1.5em;align-items:flex-start;flex-wrap:wrap}dl{display:grid;grid-template-columns:auto auto;gap:2px 10px;margin:0}
dt{color:#616161}dd{margin:0}.plot img{max-width:100%;height:auto}
.controls button{margin-right:.5em}.viewer canvas{border:1px solid #e0e0e0}.viewer input{width:420px}
"""

JS = """
function cellValue(row, i, type){var c=row.cells[i];var v=c.getAttribute('data-v');if(v===null)v=c.textContent;
 if(type==='num'){var f=parseFloat(v);return isNaN(f)?Infinity:f;}return v.toLowerCase();}
document.querySelectorAll('table.sortable th').forEach(function(th,i){th.addEventListener('click',function(){
 var table=th.closest('table'),tbody=table.tBodies[0],type=th.getAttribute('data-type');
 var asc=th.getAttribute('data-asc')!=='1';table.querySelectorAll('th').forEach(function(h){h.removeAttribute('data-asc');});
 if(asc)th.setAttribute('data-asc','1');
 var rows=Array.prototype.slice.call(tbody.rows);rows.sort(function(a,b){var x=cellValue(a,i,type),y=cellValue(b,i,type);
  return (x<y?-1:x>y?1:0)*(asc?1:-1);});rows.forEach(function(r){tbody.appendChild(r);});});});
function navViewer(box){
 var d=JSON.parse(box.querySelector('script.nav-view').textContent);
 var cv=box.querySelector('canvas'),ctx=cv.getContext('2d'),sl=box.querySelector('input'),lab=box.querySelector('.t');
 var xs=d.x.concat([d.goal[0]]),ys=d.y.concat([d.goal[1]]);
 d.obs.forEach(function(p){p.forEach(function(q){xs.push(q[0]);ys.push(q[1]);});});
 var x0=Math.min.apply(null,xs)-1,x1=Math.max.apply(null,xs)+1,y0=Math.min.apply(null,ys)-1,y1=Math.max.apply(null,ys)+1;
 var s=Math.min(cv.width/(x1-x0),cv.height/(y1-y0));
 function X(x){return (x-x0)*s;} function Y(y){return cv.height-(y-y0)*s;}
 function poly(p){ctx.beginPath();p.forEach(function(q,i){if(i)ctx.lineTo(X(q[0]),Y(q[1]));else ctx.moveTo(X(q[0]),Y(q[1]));});ctx.closePath();}
 function robot(i){var c=Math.cos(d.yaw[i]),n=Math.sin(d.yaw[i]),l=d.fp.length/2,w=d.fp.width/2;
  if(d.fp.shape==='circle'){ctx.beginPath();ctx.arc(X(d.x[i]),Y(d.y[i]),d.fp.radius*s,0,2*Math.PI);return;}
  poly([[l,w],[-l,w],[-l,-w],[l,-w]].map(function(q){return [d.x[i]+c*q[0]-n*q[1],d.y[i]+n*q[0]+c*q[1]];}));}
 function draw(i){ctx.clearRect(0,0,cv.width,cv.height);ctx.fillStyle='#9e9e9e';
  d.obs.forEach(function(p){poly(p);ctx.fill();});
  ctx.strokeStyle='#2e7d32';ctx.beginPath();ctx.arc(X(d.goal[0]),Y(d.goal[1]),Math.max(3,d.goal[2]*s),0,2*Math.PI);ctx.stroke();
  ctx.lineWidth=2;for(var k=1;k<d.x.length;k++){var f=Math.min(1,d.v[k]/d.vmax);
   ctx.strokeStyle='hsl('+Math.round(260-200*f)+',75%,'+(k<=i?45:80)+'%)';ctx.beginPath();
   ctx.moveTo(X(d.x[k-1]),Y(d.y[k-1]));ctx.lineTo(X(d.x[k]),Y(d.y[k]));ctx.stroke();}
  ctx.strokeStyle='#d50000';robot(i);ctx.stroke();ctx.lineWidth=1;
  lab.textContent='t = '+d.t[i].toFixed(2)+' s, speed '+d.v[i].toFixed(2)+' m/s (drag to replay)';}
 sl.max=String(d.x.length-1);sl.value=sl.max;sl.addEventListener('input',function(){draw(+sl.value);});draw(d.x.length-1);}
document.querySelectorAll('.viewer').forEach(navViewer);
function sortFailures(key){var box=document.getElementById('failures');
 var items=Array.prototype.slice.call(box.querySelectorAll('section.failure'));
 items.sort(function(a,b){var x=a.dataset[key]+'\\u0000'+a.dataset.nodeid,y=b.dataset[key]+'\\u0000'+b.dataset.nodeid;
  return x<y?-1:x>y?1:0;});items.forEach(function(s){box.appendChild(s);});}
"""


def build_html(entries: Sequence[Entry], *, title: str = "navscenario report",
               comparison: "Comparison | None" = None, bars_png: bytes | None = None,
               info: Sequence[str] = ()) -> str:
    """The whole report as one HTML string."""
    records = [e.record for e in entries]
    failures = [e for e in entries if e.failed]
    counts = Counter(r["outcome"] for r in records)
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines = "".join(f"<li>{_e(i)}</li>" for i in info)
    overview = ", ".join(f"{counts[o]} {o}" for o in OUTCOMES if counts[o]) or "no scenario ran"
    parts = [
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">",
        f"<meta name=\"viewport\" content=\"width=device-width,initial-scale=1\"><title>{_e(title)}</title>",
        f"<style>{CSS}</style></head><body>",
        f"<h1>{_e(title)}</h1><p class=\"muted\">{stamp} &middot; {len(records)} scenario run(s): {_e(overview)}</p>",
        f"<ul class=\"muted\">{lines}</ul>" if lines else "",
        "<h2>Summary per family</h2><p>Outcome rates with 95 % Wilson intervals.</p>",
        _summary_table(records) if records else "<p>No scenario ran.</p>",
        _comparison_section(comparison, bars_png) if comparison is not None else "",
        "<h2>All scenario runs</h2><p class=\"muted\">Click a column header to sort.</p>",
        _runs_table(entries),
        f"<h2>Failures ({len(failures)})</h2>",
        ('<p class="controls">sort by: <button onclick="sortFailures(\'family\')">family</button>'
         '<button onclick="sortFailures(\'outcome\')">outcome</button>'
         '<button onclick="sortFailures(\'nodeid\')">scenario</button></p>') if failures else "<p>None.</p>",
        "<div id=\"failures\">", "".join(_failure(e) for e in failures), "</div>",
        _passing_plots([e for e in entries if not e.failed and e.plot_png]),
        f"<script>{JS}</script></body></html>",
    ]
    return "\n".join(p for p in parts if p)


def write_html(path: str | os.PathLike, entries: Sequence[Entry], **kwargs: Any) -> Path:
    """Write the report atomically; return its path."""
    path = Path(path)
    atomic_write_text(path, build_html(entries, **kwargs))
    return path
