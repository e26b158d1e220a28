"""The context log: one SQLite file per run, filtered reads, JSONL export, ``shary log``."""

from __future__ import annotations

import argparse
import io
import json
import re
import signal
import sqlite3
import subprocess
import sys
from contextlib import closing
from pathlib import Path

import pytest

from shary.commands.log import add_log
from shary.log.contextlog import ContextLog, LogEvent, end_time, export_jsonl, read_events
from userfiles.errors import FileError

# (time, kind, task, agent, data): a short run of give-object.
RUN = [
    (0.0, "fact-added", None, "robot", {"s": "bottle1", "p": "isOn", "o": "table"}),
    (0.5, "goal", "give-1", "human1", {"goal": "give-object", "object": "bottle1"}),
    (1.0, "act", "give-1", "robot", {"act": "R-PROPOSE", "scheme": "give-object"}),
    (1.0, "transition", "give-1", None, {"from": "proposed", "to": "realizing"}),
    (2.25, "fact-removed", None, "human1", {"s": "human1", "p": "looksAt", "o": "robot"}),
    (3.0, "executor-request", "give-1/reach", "robot", {"executor": "arm", "args": [1, 2.5]}),
    (4.0, "task-state", "give-1", None, {"state": "done", "note": "two words"}),
    (4.0, "factory", None, "robot", {}),
]


def write_run(path: Path, **options) -> list[int]:
    with ContextLog(path, **options) as log:
        return [log.record(t, kind, task=task, agent=agent, **data)
                for t, kind, task, agent, data in RUN]


@pytest.fixture
def run_log(tmp_path: Path) -> Path:
    path = tmp_path / "run.sqlite"
    write_run(path, seed=42)
    return path


def kinds(events: list[LogEvent]) -> list[str]:
    return [e.kind for e in events]


def test_events_come_back_as_recorded(run_log: Path):
    events = read_events(run_log)
    assert [e.seq for e in events] == list(range(1, len(RUN) + 1))
    assert [(e.time, e.kind, e.task, e.agent, e.data) for e in events] == RUN


@pytest.mark.parametrize(("filters", "expected"), [
    ({"task": "give-1"}, ["goal", "act", "transition", "task-state"]),
    ({"agent": "human1"}, ["goal", "fact-removed"]),
    ({"kind": "act"}, ["act"]),
    ({"kind": "fact-*"}, ["fact-added", "fact-removed"]),
    ({"kind": "fact*"}, ["fact-added", "fact-removed", "factory"]),
    ({"kind": "*"}, [k for _, k, *_ in RUN]),
    ({"since": 1.0, "until": 3.0}, ["act", "transition", "fact-removed", "executor-request"]),
    ({"since": 3.5}, ["task-state", "factory"]),
    ({"task": "give-1", "agent": "robot", "until": 2.0}, ["act"]),
    ({"task": "nobody"}, []),
])
def test_filters_combine_with_and(run_log: Path, filters: dict, expected: list[str]):
    assert kinds(read_events(run_log, **filters)) == expected


def test_a_kind_prefix_is_literal_before_the_star(tmp_path: Path):
    path = tmp_path / "glob.sqlite"
    with ContextLog(path) as log:
        for kind in ("a?c", "abc", "a[b]", "ab", "a*x"):
            log.record(0.0, kind)
    assert kinds(read_events(path, kind="a?*")) == ["a?c"]
    assert kinds(read_events(path, kind="a[*")) == ["a[b]"]
    assert kinds(read_events(path, kind="a**")) == ["a*x"]
    assert kinds(read_events(path, kind="a?c")) == ["a?c"]


def test_same_records_give_the_same_log(tmp_path: Path):
    first, second = tmp_path / "first.sqlite", tmp_path / "second.sqlite"
    write_run(first, seed=7)
    write_run(second, seed=7)
    assert read_events(first) == read_events(second)
    dumps = []
    for path in (first, second):
        with closing(sqlite3.connect(path)) as conn:
            dumps.append(list(conn.iterdump()))
    assert dumps[0] == dumps[1]
    assert first.read_bytes() == second.read_bytes()


def test_data_is_stored_as_json_with_sorted_keys_and_meta_keeps_the_seed(run_log: Path):
    with closing(sqlite3.connect(run_log)) as conn:
        (data,) = conn.execute("SELECT data FROM events WHERE kind = 'fact-added'").fetchone()
        meta = dict(conn.execute("SELECT key, value FROM meta"))
        (mode,) = conn.execute("PRAGMA journal_mode").fetchone()
    assert data == '{"o":"table","p":"isOn","s":"bottle1"}'
    assert meta["format"] == "1" and meta["seed"] == "42"
    assert meta["created-by"].startswith("shary ")
    assert mode == "wal"


