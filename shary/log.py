"""The context log: everything that happened in a run, time-stamped, in one SQLite file.

This is SHARY's counterpart of HRI/OS's Context Manager. The kernel records
every fact change, act, scheme transition, task state change, executor request
and result, and plan as one *event*; ``shary log FILE`` lists and filters them,
``shary render tree`` replays them, and any SQLite tool can read the file.

Why the file looks the way it does:

* **One table, one row per event**, ``events(seq, time, kind, task, agent,
  data)``. ``seq`` orders events that share an engine time; ``time`` is the
  engine clock (simulated or wall), never the wall clock of the recording, so
  a replayed run logs the same times. ``kind`` is a free string; families of
  kinds share a prefix (``fact-added``, ``fact-removed``) so that ``fact-*``
  selects the family. ``data`` is a JSON object with sorted keys, so the same
  inputs give byte-identical rows; the ``meta`` table holds nothing that
  changes between two runs either (format version, writer, seed).
* **WAL journal**, so another process (``shary log``, a dashboard) reads the
  log while the run writes it, and a reader never blocks the event loop.
* **Commit policy**: events are committed every :data:`COMMIT_EVERY` records
  and at every :meth:`ContextLog.flush`, which the event loop calls once per
  tick (when it has handled what was due and is about to wait or advance the
  clock). A process killed with SIGKILL therefore loses at most the events
  recorded since the last flush, never more than ``COMMIT_EVERY - 1``, and
  the file is never left corrupt. A commit costs about 0.1 ms, which is why
  the log does not commit after every event: batching keeps recording above
  20,000 events per second (about 40,000 on the development machine), and a
  loop that flushed after every event would spend most of its time there.
  Commits do not wait for the disk (``synchronous=NORMAL``): a commit
  survives the death of the process, and only a power loss or an
  operating-system crash can roll back the last commits.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sqlite3
import sys
from collections.abc import Iterator
from contextlib import closing, contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import IO, Any

from rich.console import Console
from rich.markup import escape
from rich.text import Span, Text

from userfiles.errors import FileError, Problem

FORMAT_VERSION = 1
COMMIT_EVERY = 256

_SCHEMA = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE events (
    seq INTEGER PRIMARY KEY,
    time REAL NOT NULL,
    kind TEXT NOT NULL,
    task TEXT,
    agent TEXT,
    data TEXT NOT NULL
);
CREATE INDEX events_kind ON events (kind);
CREATE INDEX events_task ON events (task);
CREATE INDEX events_agent ON events (agent);
CREATE INDEX events_time ON events (time);
"""
_EVENT_COLUMNS = ("seq", "time", "kind", "task", "agent", "data")
_INSERT = "INSERT INTO events (time, kind, task, agent, data) VALUES (?, ?, ?, ?, ?)"


# The canonical JSON of an event's data: sorted keys, no spaces, no NaN. Built once,
# because json.dumps with options builds a new encoder at every call.
_encode = json.JSONEncoder(sort_keys=True, separators=(",", ":"), ensure_ascii=False,
                           allow_nan=False).encode


