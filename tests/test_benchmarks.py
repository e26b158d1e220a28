"""The benchmark scripts start as docs/benchmarks.md shows them (their figures are not
tested: timings are the scripts' business)."""

from __future__ import annotations

import json
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


def test_the_ipc_track_benchmark_counts_plans_the_verifier_accepts(tmp_path):
    """``benchmarks/ipc_track.py`` finds each domain's problems (``domain.hddl`` beside them
    or ``NAME-domain.hddl``), plans them with ``shary plan --ipc`` and counts a plan only if
    the verifier accepts it.  The verifier here is a stand-in that accepts a plan naming
    ``Load BigCrate`` as the files spell it (pandaPIparser compares names so)."""
    from test_planner_hddl_ipc import MIXED, MIXED_PROBLEM

    track = tmp_path / "total-order"
    for folder, domain_name in (("Shared", "domain.hddl"), ("Own", "p1-domain.hddl")):
        (track / folder).mkdir(parents=True)
        (track / folder / domain_name).write_text(MIXED)
        (track / folder / "p1.hddl").write_text(MIXED_PROBLEM)
    (track / "Own" / "p2-domain.hddl").write_text(MIXED)
    unsolvable = MIXED_PROBLEM.replace("(At BigCrate)", "(Done BigCrate)")
    (track / "Own" / "p2.hddl").write_text(unsolvable)
    verifier = tmp_path / "verify.py"
    verifier.write_text(
        "import sys\n"
        "ok = '0 Load BigCrate' in open(sys.argv[-1]).read()\n"
        "print('Plan verification result: \\x1b[1;32mtrue' if ok else 'false')\n")
    verifier.chmod(0o755)
    wrapper = tmp_path / "verify"
    wrapper.write_text(f"#!/bin/sh\nexec {sys.executable} {verifier} \"$@\"\n")
    wrapper.chmod(0o755)
    done = subprocess.run([sys.executable, "benchmarks/ipc_track.py", str(track), "--verifier",
                           str(wrapper), "--cutoff", "60", "--json"], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "Own: 1/1" not in done.stdout and "Own: 1/2" in done.stdout
    assert "Shared: 1/1" in done.stdout
    assert '"p2.hddl": "unsolved"' in done.stdout


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


def test_the_kernel_benchmark_runs_its_chain_and_counts_the_tasks_given_up():
    """``benchmarks/kernel.py`` on a small world: every look away of a partner whose task is
    still there stops its arm (the script asserts it), and partners who kept looking away
    are counted, not taken for a lost cancel."""
    done = subprocess.run([sys.executable, "benchmarks/kernel.py", "--json", "--tasks", "20",
                           "--changes", "600", "--repeat", "2"], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    figures = json.loads(done.stdout.splitlines()[-1])
    assert figures["tasks"] == 20 and figures["given_up"] > 0