def test_values_that_could_differ_between_runs_are_refused(tmp_path: Path):
    with ContextLog(tmp_path / "bad.sqlite") as log:
        with pytest.raises(TypeError):
            log.record(0.0, "fact-added", objects={"a", "b"})
        with pytest.raises(ValueError):
            log.record(float("nan"), "fact-added")
        with pytest.raises(ValueError):
            log.record(0.0, "")
        assert log.record(0.0, "fact-added") == 1


def test_an_existing_log_is_not_overwritten_by_accident(run_log: Path):
    with pytest.raises(FileExistsError):
        ContextLog(run_log)
    assert len(read_events(run_log)) == len(RUN)
    with ContextLog(run_log, overwrite=True) as log:
        log.record(9.0, "fresh")
    assert kinds(read_events(run_log)) == ["fresh"]


def test_flushed_events_are_readable_while_the_run_writes(tmp_path: Path):
    path = tmp_path / "live.sqlite"
    with ContextLog(path) as log:
        for i in range(3):
            log.record(float(i), "tick")
        log.flush()
        log.record(3.0, "not-yet-flushed")
        assert kinds(read_events(path)) == ["tick"] * 3
        log.flush()
        assert len(read_events(path)) == 4
        log.record(4.0, "tick")
    assert len(read_events(path)) == 5


WRITER = """
import os, signal, sys
from shary.log.contextlog import ContextLog
log = ContextLog(sys.argv[1])
for i in range(1000):
    log.record(i / 100, "tick", task="t%d" % (i % 7), agent="robot", n=i)
log.flush()
for i in range(10):
    log.record(10.0, "after-flush", n=i)
os.kill(os.getpid(), signal.SIGKILL)
"""


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL is POSIX")
def test_a_killed_run_keeps_every_flushed_event(tmp_path: Path):
    path = tmp_path / "killed.sqlite"
    done = subprocess.run([sys.executable, "-c", WRITER, str(path)], capture_output=True)
    assert done.returncode == -signal.SIGKILL, done.stderr
    events = read_events(path)
    assert [e.data["n"] for e in events[:1000]] == list(range(1000))
    assert all(e.kind == "after-flush" for e in events[1000:]) and len(events) <= 1010
    assert [e.seq for e in read_events(path, task="t3")] == list(range(4, 1001, 7))


def test_jsonl_export_to_a_path_and_to_a_stream(run_log: Path, tmp_path: Path):
    out = tmp_path / "run.jsonl"
    assert export_jsonl(run_log, out, task="give-1") == 4
    lines = [json.loads(line) for line in out.read_text(encoding="utf-8").splitlines()]
    assert lines[0] == {"seq": 2, "time": 0.5, "kind": "goal", "task": "give-1",
                        "agent": "human1", "data": {"goal": "give-object", "object": "bottle1"}}
    assert [line["kind"] for line in lines] == ["goal", "act", "transition", "task-state"]
    stream = io.StringIO()
    assert export_jsonl(run_log, stream) == len(RUN)
    assert [json.loads(line)["seq"] for line in stream.getvalue().splitlines()] == \
        list(range(1, len(RUN) + 1))


@pytest.mark.parametrize("content", [
    b"",
    b"kind,time\nact,1.0\n" * 50,
    b"SQLite format 3\x00" + b"\xff" * 200,
])
def test_a_file_that_is_not_a_log_is_a_file_error(tmp_path: Path, content: bytes):
    path = tmp_path / "not-a-log.sqlite"
    path.write_bytes(content)
    with pytest.raises(FileError) as caught:
        read_events(path)
    (problem,) = caught.value.problems
    assert (problem.file, problem.line, problem.col) == (str(path), 1, 1)
    assert "not a shary context log" in problem.message


EVENTS = ("CREATE TABLE events (seq INTEGER PRIMARY KEY, time REAL NOT NULL, "
          "kind TEXT NOT NULL, task TEXT, agent TEXT, data TEXT NOT NULL)")
META = ("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)",
        "INSERT INTO meta VALUES ('format', '1')")