class ContextLog:
    """Appends the events of one run to a new SQLite file.

    ``overwrite`` must be given to replace a non-empty file, so that a second
    run never silently destroys the log of the first one. ``seed`` is stored
    in the ``meta`` table so that a logged run can be replayed.
    """

    def __init__(self, path: str | Path, *, seed: int | None = None,
                 overwrite: bool = False):
        from shary import __version__

        self.path = Path(path)
        if self.path.exists() and self.path.stat().st_size > 0:
            if not overwrite:
                raise FileExistsError(f"{self.path}: the file exists and is not empty "
                                      "(pass overwrite=True to replace it)")
            for suffix in ("", "-wal", "-shm"):
                Path(f"{self.path}{suffix}").unlink(missing_ok=True)
        self._conn = sqlite3.connect(self.path)
        self._conn.execute("PRAGMA journal_mode=WAL")
        self._conn.execute("PRAGMA synchronous=NORMAL")
        self._conn.executescript(_SCHEMA)
        meta = {"format": str(FORMAT_VERSION), "created-by": f"shary {__version__}"}
        if seed is not None:
            meta["seed"] = str(seed)
        self._conn.executemany("INSERT INTO meta (key, value) VALUES (?, ?)", sorted(meta.items()))
        self._conn.commit()
        self._pending = 0
        self._closed = False

    def record(self, time: float, kind: str, *, task: str | None = None,
               agent: str | None = None, **data: Any) -> int:
        """Append one event and return its ``seq``; ``data`` must be JSON-serialisable.

        Sets and other unordered or opaque values are refused rather than
        converted, because their text could differ from one run to the next.
        """
        if not math.isfinite(time):
            raise ValueError(f"event time must be a finite number, not {time!r}")
        if not kind:
            raise ValueError("event kind must be a non-empty string")
        seq = self._conn.execute(_INSERT, (time, kind, task, agent, _encode(data))).lastrowid
        self._pending += 1
        if self._pending >= COMMIT_EVERY:
            self.flush()
        assert seq is not None
        return seq

    def flush(self) -> None:
        """Commit the events recorded so far: readers see them, a kill keeps them."""
        if self._pending:
            self._conn.commit()
            self._pending = 0

    def close(self) -> None:
        """Commit what is pending and close the file; closing twice does nothing."""
        if not self._closed:
            self.flush()
            self._conn.close()
            self._closed = True

    def __enter__(self) -> ContextLog:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        # The events before a failure are the record of what led to it: keep them.
        self.close()


# -- reading ------------------------------------------------------------------


@dataclass(frozen=True)
class LogEvent:
    """One recorded event, as read back from a log."""

    seq: int
    time: float
    kind: str
    task: str | None
    agent: str | None
    data: dict[str, Any]

    def as_dict(self) -> dict[str, Any]:
        """The event as one JSON object, fields in the order of the table."""
        return {"seq": self.seq, "time": self.time, "kind": self.kind, "task": self.task,
                "agent": self.agent, "data": self.data}


def read_events(path: str | Path, *, task: str | None = None, agent: str | None = None,
                kind: str | None = None, since: float | None = None,
                until: float | None = None) -> list[LogEvent]:
    """The events of a log matching every filter given, in ``seq`` order.

    ``kind`` ending in ``*`` selects every kind that starts with what comes
    before it. ``since`` and ``until`` bound the event time, both inclusive.
    Only committed events are seen, so reading while a run writes is safe.
    """
    with _select(path, task=task, agent=agent, kind=kind, since=since, until=until) as events:
        return list(events)


def export_jsonl(path: str | Path, out: str | Path | IO[str], *, task: str | None = None,
                 agent: str | None = None, kind: str | None = None,
                 since: float | None = None, until: float | None = None) -> int:
    """Write the matching events to ``out`` (a path or a text file), one JSON object a line.

    Returns the number of events written. Events are streamed, not loaded all
    at once, because a long run logs millions of them. The log is checked
    before ``out`` is opened, so a file that is not a log never truncates it.
    """
    with _select(path, task=task, agent=agent, kind=kind, since=since, until=until) as events:
        if isinstance(out, (str, Path)):
            with open(out, "w", encoding="utf-8") as stream:
                return _write_jsonl(events, stream)
        return _write_jsonl(events, out)


def _write_jsonl(events: Iterator[LogEvent], stream: IO[str]) -> int:
    count = 0
    for event in events:
        stream.write(json.dumps(event.as_dict(), ensure_ascii=False) + "\n")
        count += 1
    return count


