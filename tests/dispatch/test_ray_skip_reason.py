"""Without Ray installed, the Ray test modules skip, and the default summary (-rs in addopts) says
why and how to run them."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_ray_tests_say_how_to_run_them_when_ray_is_missing():
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    code = ("import sys; sys.modules['ray'] = None\n"          # 'import ray' now fails as if not installed
            "import pytest; sys.exit(pytest.main(['-p', 'no:xdist', 'tests/dispatch/test_ray_local.py', "
            "'tests/dispatch/test_ray_cluster.py']))")
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=120)
    out = proc.stdout + proc.stderr
    assert proc.returncode in (0, 5), out           # 5: every module skipped, so no test ran
    summary = out.split("short test summary info", 1)[-1]
    assert summary.count("SKIPPED") == 2, out
    assert summary.count("pip install -e '.[ray]'") == 2 and "pytest tests/dispatch -n 2" in summary, out
