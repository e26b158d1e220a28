"""The benchmark scripts start as docs/benchmarks.md shows them (their figures are not
tested: timings are the scripts' business)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_a_benchmark_beside_benchmarks_planner_py_imports_the_planner_package():
    """``benchmarks/planner.py`` sits in the folder a script runs from, first on the path:
    ``benchmarks/_first.py`` makes ``import planner`` the package all the same."""
    done = subprocess.run([sys.executable, "benchmarks/scenarios.py", "--help"], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "--only" in done.stdout