@pytest.mark.parametrize(("statements", "reason"), [
    (["CREATE TABLE things (name TEXT)"], "no events table"),
    (["CREATE TABLE events (seq, kind)"], "events table has columns seq, kind"),
    ([EVENTS], "no meta table"),
    ([EVENTS, META[0], "INSERT INTO meta VALUES ('format', '2')"], "log format 2"),
    ([EVENTS, *META, "INSERT INTO events (time, kind, data) VALUES (1, 'act', 'nope')"],
     r"event #1 \(kind act\): data is not JSON"),
    ([EVENTS, *META, "INSERT INTO events (time, kind, data) VALUES ('soon', 'act', '{}')"],
     r'event #1 \(kind act\): time is "soon", not a finite number'),
])
def test_a_sqlite_file_of_something_else_is_a_file_error(tmp_path: Path, statements: list[str],
                                                          reason: str):
    path = tmp_path / "other.sqlite"
    with closing(sqlite3.connect(path)) as conn:
        for statement in statements:
            conn.execute(statement)
        conn.commit()
    out = tmp_path / "export.jsonl"
    out.write_text("keep", encoding="utf-8")
    with pytest.raises(FileError, match=reason):
        export_jsonl(path, out)
    assert out.read_text(encoding="utf-8") == "keep"  # replaced only by a whole export


def test_a_missing_log_is_a_file_error(tmp_path: Path):
    with pytest.raises(FileError, match="no such file"):
        read_events(tmp_path / "missing.sqlite")


@pytest.fixture
def shary_log(capsys):
    """Run ``shary log ARGS`` through a parser built with add_log."""
    parser = argparse.ArgumentParser(prog="shary")
    add_log(parser.add_subparsers(dest="command", required=True))

    def _run(*args: str | Path) -> tuple[int, str, str]:
        namespace = parser.parse_args(["log", *map(str, args)])
        status = namespace.func(namespace)
        captured = capsys.readouterr()
        return status, captured.out, captured.err
    return _run


def test_cli_prints_the_filtered_events_as_a_table(shary_log, run_log: Path):
    status, out, _ = shary_log(run_log, "--task", "give-1", "--since", "0.9")
    assert status == 0
    lines = out.splitlines()
    assert lines[0].split() == ["time", "kind", "task", "agent", "data"]
    assert [line.split()[:4] for line in lines[1:]] == [
        ["1.000", "act", "give-1", "robot"],
        ["1.000", "transition", "give-1", "-"],
        ["4.000", "task-state", "give-1", "-"],
    ]
    assert lines[1].endswith("act=R-PROPOSE scheme=give-object")
    assert lines[3].endswith('note="two words" state=done')
    assert lines[1].index("act") == lines[0].index("kind")


def test_cli_kind_prefix_json_and_jsonl(shary_log, run_log: Path, tmp_path: Path):
    status, out, _ = shary_log(run_log, "--kind", "fact-*", "--json")
    assert status == 0
    assert [json.loads(line)["kind"] for line in out.splitlines()] == \
        ["fact-added", "fact-removed"]
    target = tmp_path / "agent.jsonl"
    status, out, _ = shary_log(run_log, "--agent", "human1", "--jsonl", target)
    assert status == 0 and "wrote 2 event(s)" in out
    assert [json.loads(line)["seq"] for line in target.read_text().splitlines()] == [2, 5]
    status, _, err = shary_log(run_log, "--task", "nobody")
    assert status == 0 and "no matching events" in err


def test_cli_on_a_bad_file_raises_file_error_for_the_main_command(shary_log, tmp_path: Path):
    path = tmp_path / "notes.txt"
    path.write_text("not a database, just some notes\n" * 20, encoding="utf-8")
    with pytest.raises(FileError):
        shary_log(path)


def damaged(tmp_path: Path, how: str) -> Path:
    """A log of 5,000 events with garbage over 8 KiB in its middle, or cut in half."""
    path = tmp_path / "run.sqlite"
    with ContextLog(path) as log:
        for i in range(5000):
            log.record(i / 10, "tick", task=f"t{i % 7}", n=i, pad="x" * 50)
    data = bytearray(path.read_bytes())
    middle = len(data) // 2
    if how == "overwritten":
        data[middle:middle + 8192] = b"\xa5" * 8192
    else:
        del data[middle:]
    path.write_bytes(bytes(data))
    return path


def test_a_damaged_log_says_so_and_where_and_the_events_before_stay_readable(tmp_path: Path):
    path = damaged(tmp_path, "overwritten")
    with pytest.raises(FileError, match=r"the log is damaged after event #(\d+): database "
                       r"disk image is malformed \(read the events before it with --limit \1\)"
                       ) as caught:
        read_events(path)
    last = int(re.search(r"#(\d+)", str(caught.value))[1])
    assert 1000 < last < 5000
    assert [e.data["n"] for e in read_events(path, limit=3)] == [0, 1, 2]
    assert [e.seq for e in read_events(path, limit=last)] == list(range(1, last + 1))


