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


def test_the_scenarios_benchmark_stops_at_a_scenario_that_fails(tmp_path):
    """A scenario that does not do its job has no time worth reporting: the benchmark
    stops, exit status 1, and says which scenario failed and how."""
    import shutil

    folder = shutil.copytree(ROOT / "docs" / "tutorial", tmp_path / "tutorial")
    scenario = folder / "tidy-table.yaml"
    scenario.write_text(scenario.read_text(encoding="utf-8").replace("within: 60s",
                                                                     "within: 1s"),
                        encoding="utf-8")
    done = subprocess.run([sys.executable, "benchmarks/scenarios.py", "--only", str(scenario),
                           "--repeat", "1", "--json"], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 1, done.stderr
    assert "scenario " + str(scenario) + " failed" in done.stderr
    assert "expected the run to be over within 1s" in done.stderr
    assert done.stdout == ""
