"""The IPC 2020 total-order HTN track, planned by ``shary plan --hddl ... --ipc``.

Each problem is planned by the command, in a process of its own, one at a time,
within ``--cutoff`` seconds of wall time for the whole command (reading,
search, our validator, the IPC output); a plan counts only if the track's own
verifier, pandaPIparser's ``-v`` (given with ``--verifier``), accepts it.  That
verifier is independent of the search and of our validator: it is the C++
program the IPC 2020 organisers wrote, reading the HDDL files itself, and it
checks the plan's decomposition tree against the methods and the actions'
executability from the initial state.

The track is the public repository ``panda-planner-dev/ipc2020-domains``
(folder ``total-order``): clone it and give the folder::

    python benchmarks/ipc_track.py ~/ipc2020-domains/total-order \\
        --verifier ~/pandaPIparser/pandaPIparser [--cutoff 30] [--only Towers,Transport]
        [--problems 'pfile_1*'] [--every 10] [--verify-timeout 120] [--json]

A problem is every ``*.hddl`` file of a domain's folder whose name does not
contain ``domain``; its domain is ``domain.hddl`` beside it, or
``NAME-domain.hddl`` (Entertainment, Monroe).  The folders hold the 892 problems
the IPC used (Robot's and Woodworking's further instances are in sub-folders,
not read).
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ACCEPTED = "Plan verification result: \x1b[1;32mtrue"
"""What pandaPIparser prints (colour codes included) when it accepts a plan."""


def problems(domain_dir: Path, pattern: str) -> list[tuple[Path, Path]]:
    """The (domain file, problem file) pairs of one domain's folder, in name order."""
    out = []
    for path in sorted(domain_dir.glob("*.hddl")):
        if "domain" in path.name or not fnmatch.fnmatch(path.stem, pattern):
            continue
        domain = domain_dir / "domain.hddl"
        if not domain.exists():
            domain = path.with_name(path.stem + "-domain.hddl")
        out.append((domain, path))
    return out


def run_one(shary: str, verifier: str, domain: Path, problem: Path, cutoff: float,
            plan_file: Path, verify_s: float) -> tuple[str, float]:
    """``solved``, ``unsolved``, ``invalid`` (the verifier refused the plan),
    ``unverified`` (a plan our validator accepted, which the verifier did not finish
    checking in ``verify_s``: its time grows steeply with the plan, 7 s for Towers'
    2,047 moves, minutes beyond 8,000), ``timeout`` or ``unreadable`` (the command
    refused a file), and the wall time."""
    start = time.perf_counter()
    try:
        done = subprocess.run([shary, "plan", "--hddl", str(domain), str(problem), "--ipc",
                               "--budget-ms", str(int(cutoff * 1000))],
                              capture_output=True, text=True, timeout=cutoff)
    except subprocess.TimeoutExpired:
        return "timeout", time.perf_counter() - start
    wall = time.perf_counter() - start
    if done.returncode != 0 or "==>" not in done.stdout:
        return ("unreadable" if done.returncode == 2 else "unsolved"), wall
    plan_file.write_text(done.stdout)
    try:
        checked = subprocess.run([verifier, "-v", str(domain), str(problem), str(plan_file)],
                                 capture_output=True, text=True, timeout=verify_s)
    except subprocess.TimeoutExpired:
        return "unverified", wall
    return ("solved" if ACCEPTED in checked.stdout else "invalid"), wall


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("track", type=Path, help="the track's total-order folder")
    parser.add_argument("--verifier", required=True, help="pandaPIparser's executable")
    parser.add_argument("--cutoff", type=float, default=30.0, help="seconds per problem")
    parser.add_argument("--verify-timeout", type=float, default=120.0,
                        help="seconds the verifier may take for one plan")
    parser.add_argument("--only", default="", help="domains (folder names), comma-separated")
    parser.add_argument("--problems", default="*", help="problem names (a glob on the stem)")
    parser.add_argument("--every", type=int, default=1,
                        help="a sample: the first problem of each domain, then every Nth")
    parser.add_argument("--json", action="store_true", help="one JSON document at the end")
    args = parser.parse_args()
    shary = shutil.which("shary") or str(Path(sys.executable).with_name("shary"))
    chosen = [d for d in args.only.split(",") if d]
    results: dict[str, dict[str, str]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for domain_dir in sorted(p for p in args.track.iterdir() if p.is_dir()):
            if chosen and domain_dir.name not in chosen:
                continue
            found = problems(domain_dir, args.problems)[::max(1, args.every)]
            if not found:
                continue
            outcome = results.setdefault(domain_dir.name, {})
            for domain, problem in found:
                status, wall = run_one(shary, args.verifier, domain, problem, args.cutoff,
                                       Path(tmp) / "plan.txt", args.verify_timeout)
                outcome[problem.name] = status
                print(f"{domain_dir.name:32s} {problem.name:48s} {status:10s} {wall:6.1f} s",
                      file=sys.stderr, flush=True)
            solved = sum(s == "solved" for s in outcome.values())
            unverified = sum(s == "unverified" for s in outcome.values())
            print(f"{domain_dir.name}: {solved}/{len(outcome)}"
                  + (f" (+{unverified} unverified)" if unverified else ""), flush=True)
    total = sum(len(o) for o in results.values())
    solved = sum(s == "solved" for o in results.values() for s in o.values())
    invalid = sum(s == "invalid" for o in results.values() for s in o.values())
    unverified = sum(s == "unverified" for o in results.values() for s in o.values())
    print(f"total: {solved}/{total} solved and verified, {unverified} unverified, "
          f"{invalid} invalid "
          f"(cutoff {args.cutoff:g} s, {time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores)")
    if args.json:
        print(json.dumps({"cutoff_s": args.cutoff, "solved": solved, "problems": total,
                          "unverified": unverified, "invalid": invalid, "domains": results}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
