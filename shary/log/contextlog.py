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
* **Reading streams and checks** (:func:`stream_events`): a cursor, never the
  whole log; read-only, and immutable once the writer is gone (no ``-wal`` or
  ``-shm`` left behind); every row checked (:mod:`shary.log.rows`), a bad one
  refused as ``LOG:1:1: error: event #SEQ (kind K): …``.  Failures to write
  raise an :class:`~userfiles.outputs.OutputError` naming the log.
"""

from __future__ import annotations

import errno
import heapq
import json
import math
import re
import sqlite3
import sys
from collections.abc import Iterator, Sequence
from contextlib import ExitStack, closing, contextmanager
from dataclasses import dataclass
from itertools import islice
from pathlib import Path
from types import TracebackType
from typing import IO, Any

from shary.log.rows import MAX_DATA_BYTES, check_row, decode_bounds, decode_data
from userfiles.errors import FileError, Problem
from userfiles.outputs import OutputError, open_output, refused

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
        conn = None
        try:
            conn = sqlite3.connect(self.path)
            conn.execute("PRAGMA journal_mode=WAL")
            conn.execute("PRAGMA synchronous=NORMAL")
            conn.executescript(_SCHEMA)
            meta = {"format": str(FORMAT_VERSION), "created-by": f"shary {__version__}"}
            if seed is not None:
                meta["seed"] = str(seed)
            conn.executemany("INSERT INTO meta (key, value) VALUES (?, ?)", sorted(meta.items()))
            conn.commit()
        except sqlite3.Error as err:
            if conn is not None:
                conn.close()
            raise _cannot_write(self.path, err) from None
        self._conn = conn
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
        text = _encode(data)
        problem = decode_bounds(text)
        if problem is not None:  # what shary writes, shary must read back
            raise ValueError(f"event {kind!r}: {problem}")
        try:
            seq = self._conn.execute(_INSERT, (time, kind, task, agent, text)).lastrowid
        except sqlite3.Error as err:
            raise _cannot_write(self.path, err) from None
        self._pending += 1
        if self._pending >= COMMIT_EVERY:
            self.flush()
        assert seq is not None
        return seq

    def flush(self) -> None:
        """Commit the events recorded so far: readers see them, a kill keeps them."""
        if self._pending:
            try:
                self._conn.commit()
            except sqlite3.Error as err:
                raise _cannot_write(self.path, err) from None
            self._pending = 0

    def close(self) -> None:
        """Commit what is pending and close the file; closing twice does nothing."""
        if not self._closed:
            self._closed = True
            try:
                self.flush()
            finally:
                self._conn.close()

    def __enter__(self) -> ContextLog:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        # The events before a failure are the record of what led to it: keep them.
        try:
            self.close()
        except OutputError:
            if exc is None:  # else the first failure is the one to report
                raise


def _cannot_write(path: Path, err: sqlite3.Error) -> OutputError:
    """An :class:`OutputError` for SQLite's failure to write the log, in a user's words.

    SQLite names the failure, not the system's reason: ``disk I/O error`` is
    what a full disk, a file-size limit or a failing disk all look like.
    """
    name = getattr(err, "sqlite_errorname", "")
    if name == "SQLITE_FULL":
        return refused(path, OSError(errno.ENOSPC, ""))
    if name.startswith("SQLITE_READONLY"):
        return refused(path, OSError(errno.EROFS, ""))
    if name.startswith("SQLITE_CANTOPEN"):
        return OutputError(path, f"cannot create the context log ({err})",
                           "choose an output folder you can write to")
    if name.startswith("SQLITE_IOERR"):
        return OutputError(path, f"cannot write the context log: SQLite reports '{err}', "
                           "which is how a full disk, a file-size limit or a failing disk "
                           "shows", "free some space, or write the run somewhere else")
    return OutputError(path, f"cannot write the context log: {err}",
                       "write the run somewhere else")


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


class BadEvent(Exception):
    """An event that a reader cannot use; :func:`stream_events` turns it into a
    :class:`FileError` naming the log, the event's ``seq`` and its kind."""

    def __init__(self, event: LogEvent | None, message: str, *, seq: int | None = None,
                 kind: str | None = None):
        self.seq = event.seq if event is not None else seq
        self.kind = event.kind if event is not None else kind
        super().__init__(message)


def read_events(path: str | Path, **filters: Any) -> list[LogEvent]:
    """The events of a log matching every filter given, in ``seq`` order, as a list
    (for short logs; :func:`stream_events` takes the same filters and streams)."""
    with stream_events(path, **filters) as events:
        return list(events)


def export_jsonl(path: str | Path, out: str | Path | IO[str], **filters: Any) -> int:
    """Write the matching events to ``out`` (a path or a text file), one JSON object a line.

    Returns the number of events written. Events are streamed, not loaded all
    at once, because a long run logs millions of them. The log is checked
    before ``out`` is opened, and a path is replaced only once every event is
    written, so a bad log or a full disk never leaves ``out`` truncated.
    """
    with stream_events(path, **filters) as events:
        if isinstance(out, (str, Path)):
            with open_output(out) as stream:
                return write_jsonl(events, stream)
        return write_jsonl(events, out)