@contextmanager
def _select(path: str | Path, *, task: str | None, agent: str | None, kind: str | None,
            since: float | None, until: float | None) -> Iterator[Iterator[LogEvent]]:
    """The matching events, streamed from a log that stays open until the block ends.

    The log is opened, checked and queried on entering the block, so that a
    bad file fails before the caller has written anything.
    """
    clauses: list[str] = []
    params: list[str | float] = []
    for column, value in (("task", task), ("agent", agent)):
        if value is not None:
            clauses.append(f"{column} = ?")
            params.append(value)
    if kind is not None and kind.endswith("*"):
        # GLOB is case-sensitive like '=' and can use the index on kind; LIKE is neither.
        clauses.append("kind GLOB ?")
        params.append(re.sub(r"[*?[]", r"[\g<0>]", kind[:-1]) + "*")
    elif kind is not None:
        clauses.append("kind = ?")
        params.append(kind)
    if since is not None:
        clauses.append("time >= ?")
        params.append(since)
    if until is not None:
        clauses.append("time <= ?")
        params.append(until)
    where = f" WHERE {' AND '.join(clauses)}" if clauses else ""
    with closing(_open(path)) as conn:
        try:
            cursor = conn.execute(f"SELECT {', '.join(_EVENT_COLUMNS)} FROM events{where} "
                                  "ORDER BY seq", params)
        except sqlite3.DatabaseError as err:
            raise _not_a_log(path, str(err)) from None
        yield _decode(path, cursor)


def _decode(path: str | Path, cursor: sqlite3.Cursor) -> Iterator[LogEvent]:
    try:
        for row in cursor:
            yield _event(path, row)
    except sqlite3.DatabaseError as err:
        raise _not_a_log(path, str(err)) from None


def _event(path: str | Path, row: tuple[Any, ...]) -> LogEvent:
    """Check the types of a row too: a hand-made file must not crash ``shary log`` later."""
    seq, time, kind, task, agent, text = row
    try:
        data = json.loads(text)
    except (TypeError, ValueError):
        data = None
    if (isinstance(time, float) and isinstance(kind, str) and isinstance(data, dict)
            and all(name is None or isinstance(name, str) for name in (task, agent))):
        return LogEvent(seq, time, kind, task, agent, data)
    raise _not_a_log(path, f"event {seq} is malformed (expected a number as time, text as "
                     "kind, task and agent, and a JSON object as data)")


def _open(path: str | Path) -> sqlite3.Connection:
    """Open a log read-only (a reader must never change a run's file) and check its tables."""
    where = Path(path)
    if not where.is_file():
        raise FileError([Problem(str(path), 1, 1,
                                 "not a file" if where.exists() else "no such file")])
    try:
        conn = sqlite3.connect(f"{where.resolve().as_uri()}?mode=ro", uri=True)
    except sqlite3.Error as err:
        raise _not_a_log(path, str(err)) from None
    try:
        problem = _problem_with(conn)
    except sqlite3.DatabaseError as err:
        problem = str(err)
    if problem is not None:
        conn.close()
        raise _not_a_log(path, problem)
    return conn


def _problem_with(conn: sqlite3.Connection) -> str | None:
    """Why an open SQLite file is not a log this version can read, or None."""
    columns = tuple(row[1] for row in conn.execute("PRAGMA table_info(events)"))
    if columns != _EVENT_COLUMNS:
        return f"events table has columns {', '.join(columns)}" if columns else "no events table"
    found = conn.execute("SELECT value FROM meta WHERE key = 'format'").fetchone()
    if found is None or found[0] != str(FORMAT_VERSION):
        return (f"log format {found[0] if found else 'missing'} "
                f"(this shary reads format {FORMAT_VERSION})")
    return None


def _not_a_log(path: str | Path, reason: str) -> FileError:
    return FileError([Problem(str(path), 1, 1, f"not a shary context log: {reason}")])


# -- the `shary log` command ---------------------------------------------------

_out = Console(highlight=False, soft_wrap=True)
_err = Console(stderr=True, highlight=False, soft_wrap=True)
_LINES_PER_PRINT = 1000  # one print per line through rich is ten times slower
_CONTROL = re.compile(r"[\x00-\x1f]")  # what JSON escapes
_BARE = re.compile(r"[^\s\"'=,\[\]{}\x00-\x1f]+")


