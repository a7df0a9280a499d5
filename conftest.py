"""Root conftest.

* makes pytest's own ``pytester`` fixture available to the project's tests;
* puts the project root on ``sys.path`` so that ``--nav-subject=examples.mynav:Planner`` works
  from a plain checkout (``pytest examples/scenarios --nav-subject=examples.mynav:Planner``);
  pytest loads this file before the plugin loads the subject at session start.
"""
import sys
from pathlib import Path

pytest_plugins = ["pytester"]

_ROOT = str(Path(__file__).resolve().parent)
if _ROOT not in sys.path:
    sys.path.insert(0, _ROOT)

# Folders pytest must not collect (e.g. data files that would look like scenarios) go here.
collect_ignore: list[str] = []
