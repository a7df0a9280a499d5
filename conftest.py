"""Root conftest: makes pytest's own ``pytester`` fixture available to the project's tests.

(``pytest examples/scenarios --nav-subject=examples.mynav:Planner`` needs nothing here: a
subject's module is looked up on sys.path, then in the rootdir; see
docs/reference/planner-protocol.md#where-a-subject-is-looked-up.)
"""
pytest_plugins = ["pytester"]

# Folders pytest must not collect (e.g. data files that would look like scenarios) go here.
# (Scenario files that tests load as data are kept as .txt in tests/data, e.g. dock-tip.txt, so that
# no run collects them.)
collect_ignore: list[str] = []
