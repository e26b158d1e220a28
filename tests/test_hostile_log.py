"""Hostile context logs: rows that are not quite rows, and logs too big to hold.

The small logs are ``tests/hostile/log/*.sqlite``, built by
``tests/hostile/log/make_corpus.py`` (each is a good log plus one bad row);
the big ones are generated here, in a temporary folder.  A SQLite file has no
lines: a refused log is blamed at ``LOG:1:1`` and the message names the event
(``event #SEQ (kind K): …``), as docs/recipes.md says.
"""

from __future__ import annotations

import importlib.util
import sqlite3
import subprocess
import sys
from contextlib import closing
from pathlib import Path

import pytest
from hostile import HOSTILE, MAX_MB, MAX_SECONDS, assert_refused, run_inprocess, run_subprocess
from rich.console import Console

sys.path.insert(0, str(HOSTILE / "log"))
from make_corpus import CORPUS, TREE_ONLY, good_log  # noqa: E402

from shary.commands import log as shary_log  # noqa: E402
from shary.kernel.tasktree import MAX_DRAWN_NODES  # noqa: E402

LOGS = HOSTILE / "log"
TREE_KINDS = {"node", "task-state", "node-removed"}


def test_the_corpus_is_the_one_the_script_makes():
    assert sorted(p.stem for p in LOGS.glob("*.sqlite")) == sorted(CORPUS)


@pytest.mark.parametrize("name", sorted(CORPUS))
def test_shary_log_refuses_the_bad_row(name: str):
    path = LOGS / f"{name}.sqlite"
    kind, _, _, message = CORPUS[name]
    outcome = run_inprocess("log", path)
    if name in TREE_ONLY:  # a good shape: listed, as it is
        assert outcome.status == 0 and CORPUS[name][1] in outcome.out, outcome.err
        return
    assert_refused(outcome, path, message=rf"^event #5 \(kind {kind}\): {message}")
    assert not list(LOGS.glob("*-wal")) and not list(LOGS.glob("*-shm"))


@pytest.mark.parametrize("name", sorted(CORPUS))
def test_render_tree_refuses_a_bad_row_it_needs_and_skips_the_others(name: str,
                                                                      tmp_path: Path):
    path, out = LOGS / f"{name}.sqlite", tmp_path / "tree.svg"
    kind, _, _, message = CORPUS[name]
    outcome = run_inprocess("render", "tree", path, "-o", out)
    if kind in TREE_KINDS:
        assert_refused(outcome, path, message=rf"^event #5 \(kind {kind}\): {message}")
        assert not out.exists()
    else:  # the tree never reads this row: the drawing is made
        assert outcome.status == 0, outcome.err
        assert "(3 nodes)" in outcome.out and out.read_text().startswith("<?xml")


def test_a_node_added_twice_is_refused(tmp_path: Path):
    path = tmp_path / "twice.sqlite"
    good_log(path)
    with closing(sqlite3.connect(path)) as conn:
        conn.execute("""INSERT INTO events (time, kind, task, data) VALUES (9, 'node', 'n1',
                     '{"name":"again","node_kind":"task","parent":"n3","state":"todo"}')""")
        conn.commit()
    outcome = run_inprocess("render", "tree", path, "-o", tmp_path / "tree.svg")
    assert_refused(outcome, path, message=r"^event #5 \(kind node\): node n1 is added again")


def test_a_data_key_named_like_a_node_attribute_does_not_break_the_replay(tmp_path: Path):
    path = tmp_path / "odd.sqlite"
    good_log(path)
    with closing(sqlite3.connect(path)) as conn:
        conn.execute("""INSERT INTO events (time, kind, task, data) VALUES (9, 'node', 'n9',
                     '{"kind":"x","name":"odd","node_kind":"atomic","parent":"n1",
                       "state":"todo"}')""")
        conn.commit()
    outcome = run_inprocess("render", "tree", path, "-o", tmp_path / "tree.dot")
    assert outcome.status == 0, outcome.err
    assert "odd" in (tmp_path / "tree.dot").read_text()