def write_jsonl(events: Iterator[LogEvent], stream: IO[str]) -> int:
    """Write events to a text stream, one JSON object a line; how many were written."""
    count = 0
    for event in events:
        stream.write(_line(event.as_dict()) + "\n")
        count += 1
    return count


_line = json.JSONEncoder(ensure_ascii=False).encode  # built once, as _encode is


@contextmanager
def stream_events(path: str | Path, *, task: str | None = None, agent: str | None = None,
                  kind: str | None = None, kinds: Sequence[str] | None = None,
                  since: float | None = None, until: float | None = None,
                  limit: int | None = None, offset: int = 0) -> Iterator[Iterator[LogEvent]]:
    """The events matching every filter given, streamed in ``seq`` order from a log that
    stays open until the block ends.

    ``kind`` ending in ``*`` selects every kind that starts with what comes
    before it; ``kinds`` selects exact kinds; ``since`` and ``until`` bound the
    event time, both inclusive (a row whose time is not a finite number passes both,
    to be refused); ``offset`` and ``limit`` page the result.  Only
    committed events are seen, so reading while a run writes is safe.  The log
    is opened and checked on entering the block, so a bad file fails before the
    caller has written anything; a bad event (and :class:`BadEvent` raised in
    the block by a reader that takes events apart) ends the block with a
    :class:`FileError` at ``LOG:1:1`` naming the event.
    """
    clauses: list[str] = []
    params: list[str | float | int] = []
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
    if kinds is not None:
        clauses.append(f"kind IN ({', '.join('?' * len(kinds))})")
        params.extend(kinds)
    # A row whose time is not a finite number is neither before nor after a bound: it
    # is read, and refused by the reader, instead of being left out unseen.  SQLite
    # orders text and blobs after every number, and an infinity lies beyond the
    # largest float, so each bound stays ranges of the time index.
    if since is not None:
        clauses.append("(time >= ? OR time < ? OR time IS NULL)")
        params += [since, -sys.float_info.max]
    if until is not None:
        clauses.append("(time <= ? OR time > ? OR time IS NULL)")
        params += [until, sys.float_info.max]
    where = f" WHERE {' AND '.join(clauses)}" if clauses else ""
    page = ""
    if limit is not None or offset:
        page = " LIMIT ? OFFSET ?"
        params += [-1 if limit is None else limit, offset]
    with closing(_open(path)) as conn:
        try:
            cursor = conn.execute(f"SELECT {', '.join(_EVENT_COLUMNS)} FROM events{where} "
                                  f"ORDER BY seq{page}", params)
        except sqlite3.DatabaseError as err:
            raise _damaged(path, err, None) from None
        reader = _Reader(path, conn, cursor)
        try:
            yield iter(reader)
        except BadEvent as bad:
            raise _bad_event(path, bad) from None


def end_time(path: str | Path) -> float:
    """The time of a log's last event (0 for a log without events)."""
    with closing(_open(path)) as conn:
        try:
            row = conn.execute("SELECT seq, time FROM events ORDER BY seq DESC LIMIT 1").fetchone()
        except sqlite3.DatabaseError as err:
            raise _damaged(path, err, None) from None
    if row is None:
        return 0.0
    problem = check_row(row[1], "-", None, None, {})
    if problem is not None:
        raise _bad_event(path, BadEvent(None, problem, seq=row[0]))
    return float(row[1])


class _Reader:
    """Rows to checked events.  Remembers the last good event to name where damage is."""

    def __init__(self, path: str | Path, conn: sqlite3.Connection,
                 cursor: Iterator[tuple[Any, ...]]):
        self.path, self.conn, self.cursor = path, conn, cursor
        self.last: int | None = None

    def __iter__(self) -> Iterator[LogEvent]:
        try:
            for row in self.cursor:
                event = self.event(row)
                self.last = event.seq
                yield event
        except sqlite3.DataError as err:  # SQLITE_TOOBIG: a value past the length limit
            raise _bad_event(self.path, self._oversized(err)) from None
        except sqlite3.DatabaseError as err:
            raise _damaged(self.path, err, self.last) from None

    def event(self, row: tuple[Any, ...]) -> LogEvent:
        seq, time, kind, task, agent, text = row
        data = decode_data(text)
        problem = data if isinstance(data, str) else check_row(time, kind, task, agent, data)
        if problem is not None:
            raise _bad_event(self.path, BadEvent(None, problem, seq=seq,
                                                 kind=kind if isinstance(kind, str) else None))
        assert isinstance(data, dict)
        return LogEvent(seq, float(time), kind, task, agent, data)

    def _oversized(self, err: sqlite3.Error) -> BadEvent:
        """Which event holds the value SQLite refused to load, and in which column (the
        cursor reads one row ahead: it is the next event or the one after it)."""
        after = -1 if self.last is None else self.last
        for (seq,) in self.conn.execute("SELECT seq FROM events WHERE seq > ? ORDER BY seq "
                                        "LIMIT 2", (after,)).fetchall():
            values: dict[str, Any] = {}
            for column in _EVENT_COLUMNS[2:]:
                try:
                    values[column] = self.conn.execute(
                        f"SELECT {column} FROM events WHERE seq = ?", (seq,)).fetchone()[0]
                except sqlite3.DataError:
                    kind = values.get("kind")
                    return BadEvent(None, f"{column} is larger than "
                                    f"{MAX_DATA_BYTES // 2**20} MiB", seq=seq,
                                    kind=kind if isinstance(kind, str) else None)
        return BadEvent(None, str(err), seq=after + 1)


