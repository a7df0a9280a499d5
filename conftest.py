"""Root conftest: makes pytest's own ``pytester`` fixture available to the project's tests.

(``pytest examples/scenarios --nav-subject=examples.mynav:Planner`` needs nothing here: a
subject's module is looked up on sys.path, then in the rootdir; see
docs/reference/planner-protocol.md#where-a-subject-is-looked-up.)
"""
pytest_plugins = ["pytester"]

# Folders pytest must not collect (e.g. data files that would look like scenarios) go here.
collect_ignore: list[str] = [
    # frozen failures the picture tests load (tests/report/test_readable_pictures.py): they fail by
    # design, so the default run must not collect them as scenario items
    "tests/data/dock-tip.yaml", "tests/data/person-stop.yaml",
]
