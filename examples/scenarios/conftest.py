"""Registers the custom mark the example scenarios use (``marks: [obstacles]`` in YAML), so that
``pytest examples/scenarios -m obstacles`` selects them without an unknown-mark warning.
In your own project, put the same line in pytest.ini / pyproject.toml ``markers`` instead."""


def pytest_configure(config):
    config.addinivalue_line("markers", "obstacles: scenarios with at least one obstacle")
