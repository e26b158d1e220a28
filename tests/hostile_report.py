"""Run every hostile corpus and print, per format, its files and its costliest runs.

    python tests/hostile_report.py [--json]

The tests assert the rule (exit 2 at a line of the file, no traceback, under
10 s of CPU time and 500 MB); this script says by how much each format stays inside it.
The figures come from the harness itself (``tests/hostile.py``), which notes
every run it measures when ``SHARY_HOSTILE_REPORT`` names a file.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def main() -> int:
    with tempfile.TemporaryDirectory() as scratch:
        report = Path(scratch) / "runs.jsonl"
        env = dict(os.environ, SHARY_HOSTILE_REPORT=str(report))
        tests = sorted(str(p) for p in TESTS.glob("test_hostile_*.py"))
        done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                               *tests], env=env, cwd=TESTS.parent, capture_output=True,
                              text=True)
        runs = [json.loads(line) for line in report.read_text().splitlines()] \
            if report.exists() else []
    per: dict[str, list[dict]] = defaultdict(list)
    for run in runs:
        per[Path(run["test"].split("::")[0]).stem.removeprefix("test_hostile_")].append(run)
    rows = []
    for fmt in sorted(per):
        folder = TESTS / "hostile" / fmt
        if not folder.is_dir():  # test_hostile_zenoh_config.py reads hostile/zenoh-config/
            folder = TESTS / "hostile" / fmt.replace("_", "-")
        kept = folder.rglob("*") if folder.is_dir() else ()
        files = sum(1 for p in kept if p.is_file() and p.suffix not in (".md", ".py"))
        slowest = max(per[fmt], key=lambda r: r["seconds"])
        largest = max(per[fmt], key=lambda r: r["peak_mb"])
        rows.append({"format": fmt, "files": files, "runs": len(per[fmt]),
                     "slowest_s": round(slowest["seconds"], 2), "slowest": slowest["test"],
                     "largest_mb": round(largest["peak_mb"], 1), "largest": largest["test"],
                     "largest_mode": largest["mode"]})
    if "--json" in sys.argv[1:]:
        print(json.dumps(rows))
    else:
        print(f"{'format':<10} {'files':>5} {'runs':>5} {'slowest':>8} {'largest':>9}")
        for r in rows:
            print(f"{r['format']:<10} {r['files']:>5} {r['runs']:>5} {r['slowest_s']:>7.2f}s "
                  f"{r['largest_mb']:>7.1f}MB  ({r['largest_mode']})")
        print(done.stdout.strip().splitlines()[-1] if done.stdout.strip() else done.stderr[-500:])
    return done.returncode


if __name__ == "__main__":
    sys.exit(main())