def _with_time(path: Path, time: str) -> Path:
    """A good log whose second event (node n2, at 1 s) has the time ``time`` (SQL), in a
    table that allows a null time as a table made by another tool may."""
    good_log(path)
    with closing(sqlite3.connect(path)) as conn:
        conn.executescript(f"""
            CREATE TABLE loose (seq INTEGER PRIMARY KEY, time REAL, kind TEXT NOT NULL,
                                task TEXT, agent TEXT, data TEXT NOT NULL);
            INSERT INTO loose SELECT * FROM events;
            DROP TABLE events;
            ALTER TABLE loose RENAME TO events;
            UPDATE events SET time = {time} WHERE seq = 2;""")
    return path


@pytest.mark.parametrize("time, shown", [("'soon'", '"soon"'), ("X'00'", "bytes"),
                                         ("9e999", "inf"), ("NULL", "null")])
def test_a_tree_at_a_time_refuses_a_row_whose_time_is_not_a_number(time: str, shown: str,
                                                                    tmp_path: Path):
    """Before, the time bound left such a row out unseen: the tree at 2.5 s was drawn
    without it (``shary render tree LOG --at 2.5``: "0 nodes" when every time was text)."""
    path, out = _with_time(tmp_path / "log.sqlite", time), tmp_path / "tree.svg"
    outcome = run_inprocess("render", "tree", path, "--at", "2.5", "-o", out)
    assert_refused(outcome, path, message=rf"^event #2 \(kind node\): time is {shown}, "
                   r"not a finite number of seconds")
    assert not out.exists()


@pytest.mark.parametrize("time, shown", [("-9e999", "-inf"), ("NULL", "null")])
def test_events_since_a_time_refuse_a_row_whose_time_is_not_a_number(time: str, shown: str,
                                                                      tmp_path: Path):
    path = _with_time(tmp_path / "log.sqlite", time)
    outcome = run_inprocess("log", path, "--since", "0.5")
    assert_refused(outcome, path, message=rf"^event #2 \(kind node\): time is {shown}, "
                   r"not a finite number of seconds")


HUGE = """
import sqlite3, sys
conn = sqlite3.connect(sys.argv[1])
conn.execute('''INSERT INTO events (time, kind, data) VALUES (9, 'plan',
             '{"steps":[' || replace(printf('%.*c', 50000000, 'x'), 'x', '1,') || '1]}')''')
conn.commit()
"""


def test_a_value_too_big_to_load_is_refused_without_loading_it(tmp_path: Path):
    """100 MB of ``[1,1,…]`` took 830 MB to parse; now SQLite refuses to load it.  The row
    is written by a child process: a child's peak memory (``ru_maxrss``) starts from its
    parent's size at the fork, so this process must not grow by 100 MB first."""
    path = tmp_path / "huge.sqlite"
    good_log(path)
    subprocess.run([sys.executable, "-c", HUGE, path], check=True)
    for argv in (("log", path, "--json"), ("render", "tree", path, "-o", tmp_path / "t.svg")):
        outcome = run_subprocess(*argv)
        if argv[0] == "log":
            assert_refused(outcome, path, message=r"^event #5 \(kind plan\): data is "
                           r"larger than 4 MiB")
        else:  # not a kind the tree reads
            assert outcome.status == 0 and outcome.peak_mb < MAX_MB, outcome.err


# -- big logs ----------------------------------------------------------------------

EVENTS = 1_000_000


def big_log(path: Path, events: int, nodes: int) -> Path:
    """A log as a long run leaves it: a task tree of ``nodes`` nodes (each with up to
    three children), then ``events`` fact changes; made by the log benchmark's own
    generator (SQL, not event by event: a million rows in seconds)."""
    _benchmark().make_log(path, events, nodes)
    return path


