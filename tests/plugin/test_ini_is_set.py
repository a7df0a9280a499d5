"""Whether an ini option is set (not defaulted) is read without config.inicfg, which pytest 9.2
deprecates: reading it printed a PytestRemovedIn10Warning in every search's summary line
("1 passed, 1 warning"), in a fresh install."""
from __future__ import annotations

import warnings

import pytest

from pytest_navscenario.plugin.options import ini_is_set
from pytest_navscenario.plugin.search_report import _plots_asked


def _deprecated(self):      # what pytest >= 9.2 does on every read of config.inicfg
    warnings.warn(pytest.PytestRemovedIn10Warning("config.inicfg is deprecated"), stacklevel=2)
    return {}


def test_ini_is_set_tells_a_set_value_from_the_default_without_inicfg(pytester, monkeypatch):
    pytester.makeini("[pytest]\nnav_plots = all\n")
    config = pytester.parseconfig()
    overridden = pytester.parseconfig("-o", "nav_html=search.html")
    monkeypatch.setattr(pytest.Config, "inicfg", property(_deprecated))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _plots_asked(config)
        assert ini_is_set(config, "nav_plots") and not ini_is_set(config, "nav_html")
        assert ini_is_set(overridden, "nav_html") and not ini_is_set(overridden, "nav_html_x")
