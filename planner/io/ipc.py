"""Plans in the IPC 2020 HTN track's format: writing ours, reading any.

The format (what the track's verifier, pandaPIparser's ``-verify``, reads)::

    ==>
    0 pick-up b1
    1 stack b1 b2
    root 2
    2 do_put_on b1 b2 -> m1_do_put_on 3 4
    ...
    <==

Actions first (``ID NAME ARGS``, in plan order), then ``root`` and the ids of
the top tasks, then one line per compound task: ``ID TASK ARGS -> METHOD
CHILD-IDS``.  A top task that is an action is listed by its action id.  Ids
are ours to choose: actions are numbered 0, 1, ... in plan order, compound
tasks after them, depth first.  The task that stands for an initial task
network with parameters (:data:`planner.io.translate.NETWORK`) is left out: its
subtasks are the top tasks.  :func:`shape` forgets the ids, so that two
plans can be compared (the feature tests' ``plans/``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from planner.io.translate import NETWORK
from planner.model.plan import Plan
from userfiles.errors import FileError
from userfiles.errors import Problem as FileProblem


def write_ipc(plan: Plan, spelling: Mapping[str, str] | None = None) -> str:
    """``plan`` in the IPC format (ending with a newline), its names spelt as
    ``spelling`` says (:attr:`planner.model.domain.Problem.spelling`: the files' own spelling,
    which the track's verifier expects; a name it does not give is written as it is)."""
    count = len(plan.actions)
    ids: dict[int, int] = {}
    order: list[int] = []
    roots: list[int] = []
    for root in plan.roots:  # a network with parameters: its tasks are the top tasks
        node = plan.tree[root]
        roots.extend(node.children if node.task == NETWORK else [root])
    stack = list(reversed(roots))
    while stack:
        node = plan.tree[stack.pop()]
        if node.action is not None:
            ids[node.id] = node.action
            continue
        ids[node.id] = count + len(order)
        order.append(node.id)
        stack.extend(reversed(node.children))
    spell = (lambda word: word) if not spelling else (lambda word: spelling.get(word, word))
    lines = ["==>"]
    lines += [_words(str(i), spell(a.name), *(spell(str(x)) for x in a.args))
              for i, a in enumerate(plan.actions)]
    lines.append(_words("root", *(str(ids[r]) for r in roots)))
    for node_id in order:
        node = plan.tree[node_id]
        lines.append(_words(str(ids[node_id]), spell(node.task),
                            *(spell(str(x)) for x in node.args), "->",
                            spell(str(node.decomposition)), *(str(ids[c]) for c in node.children)))
    lines.append("<==")
    return "\n".join(lines) + "\n"


def _words(*words: str) -> str:
    return " ".join(words)


@dataclass
class IPCPlan:
    """A plan read from the IPC format: ``actions`` by id, ``roots``, and
    ``decompositions`` by id (task, arguments, method, child ids)."""

    actions: dict[int, tuple[str, tuple[str, ...]]]
    roots: list[int]
    decompositions: dict[int, tuple[str, tuple[str, ...], str, list[int]]]


def read_ipc(text: str, file: str = "<string>") -> IPCPlan:
    """Parse the IPC plan format; ``FileError`` with the line of each problem."""
    problems: list[FileProblem] = []
    actions: dict[int, tuple[str, tuple[str, ...]]] = {}
    decompositions: dict[int, tuple[str, tuple[str, ...], str, list[int]]] = {}
    roots: list[int] | None = None
    inside = False
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith(";"):
            continue
        if line == "==>":
            inside = True
            continue
        if line == "<==":
            break
        if not inside:
            continue
        words = line.split()
        col = raw.index(words[0]) + 1

        def bad(message: str, _n: int = number, _c: int = col) -> None:
            problems.append(FileProblem(file, _n, _c, message))

        if words[0] == "root":
            ids = [_int(w) for w in words[1:]]
            if any(i is None for i in ids):
                bad("'root' is followed by the ids of the top tasks")
            roots = [i for i in ids if i is not None]
            continue
        node = _int(words[0])
        if node is None or len(words) < 2:
            bad(f"expected 'ID NAME ARGS...', found {line!r}")
            continue
        if node in actions or node in decompositions:
            bad(f"id {node} is given twice")
            continue
        if roots is None:
            actions[node] = (words[1].lower(), tuple(w.lower() for w in words[2:]))
            continue
        if "->" not in words or len(words) < words.index("->") + 2:
            bad(f"expected 'ID TASK ARGS -> METHOD CHILD-IDS', found {line!r}")
            continue
        arrow = words.index("->")
        children = [_int(w) for w in words[arrow + 2:]]
        if any(c is None for c in children):
            bad("the ids of a decomposition's children are numbers")
            continue
        decompositions[node] = (words[1].lower(), tuple(w.lower() for w in words[2:arrow]),
                                words[arrow + 1].lower(), [c for c in children if c is not None])
    if roots is None:
        problems.append(FileProblem(file, 1, 1, "no 'root' line: not a plan in the IPC format"))
    if problems:
        raise FileError(problems)
    assert roots is not None
    return IPCPlan(actions, roots, decompositions)


def _int(word: str) -> int | None:
    return int(word) if word.isdigit() else None


def shape(plan: IPCPlan) -> tuple[Any, ...]:
    """The plan without its ids: the actions in order and each top task's tree of
    ``(task, args, method, children)`` (an action: ``(name, args)``)."""

    def tree(node: int, depth: int = 0) -> Any:
        if node in plan.actions:
            return plan.actions[node]
        if node not in plan.decompositions or depth > len(plan.decompositions):
            return ("?", node)
        task, args, method, children = plan.decompositions[node]
        return (task, args, method, tuple(tree(c, depth + 1) for c in children))

    ordered = tuple(plan.actions[i] for i in sorted(plan.actions))
    return ordered, tuple(tree(r) for r in plan.roots)