def _benchmark():
    """``benchmarks/log.py``, loaded by its path (benchmarks are scripts, not a package)."""
    spec = importlib.util.spec_from_file_location(
        "log_benchmark", HOSTILE.parents[1] / "benchmarks" / "log.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def million(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return big_log(tmp_path_factory.mktemp("big") / "million.sqlite", EVENTS, 300)


def within_the_rule(outcome) -> None:
    assert outcome.status == 0, outcome.err
    assert "Traceback" not in outcome.err
    assert outcome.seconds < MAX_SECONDS and outcome.peak_mb < MAX_MB, \
        f"{outcome.seconds:.1f} s, {outcome.peak_mb:.0f} MB"


def test_a_million_events_are_paged_not_loaded(million: Path):
    outcome = run_subprocess("log", million, "--offset", 300 + EVENTS - 3, "--limit", 3)
    within_the_rule(outcome)
    lines = outcome.out.splitlines()
    assert lines[0].split() == ["time", "kind", "task", "agent", "data"]
    assert [line.split()[1] for line in lines[1:]] == ["fact-added"] * 3
    assert lines[-1].endswith("s=bottle0")  # the last event of the log


def test_the_tree_of_a_million_event_log_is_replayed_from_its_own_rows(million: Path,
                                                                        tmp_path: Path):
    out = tmp_path / "tree.svg"
    outcome = run_subprocess("render", "tree", million, "-o", out)
    within_the_rule(outcome)
    assert "(300 nodes)" in outcome.out and "t = 1100 s" in out.read_text()


def test_a_long_log_on_a_terminal_is_listed_a_page_at_a_time(million: Path, monkeypatch):
    """Before: every event was drawn on the terminal, a few thousand lines a second
    (500,000 events took minutes); now the first page, then how to see more or fewer."""
    monkeypatch.setattr(shary_log, "_out", Console(force_terminal=True, highlight=False,
                                                   soft_wrap=True))
    outcome = run_inprocess("log", million)
    within_the_rule(outcome)
    assert outcome.out.count("\n") == 1 + shary_log.TERMINAL_PAGE  # the header, a page
    assert "--offset 1000 --limit 1000" in outcome.err
    assert all(f"--{flag}" in outcome.err for flag in ("kind", "task", "agent", "since"))
    outcome = run_inprocess("log", million, "--kind", "node", "--limit", 3)
    assert outcome.out.count("\n") == 4 and "more events" not in outcome.err


@pytest.mark.skipif(sys.platform == "win32", reason="a closed pipe is POSIX's")
def test_a_reader_that_stops_early_stops_shary_log(million: Path):
    """``shary log big --json | head -2``: no traceback, and it does not read on."""
    proc = subprocess.Popen([sys.executable, "-m", "shary", "log", million, "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    first = [proc.stdout.readline() for _ in range(2)]
    proc.stdout.close()
    assert proc.wait(timeout=3 * MAX_SECONDS) == 0
    assert proc.stderr.read() == b""
    assert all(line.startswith(b'{"seq": ') for line in first)


@pytest.fixture(scope="module")
def wide(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return big_log(tmp_path_factory.mktemp("wide") / "wide.sqlite", 0, 60_000)


def test_a_tree_too_big_to_lay_out_is_refused_naming_the_limit(wide: Path, tmp_path: Path):
    out = tmp_path / "tree.svg"
    outcome = run_subprocess("render", "tree", wide, "-o", out)
    assert_refused(outcome, wide, message=rf"has 60000 nodes; shary lays out at most "
                   rf"{MAX_DRAWN_NODES} \(draw an earlier time with --at")
    assert not out.exists()


def test_at_an_earlier_time_or_as_dot_text_the_big_tree_is_drawn(wide: Path, tmp_path: Path):
    outcome = run_subprocess("render", "tree", wide, "--at", 0.5, "-o", tmp_path / "early.svg")
    within_the_rule(outcome)
    assert "(500 nodes)" in outcome.out
    outcome = run_subprocess("render", "tree", wide, "-o", tmp_path / "all.dot")
    within_the_rule(outcome)
    assert "(60000 nodes)" in outcome.out
    assert (tmp_path / "all.dot").read_text().count("->") == 59_999
