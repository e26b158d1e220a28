"""The dynamic task tree.

SHARY's "incremental context-based task refinement process ... results in a
dynamic hierarchical task tree": a task node, under it an act x task node for
each act its scheme visits, under those the recipe's steps (atomic tasks, or
subtasks with their own act x task nodes).  The tree grows when an act is
entered, is cut when an act is preempted (what it had running is cancelled
first), and is kept when an act is suspended, so that it can resume.

States are strings so that JAHRVIS's nine states (PLANNED, TODO, ONGOING,
EXECUTED, SUSPENDED, UNPLANNED, NOT_STARTING, NOT_FINISHED, NOT_SEEN) can be
added without changing the structure.  Every change is reported to a
recorder (the context log), which is how a tree is redrawn at any past time.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

import networkx as nx

from shary.log.contextlog import BadEvent, LogEvent, stream_events

PLANNED, TODO, ONGOING, DONE, FAILED, SUSPENDED, CANCELLED = (
    "planned", "todo", "ongoing", "done", "failed", "suspended", "cancelled")
STATES = (PLANNED, TODO, ONGOING, DONE, FAILED, SUSPENDED, CANCELLED)
FINISHED = frozenset({DONE, FAILED, CANCELLED})

TASK, ACT, ATOMIC = "task", "act", "atomic"
"""Node kinds: a task, an act x task, an atomic task."""
NODE_KINDS = (TASK, ACT, ATOMIC)

Recorder = Callable[..., Any]


class TaskTree:
    """Tasks, act x task nodes and atomic tasks: a forest of nodes with attributes.

    Kept in plain dictionaries (a node's attributes, its parent, its children
    in insertion order): the tree grows and is cut on every act entered or
    left, thousands of times a second, and a networkx graph costs several
    times more per node added or removed.  :attr:`graph` gives the tree as a
    networkx graph for drawing and analysis.
    """

    def __init__(self, recorder: Recorder | None = None, *, prefix: str = "n"):
        self._record = recorder
        self._prefix = prefix
        """Node ids are PREFIX + a number: a team's robots share one log, so each tree
        has its own prefix (``K-10/n3``)."""
        self._next = 0
        self._attrs: dict[str, dict[str, Any]] = {}
        self._parent: dict[str, str | None] = {}
        self._children: dict[str, dict[str, None]] = {}  # an ordered set
        self.watchers: list[Callable[[str, str], Any]] = []
        """Told ``(node, state)`` after a node's state changes (the body's arbiter
        releases what an act held when the act ends)."""

    def add(self, kind: str, name: str, parent: str | None = None, *, state: str = PLANNED,
            **attrs: Any) -> str:
        """Add a node (under ``parent``) and return its id."""
        self._next += 1
        node = f"{self._prefix}{self._next}"
        self._insert(node, parent, {"kind": kind, "name": name, "state": state, **attrs})
        if self._record is not None:
            self._record("node", task=node, parent=parent, node_kind=kind, name=name,
                         state=state, **{k: v for k, v in attrs.items() if v is not None})
        return node

    def _insert(self, node: str, parent: str | None, attrs: dict[str, Any]) -> None:
        self._attrs[node] = attrs
        self._children[node] = {}
        if parent is not None and parent in self._attrs:
            self._parent[node] = parent
            self._children[parent][node] = None
        else:
            self._parent[node] = None

    def state(self, node: str) -> str:
        return self._attrs[node]["state"]

    def set_state(self, node: str, state: str, reason: str | None = None) -> None:
        """Change a node's state (recorded; a no-op when it does not change)."""
        data = self._attrs[node]
        if data["state"] == state:
            return
        data["state"] = state
        if self._record is not None:
            extra = {"reason": reason} if reason else {}
            self._record("task-state", task=node, name=data["name"], state=state, **extra)
        for watcher in self.watchers:
            watcher(node, state)

    def node(self, node: str) -> dict[str, Any]:
        return self._attrs[node]

    def parent(self, node: str) -> str | None:
        return self._parent[node]

    def children(self, node: str) -> list[str]:
        return list(self._children[node])

    def subtree(self, node: str) -> Iterator[str]:
        """The node and its descendants, parents before children."""
        yield node
        for child in self._children[node]:
            yield from self.subtree(child)

    def cut(self, node: str) -> None:
        """Remove a node and everything under it (finished nodes are marked cancelled first)."""
        nodes = list(self.subtree(node))
        for n in nodes:
            if self._attrs[n]["state"] not in FINISHED:
                self.set_state(n, CANCELLED, "cut")
        self._remove(nodes)
        if self._record is not None:
            self._record("node-removed", task=node, nodes=nodes)

    def _remove(self, nodes: Iterable[str]) -> None:
        for n in nodes:
            if n not in self._attrs:
                continue
            del self._attrs[n]
            parent = self._parent.pop(n)
            if parent is not None and parent in self._children:
                del self._children[parent][n]
            for child in self._children.pop(n):
                self._parent[child] = None

    @property
    def graph(self) -> nx.DiGraph:
        """The tree as a networkx directed graph (a copy, built when asked for)."""
        graph = nx.DiGraph()
        for node, attrs in self._attrs.items():
            graph.add_node(node, **attrs)
        graph.add_edges_from((parent, node) for node, parent in self._parent.items()
                             if parent is not None)
        return graph

    def __iter__(self) -> Iterator[str]:
        """Node ids, in the order they were added."""
        return iter(self._attrs)

    def __contains__(self, node: object) -> bool:
        return node in self._attrs

    def __len__(self) -> int:
        return len(self._attrs)

    @classmethod
    def replay(cls, events: Iterable[LogEvent], until: float | None = None) -> TaskTree:
        """The tree as it stood at time ``until`` (default: the end), rebuilt from the
        ``node``, ``task-state`` and ``node-removed`` events of a context log.

        The events' shapes are checked by the log's reader (``shary.log.rows``);
        what only the tree can see is a :class:`BadEvent`, refused at its row
        rather than drawn: a node added twice, a node kind the tree has not, a
        node of its own parent, a state change or removal of a node that is
        not in the tree (the writer only changes and removes nodes it has).  A
        node whose parent is not in the tree becomes a root (its parent may
        have been cut).  Nothing here recurses, so a tree of any depth replays.
        """
        tree = cls()
        attrs = tree._attrs
        for event in events:
            if until is not None and event.time > until:
                break
            if event.kind == "node":
                node = event.task
                if node in attrs:
                    raise BadEvent(event, f"node {node} is added again while it is in the tree")
                data = dict(event.data)
                parent = data.pop("parent", None)
                if event.agent:
                    data["agent"] = event.agent
                node_kind = data.pop("node_kind")
                if node_kind not in NODE_KINDS:
                    raise BadEvent(event, f"data.node_kind is {node_kind[:40]!r}, not one of "
                                   f"{', '.join(NODE_KINDS)}")
                if not node or parent == node:
                    raise BadEvent(event, "task is empty, not a node id" if not node else
                                   f"node {node} is its own parent")
                tree._insert(node, parent, {**data, "kind": node_kind})
            elif event.kind == "task-state":
                if event.task not in attrs:
                    raise BadEvent(event, f"node {event.task[:40]} changes state, but it is not "
                                   "in the tree")
                attrs[event.task]["state"] = event.data["state"]
            elif event.kind == "node-removed":
                missing = next((n for n in event.data["nodes"] if n not in attrs), None)
                if missing is not None:
                    raise BadEvent(event, f"node {missing[:40]} is removed, but it is not in "
                                   "the tree")
                tree._remove(event.data["nodes"])
        return tree


REPLAYED = ("node", "task-state", "node-removed")
"""The kinds of events that :meth:`TaskTree.replay` reads."""
MAX_DRAWN_NODES = 2000
"""The most nodes ``shary render tree`` lays out (.svg, .png).  Graphviz takes about
0.6 s for 2,000 nodes and 9 s for 5,000 on the development machine, and a picture
of thousands of nodes is no longer read; DOT text (.dot, .gv) has no limit."""


def replay_log(path: str | Path, until: float | None = None) -> TaskTree:
    """The task tree of a logged run as it stood at ``until`` (default: the end), read
    as a stream: a log of millions of events is never held whole."""
    with stream_events(path, kinds=REPLAYED, until=until) as events:
        return TaskTree.replay(events, until)