def _open(path: str | Path) -> sqlite3.Connection:
    """Open a log read-only and check its tables.

    A reader must never change a run's file, nor leave files beside it: a log
    whose writer has finished (no ``-wal`` file beside it) is opened
    ``immutable``, so that SQLite creates no ``-wal`` and ``-shm`` files; a log
    being written (or left by a killed writer) is read through its write-ahead
    log, which is already there.
    """
    where = Path(path)
    if not where.is_file():
        raise FileError([Problem(str(path), 1, 1,
                                 "not a file" if where.exists() else "no such file")])
    settled = not any(Path(f"{where}{suffix}").exists() for suffix in ("-wal", "-journal"))
    uri = f"{where.resolve().as_uri()}?mode=ro" + ("&immutable=1" if settled else "")
    try:
        conn = sqlite3.connect(uri, uri=True)
    except sqlite3.Error as err:
        raise _not_a_log(path, str(err)) from None
    if hasattr(conn, "setlimit"):  # Python 3.11+: a huge value is refused, never loaded
        conn.setlimit(sqlite3.SQLITE_LIMIT_LENGTH, MAX_DATA_BYTES)
    try:
        problem = _problem_with(conn)
    except sqlite3.DatabaseError as err:
        if getattr(err, "sqlite_errorname", "").startswith("SQLITE_CORRUPT"):
            conn.close()
            raise _damaged(path, err, None) from None
        problem = str(err)
    if problem is not None:
        conn.close()
        raise _not_a_log(path, problem)
    return conn


def _problem_with(conn: sqlite3.Connection) -> str | None:
    """Why an open SQLite file is not a log this version can read, or None."""
    tables = {name for (name,) in conn.execute(
        "SELECT name FROM sqlite_master WHERE type = 'table'")}
    if "events" not in tables:
        return "no events table" + (f" (its tables: {', '.join(sorted(tables))})"
                                    if tables else " (the database is empty)")
    info = list(conn.execute("PRAGMA table_info(events)"))
    columns = tuple(row[1] for row in info)
    if columns != _EVENT_COLUMNS:
        return f"events table has columns {', '.join(columns)}"
    if (info[0][2].upper(), info[0][5]) != ("INTEGER", 1):
        return "events.seq is not the table's INTEGER PRIMARY KEY"
    if "meta" not in tables:
        return "no meta table (a shary log records its format there)"
    found = conn.execute("SELECT value FROM meta WHERE key = 'format'").fetchone()
    if found is None or found[0] != str(FORMAT_VERSION):
        return (f"log format {found[0] if found else 'missing'} "
                f"(this shary reads format {FORMAT_VERSION})")
    return None


def _not_a_log(path: str | Path, reason: str) -> FileError:
    return FileError([Problem(str(path), 1, 1, f"not a shary context log: {reason}")])


def _damaged(path: str | Path, err: sqlite3.Error, last: int | None) -> FileError:
    if last is None:
        return FileError([Problem(str(path), 1, 1, f"the log is damaged: {err}")])
    return FileError([Problem(str(path), 1, 1, f"the log is damaged after event #{last}: {err} "
                              f"(read the events before it with --limit {last})")])


def _bad_event(path: str | Path, bad: BadEvent) -> FileError:
    kind = f" (kind {printable(bad.kind)})" if bad.kind else ""
    return FileError([Problem(str(path), 1, 1, f"event #{bad.seq}{kind}: {bad}")])


# -- several logs as one, names as printed ----------------------------------


@contextmanager
def merged_events(paths: Sequence[str | Path], *, limit: int | None = None, offset: int = 0,
                  **filters: Any) -> Iterator[Iterator[LogEvent]]:
    """The matching events of several logs (one per agent of a distributed team) as one
    stream ordered by time (each log is in time order: one loop, one clock), streamed;
    ``limit`` and ``offset`` count in the merged stream."""
    if len(paths) == 1:
        with stream_events(paths[0], limit=limit, offset=offset, **filters) as events:
            yield events
        return
    with ExitStack() as stack:
        streams = [stack.enter_context(stream_events(path, **filters)) for path in paths]
        merged = heapq.merge(*streams, key=lambda event: event.time)
        yield islice(merged, offset, None if limit is None else offset + limit)


_CONTROL = re.compile(r"[\x00-\x1f]")  # what JSON escapes


def printable(name: str) -> str:
    """A name as printed: quoted when it holds control characters that would drive the
    terminal (a log may come from anywhere)."""
    return json.dumps(name, ensure_ascii=False) if _CONTROL.search(name) else name
