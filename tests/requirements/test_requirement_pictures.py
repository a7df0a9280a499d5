"""Issue 34, the pictures and the HTML report: the map marks where each violated requirement was
first violated and outlines the regions the signals declare; a figure shows each requirement's
signals over time with the thresholds its formula compares them to and the first violation's time;
the HTML report carries every requirement's robustness and that figure. Real runs, real files."""
from __future__ import annotations

from pathlib import Path

import pytest

import pytest_navscenario.plugin.payload  # noqa: F401  (numpy: in-process runs cannot import it afresh)
from pytest_navscenario import loads_scenario
from pytest_navscenario.harness.runner import run_scenario

ROOT = Path(__file__).resolve().parents[2]
TOUR = (ROOT / "scenarios" / "dock-tour.yaml").read_text()
# the keep-out zone moved onto the robot's line: the seed violates never-in-keep-out at once
INTO = TOUR.replace("[[0.9, 5.0], [2.5, 5.0], [2.5, 7.0], [0.9, 7.0]]", "[[-0.5, 5.0], [2.5, 5.0], [2.5, 7.0], [-0.5, 7.0]]")


def test_the_map_marks_the_first_violation_and_outlines_the_regions():
    from pytest_navscenario.report.plots import trajectory_figure
    result = run_scenario(loads_scenario(INTO), "dwa")
    assert result.outcome.value == "requirement"
    fig = trajectory_figure(result)
    labels = [" ".join(t.get_text().split()) for t in fig.legends[0].get_texts()]   # wrapped entries read as one line
    (when,) = [r.first_violation for r in result.requirements if r.name == "never-in-keep-out"]
    assert f"violated never-in-keep-o… t={when:.1f} s" in labels
    texts = {t.get_text() for t in fig.axes[0].texts}
    assert {"at_a", "at_b", "at_dock", "keepout"} <= texts


def test_the_signals_figure_has_each_requirements_signals_thresholds_and_violation_time():
    from pytest_navscenario.report.requirement_plot import requirements_figure
    result = run_scenario(loads_scenario(INTO), "dwa")
    fig = requirements_figure(result)
    assert len(fig.axes) == 3
    keepout = fig.axes[2]
    assert keepout.get_title(loc="left").startswith("never-in-keep-out: always (keepout <= 0)  (violated")
    legend = [t.get_text() for t in keepout.get_legend().get_texts()]
    assert legend[:2] == ["keepout (m)", "keepout <= 0"] and legend[2].startswith("first violated t=")
    kept = fig.axes[1]
    assert "(kept, robustness" in kept.get_title(loc="left")


def test_the_html_report_carries_each_requirements_robustness_and_its_figure(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    (pytester.path / "scenarios").mkdir()
    (pytester.path / "scenarios" / "into.yaml").write_text(INTO)
    pytester.runpytest("-p", "pytest_navscenario.plugin", "--nav-html=report.html", "scenarios")
    html = (pytester.path / "report.html").read_text()
    assert '<table class="requirements">' in html
    assert '<tr class="violated"><td>never-in-keep-out</td><td><code>always (keepout &lt;= 0)</code></td>' in html
    assert 'alt="scenarios/into.yaml::into requirements over time"' in html or "requirements over time" in html
    assert list((pytester.path / "nav-artifacts").rglob("trajectory-requirements.png"))
