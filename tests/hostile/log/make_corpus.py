"""Build the hostile context logs of this folder: ``python tests/hostile/log/make_corpus.py``.

Each file is a good little log, written by :class:`shary.log.contextlog.ContextLog` (a task
with an act and an atomic task, one state change), plus one row a reader
cannot use, inserted behind the writer's back as another tool, a crash or a
hand edit could.  ``CORPUS`` says what each file holds and what a reader must
say about it; ``tests/test_hostile_log.py`` reads it.  Every file here made
``shary render tree`` (and, for the deep one, ``shary log``) end in a Python
traceback before the reader checked rows, or draw a tree from rows the writer
never writes (the ones :data:`TREE_ONLY` names).
"""

from __future__ import annotations

import json
import sqlite3
import sys
from contextlib import closing
from pathlib import Path

HERE = Path(__file__).resolve().parent
DEEP = 5_000
"""Nesting of the deep row: far past Python's recursion limit (1,000)."""

# name -> (kind, task, data as JSON text, the message a reader must give)
CORPUS: dict[str, tuple[str, str | None, str, str]] = {
    "node-without-node-kind": (
        "node", "n9", '{"name":"fetch","state":"todo"}', r"data\.node_kind is missing"),
    "node-with-null-task": (
        "node", None, '{"name":"fetch","node_kind":"task","state":"todo"}',
        r"task is null, not text"),
    "node-with-list-parent": (
        "node", "n9", '{"name":"fetch","node_kind":"task","parent":["n1"],"state":"todo"}',
        r"data\.parent is a list, not text"),
    "node-with-list-args": (
        "node", "n9", '{"args":["bottle"],"name":"fetch","node_kind":"task","state":"todo"}',
        r"data\.args is a list, not object"),
    "node-removed-with-a-number": (
        "node-removed", "n2", '{"nodes":2}', r"data\.nodes is a number, not list of text"),
    "node-removed-with-objects": (
        "node-removed", "n2", '{"nodes":[{"id":"n2"}]}', r"data\.nodes holds an object, "
        r"not only text"),
    "node-removed-without-nodes": (
        "node-removed", "n2", '{}', r"data\.nodes is missing"),
    "task-state-without-state": (
        "task-state", "n2", '{"name":"GIVE"}', r"data\.state is missing"),
    "task-state-with-object-state": (
        "task-state", "n2", '{"name":"GIVE","state":{"done":true}}',
        r"data\.state is an object, not text"),
    # rows of a good shape that only the task tree sees are wrong (shary log lists them)
    "node-of-an-unknown-kind": (
        "node", "n9", '{"name":"fetch","node_kind":"banana","parent":"n1","state":"todo"}',
        r"data\.node_kind is 'banana', not one of task, act, atomic"),
    "node-its-own-parent": (
        "node", "n9", '{"name":"fetch","node_kind":"task","parent":"n9","state":"todo"}',
        r"node n9 is its own parent"),
    "task-state-of-no-node": (
        "task-state", "n77", '{"name":"GIVE","state":"done"}',
        r"node n77 changes state, but it is not in the tree"),
    "node-removed-of-no-node": (
        "node-removed", "n77", '{"nodes":["n77"]}',
        r"node n77 is removed, but it is not in the tree"),
    "deeply-nested-data": (
        "fact-added", None, '{"o":' + "[" * DEEP + "]" * DEEP + "}",
        r"data nests lists and objects deeper than 64 levels"),
}

TREE_ONLY = {"node-of-an-unknown-kind", "node-its-own-parent", "task-state-of-no-node",
             "node-removed-of-no-node"}
"""Rows of a good shape that ``shary log`` lists; only the tree's replay refuses them."""


def good_log(path: Path) -> None:
    """A small log as shary writes it: a task, its act, an atomic task, a state change."""
    from shary.kernel.tasktree import ACT, ATOMIC, TASK, TaskTree
    from shary.log.contextlog import ContextLog

    path.unlink(missing_ok=True)
    with ContextLog(path, seed=0) as log:
        clock = iter(range(100))
        tree = TaskTree(lambda kind, task=None, agent=None, **data: log.record(
            float(next(clock)), kind, task=task, agent=agent, **data))
        task = tree.add(TASK, "give-object", args={"object": "bottle"})
        act = tree.add(ACT, "GIVE", task, agent="robot", act_type="R-ACT")
        tree.add(ATOMIC, "reach", act, state="ongoing")
        tree.set_state(act, "ongoing")


def build(folder: Path = HERE) -> list[Path]:
    """Write every file of :data:`CORPUS` into ``folder``; return their paths."""
    made = []
    for name, (kind, task, data, _) in CORPUS.items():
        path = folder / f"{name}.sqlite"
        good_log(path)
        with closing(sqlite3.connect(path, isolation_level=None)) as conn:
            conn.execute("PRAGMA journal_mode = DELETE")  # one file, nothing beside it
            conn.execute("INSERT INTO events (time, kind, task, agent, data) "
                         "VALUES (50.0, ?, ?, NULL, ?)", (kind, task, data))
            conn.execute("PRAGMA page_size = 512")  # small files in git
            conn.execute("VACUUM")
        made.append(path)
    return made


if __name__ == "__main__":
    for made in build(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE):
        print(made, made.stat().st_size, "bytes", json.dumps(CORPUS[made.stem][3]))