def add_log_command(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``shary log FILE [filters] [--json | --jsonl OUT]`` to the ``shary`` command."""
    p = subparsers.add_parser(
        "log", help="list the events of a context log, filtered by task, agent, kind, time",
        description="List the events of a context log. Filters combine: an event is shown "
        "when it matches all of them.")
    p.add_argument("file", type=Path, metavar="FILE", help="a context log (.sqlite) of a run")
    p.add_argument("--task", metavar="T", help="only the events of this task")
    p.add_argument("--agent", metavar="A", help="only the events of this agent")
    p.add_argument("--kind", metavar="K",
                   help="only this kind of event; a trailing * matches a prefix ('fact-*')")
    p.add_argument("--since", type=float, metavar="SECONDS",
                   help="only the events at or after this engine time")
    p.add_argument("--until", type=float, metavar="SECONDS",
                   help="only the events at or before this engine time")
    output = p.add_mutually_exclusive_group()
    output.add_argument("--jsonl", type=Path, metavar="OUT",
                        help="write the events to OUT, one JSON object a line")
    output.add_argument("--json", action="store_true",
                        help="print the events as JSON lines instead of a table")
    p.set_defaults(func=cmd_log)


def cmd_log(args: argparse.Namespace) -> int:
    """Run ``shary log``; a bad log raises :class:`FileError` for the CLI to print."""
    filters: dict[str, Any] = {"task": args.task, "agent": args.agent, "kind": args.kind,
                               "since": args.since, "until": args.until}
    if args.jsonl is not None:
        try:
            count = export_jsonl(args.file, args.jsonl, **filters)
        except OSError as err:
            _err.print(f"[bold red]error:[/bold red] cannot write "
                       f"{escape(str(args.jsonl))}: {escape(err.strerror or str(err))}")
            return 1
        _out.print(f"wrote {count} event(s) to {escape(str(args.jsonl))}")
        return 0
    with _select(args.file, **filters) as events:
        if args.json:
            _write_jsonl(events, sys.stdout)
        else:
            _print_table(list(events))
    return 0


def _print_table(events: list[LogEvent]) -> None:
    """One aligned line per event: greppable, and fast enough for a long log.

    A rich Table measures every cell (a millisecond a row) and Text.assemble
    sanitises every piece, so each block of lines is one Text whose styled
    spans are computed from the column widths.
    """
    if not events:
        _err.print("no matching events")
        return
    rows = [(f"{e.time:.3f}", _shown(e.kind), e.task and _shown(e.task),
             e.agent and _shown(e.agent), _compact(e.data)) for e in events]
    w_time, w_kind, w_task, w_agent = (
        max(len(title), *(len(row[i] or "-") for row in rows))
        for i, title in enumerate(("time", "kind", "task", "agent")))
    at_kind = w_time + 2
    at_task = at_kind + w_kind + 2
    at_agent = at_task + w_task + 2
    _out.print(Text(f"{'time':>{w_time}}  {'kind':<{w_kind}}  {'task':<{w_task}}  "
                    f"{'agent':<{w_agent}}  data", style="bold"))
    for first in range(0, len(rows), _LINES_PER_PRINT):
        lines: list[str] = []
        spans: list[Span] = []
        start = 0
        for time, kind, task, agent, data in rows[first:first + _LINES_PER_PRINT]:
            spans.append(Span(start + at_kind, start + at_kind + len(kind), "cyan"))
            spans.extend(Span(start + at, start + at + 1, "dim")
                         for at, name in ((at_task, task), (at_agent, agent)) if name is None)
            line = (f"{time:>{w_time}}  {kind:<{w_kind}}  {task or '-':<{w_task}}  "
                    f"{agent or '-':<{w_agent}}  {data}")
            lines.append(line)
            start += len(line) + 1
        _out.print(Text("\n".join(lines), spans=spans))


def _shown(name: str) -> str:
    """A name as printed: quoted when it holds control characters that would drive the
    terminal (a log may come from anywhere)."""
    return json.dumps(name, ensure_ascii=False) if _CONTROL.search(name) else name


def _compact(data: dict[str, Any]) -> str:
    """``key=value …`` with simple strings bare and everything else as compact JSON."""
    return " ".join(
        f"{key}={value}" if isinstance(value, str) and _BARE.fullmatch(value)
        else f"{key}={json.dumps(value, ensure_ascii=False, separators=(',', ':'))}"
        for key, value in data.items())
