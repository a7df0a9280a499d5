"""The ``navscenario`` console script.

In: command-line arguments. Out: exit codes and files. Each subcommand lives in its own module
(``run.py``: run and check-planner; ``compare.py``; the importers in ``ros/``), imported only when
it runs, so ``navscenario --help`` stays fast.

Read first: ``main.py`` (the subcommand table and the dispatcher).
"""
from .main import SUBCOMMANDS, build_parser, main  # noqa: F401
