"""Context-log reading: what checking every row costs, against a bare SQLite reader.

A log of N events (a task tree of ``--nodes`` nodes, then fact changes, as a
long run leaves it) is written with SQL into a file made by the real writer.
Then, in the same run:

* **peer**: a bare reader, ``sqlite3`` cursor + ``json.loads`` per row, no checks
  (the least any reader of the file does);
* **shary**: :func:`shary.log.contextlog.stream_events`, every row checked (types, bounds,
  depth measured before parsing, the shape of its kind);
* the replay of the task tree (:func:`shary.kernel.tasktree.replay_log`), the JSONL
  export, and the table ``shary log`` prints into a pipe.

Both readers must see the same events, or the run fails.

    python benchmarks/log.py [--json] [--events N] [--nodes N]
"""

from __future__ import annotations

import argparse
import io
import json
import sqlite3
import sys
import tempfile
import time
from contextlib import closing, redirect_stdout
from pathlib import Path

from shary.cli import main as shary_main
from shary.kernel.tasktree import replay_log
from shary.log.contextlog import ContextLog, export_jsonl, stream_events


def make_log(path: Path, events: int, nodes: int) -> None:
    """A log file made by the real writer, then filled by SQL (a million rows in
    seconds): a task tree of ``nodes`` nodes, each with up to three children, then
    ``events`` fact changes.  ``tests/test_hostile_log.py`` uses it too."""
    with ContextLog(path, seed=0):
        pass
    with closing(sqlite3.connect(path)) as conn:
        conn.execute("PRAGMA synchronous = OFF")
        conn.execute("""
            INSERT INTO events (time, kind, task, agent, data)
            WITH RECURSIVE c(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM c WHERE i < ?)
            SELECT i * 1e-3, 'node', 'n' || i, 'robot',
                   printf('{"name":"step %d","node_kind":"%s","parent":%s,"state":"done"}',
                          i, iif(i = 1, 'task', 'atomic'),
                          iif(i = 1, 'null', '"n' || ((i - 2) / 3 + 1) || '"'))
            FROM c""", (nodes,))
        conn.execute("""
            INSERT INTO events (time, kind, task, agent, data)
            WITH RECURSIVE c(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM c WHERE i < ?)
            SELECT 100 + i * 1e-3, 'fact-added', NULL, 'robot',
                   printf('{"o":"table","p":"isOn","s":"bottle%d"}', i % 10)
            FROM c""", (events,))
        conn.commit()


def bare(path: Path) -> tuple[int, int]:
    """The peer: every row, its data parsed, nothing checked."""
    count = checksum = 0
    with closing(sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro&immutable=1",
                                 uri=True)) as conn:
        for seq, _, _, _, _, text in conn.execute("SELECT * FROM events ORDER BY seq"):
            checksum += seq + len(json.loads(text))
            count += 1
    return count, checksum


def checked(path: Path) -> tuple[int, int]:
    count = checksum = 0
    with stream_events(path) as events:
        for event in events:
            checksum += event.seq + len(event.data)
            count += 1
    return count, checksum


def timed(work):  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    result = work()
    return time.perf_counter() - start, result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--events", type=int, default=500_000)
    parser.add_argument("--nodes", type=int, default=60_000)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "run.sqlite"
        make_log(path, args.events, args.nodes)
        rows = args.events + args.nodes
        t_bare, seen_bare = timed(lambda: bare(path))
        t_checked, seen_checked = timed(lambda: checked(path))
        if seen_bare != seen_checked:
            print(f"FAILED: the readers disagree: {seen_bare} against {seen_checked}")
            return 1
        t_replay, tree = timed(lambda: replay_log(path))
        t_jsonl, _ = timed(lambda: export_jsonl(path, Path(folder) / "run.jsonl"))
        with redirect_stdout(io.StringIO()):  # not a terminal: plain lines, as into a pipe
            t_table, _ = timed(lambda: shary_main(["log", str(path)]))
    figures = {
        "rows": rows, "nodes": len(tree),
        "bare_rows_per_s": round(rows / t_bare), "checked_rows_per_s": round(rows / t_checked),
        "check_cost_ratio": round(t_checked / t_bare, 2),
        "replay_s": round(t_replay, 2), "jsonl_rows_per_s": round(rows / t_jsonl),
        "table_rows_per_s": round(rows / t_table),
    }
    print(f"{rows:,} rows ({args.nodes:,} tree nodes, {args.events:,} fact changes)")
    print(f"  bare sqlite3 + json.loads : {figures['bare_rows_per_s']:>9,} rows/s (peer)")
    print(f"  shary, every row checked  : {figures['checked_rows_per_s']:>9,} rows/s "
          f"(x{figures['check_cost_ratio']} the peer's time)")
    print(f"  task tree replay          : {figures['replay_s']} s for {len(tree):,} nodes")
    print(f"  JSONL export              : {figures['jsonl_rows_per_s']:>9,} rows/s")
    print(f"  table into a pipe         : {figures['table_rows_per_s']:>9,} rows/s")
    if args.json:
        print(json.dumps(figures, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
