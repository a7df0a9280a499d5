"""pytest plugin entry point (hooks only). Filled in by the plugin work (issue 3).

Feature plugins live in their own modules and are registered through ``pytest_plugins`` so
that each stays small: search, reports/comparison, bags.
"""
pytest_plugins = [
    "pytest_navscenario.search_plugin",
    "pytest_navscenario.report_plugin",
    "pytest_navscenario.bag_plugin",
]