def test_a_truncated_log_is_damaged_not_foreign(tmp_path: Path):
    with pytest.raises(FileError, match=r":1:1: error: the log is damaged: "):
        read_events(damaged(tmp_path, "truncated"))


def test_reading_a_finished_log_leaves_nothing_beside_it(run_log: Path, shary_log):
    """No -wal/-shm files after `shary log` (the log is opened immutable)."""
    assert sorted(p.name for p in run_log.parent.iterdir()) == ["run.sqlite"]
    before = run_log.read_bytes()
    assert shary_log(run_log)[0] == 0 and len(read_events(run_log, kind="act")) == 1
    assert sorted(p.name for p in run_log.parent.iterdir()) == ["run.sqlite"]
    assert run_log.read_bytes() == before


def test_pages_kinds_and_the_end_time(run_log: Path):
    everything = read_events(run_log)
    assert read_events(run_log, offset=2, limit=3) == everything[2:5]
    assert read_events(run_log, offset=7) == everything[7:]
    assert kinds(read_events(run_log, kinds=("act", "goal"))) == ["goal", "act"]
    assert end_time(run_log) == 4.0
    with ContextLog(run_log.parent / "empty.sqlite"):
        pass
    assert end_time(run_log.parent / "empty.sqlite") == 0.0


def test_streamed_events_are_checked_as_they_come(tmp_path: Path):
    path = tmp_path / "odd.sqlite"
    with ContextLog(path) as log:
        log.record(0.0, "tick")
    with closing(sqlite3.connect(path)) as conn:
        conn.execute("INSERT INTO events (time, kind, data) VALUES (1, 'node', '{}')")
        conn.execute("INSERT INTO events (time, kind, data) VALUES (9e999, 'tick', '{}')")
        conn.commit()
    with pytest.raises(FileError, match=r"event #2 \(kind node\): task is null, not text"):
        read_events(path)
    with pytest.raises(FileError, match=r"event #3 \(kind tick\): time is inf, not a finite"):
        read_events(path, kind="tick")


def test_the_writer_refuses_what_it_could_not_read_back(tmp_path: Path):
    with ContextLog(tmp_path / "deep.sqlite") as log:
        deep: list = []
        for _ in range(70):
            deep = [deep]
        with pytest.raises(ValueError, match="deeper than 64 levels"):
            log.record(0.0, "plan", steps=deep)
        with pytest.raises(ValueError, match="larger than 4 MiB"):
            log.record(0.0, "plan", text="x" * (4 * 2**20 + 1))


def test_nesting_is_measured_without_recursion():
    from shary.log.rows import nesting

    assert nesting("[" * 100 + "]" * 100) == 100
    assert nesting("[" * 200_000) == 200_000  # unclosed: as deep as it goes
    assert nesting('{"a":"' + "[" * 100 + '"}') == 1  # brackets in a string do not nest
    assert nesting('{"a":"\\"' + "[" * 100 + '"}') == 1  # nor after an escaped quote


INTERRUPTED = """
import sys
from shary.log.contextlog import ContextLog
with ContextLog(sys.argv[1]) as log:
    i = 0
    while True:
        log.record(i / 100, "tick", n=i)
        i += 1
        if i == 300:
            log.flush()
            print("ready", flush=True)
"""


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child is POSIX")
def test_ctrl_c_while_writing_keeps_every_recorded_event(tmp_path: Path):
    """Ctrl-C unwinds through the log's `with`: what was recorded, even unflushed, is kept."""
    path = tmp_path / "interrupted.sqlite"
    child = subprocess.Popen([sys.executable, "-c", INTERRUPTED, str(path)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert child.stdout is not None and child.stdout.readline() == "ready\n"
    child.send_signal(signal.SIGINT)
    _, err = child.communicate(timeout=30)
    assert "KeyboardInterrupt" in err
    events = read_events(path)
    assert len(events) >= 300 and [e.data["n"] for e in events] == list(range(len(events)))


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child is POSIX")
def test_ctrl_c_while_shary_log_prints_exits_130_without_a_traceback(tmp_path: Path):
    path = tmp_path / "long.sqlite"
    with ContextLog(path) as log:
        for i in range(20_000):  # far more than a pipe holds: the child waits to write
            log.record(i / 100, "tick", n=i)
    child = subprocess.Popen([sys.executable, "-m", "shary", "log", str(path), "--json"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert child.stdout is not None and child.stdout.readline().startswith(b'{"seq": 1,')
    child.send_signal(signal.SIGINT)
    child.stdout.close()  # as a terminal would: nothing more is read
    assert child.wait(timeout=30) == 130
    assert child.stderr is not None and b"Traceback" not in child.stderr.read()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["long.sqlite"]
