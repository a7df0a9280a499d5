"""Requirements (issue 34): until the STL package (branch ``stl``) is merged, its agreed API is
stood in for by ``stl_stand_in`` (RTAMT underneath), for these tests only."""
from __future__ import annotations

import importlib.util
import sys

if importlib.util.find_spec("pytest_navscenario.stl") is None:
    from pathlib import Path
    _spec = importlib.util.spec_from_file_location("pytest_navscenario.stl", Path(__file__).with_name("stl_stand_in.py"))
    stl_stand_in = importlib.util.module_from_spec(_spec)
    sys.modules["pytest_navscenario.stl"] = stl_stand_in
    _spec.loader.exec_module(stl_stand_in)
    sys.modules["pytest_navscenario.stl"] = stl_stand_in
    import pytest_navscenario
    pytest_navscenario.stl = stl_stand_in
