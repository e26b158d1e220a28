"""Start-up of the ``shary`` command: what the registry of commands costs.

``shary`` builds its parser from the entry points that packages register
(docs/cli.md): finding them in the installed metadata and importing every
command module is paid on each command.  Measured, in child processes, CPU
time (user + system; the machines here are shared, so wall time counts the
neighbours' work too), median of N runs, interleaved so that load affects all
alike:

* ``python -c "import shary"``: the peer and floor, the engine's own import,
  which any command pays;
* ``shary --help``: the floor plus the registry (every command module loaded,
  the parser built);
* ``shary schemes``: a command that does a little work.

    python benchmarks/cli.py [--json] [--runs N]
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys

CASES = {
    "import shary (peer)": [sys.executable, "-c", "import shary"],
    "shary --help": [sys.executable, "-m", "shary", "--help"],
    "shary schemes": [sys.executable, "-m", "shary", "schemes"],
}


def cpu_seconds(argv: list[str]) -> float:
    """CPU time (user + system) of one child running ``argv``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=10)
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args()
    samples: dict[str, list[float]] = {name: [] for name in CASES}
    for _ in range(args.runs):
        for name, argv in CASES.items():
            samples[name].append(cpu_seconds(argv))
    medians = {name: statistics.median(values) for name, values in samples.items()}
    peer = medians["import shary (peer)"]
    for name, value in medians.items():
        print(f"{name:<22} {value * 1000:7.0f} ms CPU  (x{value / peer:.2f} the peer; "
              f"median of {args.runs})")
    if args.json:
        print(json.dumps({"runs": args.runs,
                          "cpu_ms": {n: round(v * 1000, 1) for n, v in medians.items()},
                          "ratio_to_peer": {n: round(v / peer, 3) for n, v in medians.items()}}))


if __name__ == "__main__":
    main()
