"""The tree an HDDL file is read into, and what can be told from it alone (types, order).

See :mod:`planner.io.hddl` for the shape of each node.  Every node keeps the
``line`` and ``col`` it was read at, so that later checks (the translation,
the refusal of partial order) can point into the file.
"""

from __future__ import annotations

import heapq
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import NamedTuple

from userfiles.errors import FileError, Problem

Params = tuple[tuple[str, str], ...]


# --------------------------------------------------------------------------- the tree


@dataclass(frozen=True)
class Formula:
    """A condition or an effect; see the module's docstring for ``children`` by ``kind``."""

    kind: str
    children: tuple
    line: int
    col: int

    def walk(self) -> Iterator[Formula]:
        """This formula and every formula inside it, depth first."""
        todo = [self]
        while todo:
            formula = todo.pop()
            yield formula
            kind, children = formula.kind, formula.children
            if kind in ("and", "or", "not", "imply", "when"):
                todo.extend(reversed(children))
            elif kind in ("forall", "exists"):
                todo.append(children[1])

    def __str__(self) -> str:
        kind, children = self.kind, self.children
        if kind == "pred":
            return "(" + " ".join((children[0], *children[1])) + ")"
        if kind == "=":
            return f"(= {children[0]} {children[1]})"
        if kind in ("forall", "exists"):
            return f"({kind} ({_params_text(children[0])}) {children[1]})"
        return "(" + " ".join([kind, *(str(c) for c in children)]) + ")"


def _params_text(params: Params) -> str:
    return " ".join(f"{var} - {kind}" for var, kind in params)


@dataclass(frozen=True)
class Call:
    """A task (or predicate) applied to terms: the task a method decomposes."""

    name: str
    args: tuple[str, ...]
    line: int
    col: int


@dataclass(frozen=True)
class Subtask:
    """One subtask of a task network; ``id`` is ``None`` when the file gives none."""

    id: str | None
    name: str
    args: tuple[str, ...]
    line: int
    col: int


@dataclass(frozen=True)
class Fact:
    """A fact of the initial state."""

    pred: str
    args: tuple[str, ...]
    line: int
    col: int


@dataclass(frozen=True)
class HAction:
    name: str
    params: Params
    precondition: Formula | None
    effect: Formula | None
    line: int
    col: int


@dataclass(frozen=True)
class HMethod:
    name: str
    params: Params
    task: Call
    precondition: Formula | None
    subtasks: tuple[Subtask, ...]
    ordered: bool
    line: int
    col: int
    ordering: tuple[tuple[str, str], ...] = ()
    constraints: Formula | None = None
    """The method's ``:constraints`` that are conditions: ``=`` and ``not =``, as an
    ``and``; its ``sortof`` constraints narrow the types of ``params`` instead."""


@dataclass
class HDDLDomain:
    name: str
    requirements: tuple[str, ...]
    types: dict[str, str | None]
    constants: dict[str, str]
    predicates: dict[str, Params]
    tasks: dict[str, Params]
    methods: list[HMethod]
    actions: dict[str, HAction]
    file: str = "<string>"
    line: int = 1
    col: int = 1
    where: dict[tuple[str, str], tuple[int, int]] = field(default_factory=dict)
    spelling: dict[str, str] = field(default_factory=dict)
    """Names (lower case) that the file spells otherwise, with that spelling: the IPC
    verifier compares names case-sensitively, so a plan must write them so."""


@dataclass
class HDDLProblem:
    name: str
    domain_name: str
    objects: dict[str, str]
    init: tuple[Fact, ...]
    htn_params: Params
    htn_subtasks: tuple[Subtask, ...]
    ordered: bool
    goal: Formula | None
    file: str = "<string>"
    line: int = 1
    col: int = 1
    requirements: tuple[str, ...] = ()
    htn_ordering: tuple[tuple[str, str], ...] = ()
    htn_line: int = 0
    htn_col: int = 0
    where: dict[tuple[str, str], tuple[int, int]] = field(default_factory=dict)
    htn_constraints: Formula | None = None
    """The initial task network's ``:constraints`` that are conditions (``=``, ``not =``),
    as an ``and``; its ``sortof`` constraints narrow the types of ``htn_params``."""
    spelling: dict[str, str] = field(default_factory=dict)
    """The problem's object names spelt otherwise than in lower case (see
    :attr:`HDDLDomain.spelling`)."""


def supertypes(domain: HDDLDomain, type_name: str) -> list[str]:
    """``type_name`` and its ancestors, nearest first; ``object`` is always last."""
    current: str | None = type_name.lower()
    if current not in domain.types:
        raise KeyError(f"unknown type {type_name!r} in domain {domain.name!r}")
    chain: list[str] = []
    while current is not None and current not in chain:
        chain.append(current)
        current = domain.types.get(current)
    if chain[-1] != "object":
        chain.append("object")
    return chain


def all_objects(domain: HDDLDomain, problem: HDDLProblem) -> dict[str, str]:
    """The domain's constants and the problem's objects, object -> type."""
    return {**domain.constants, **problem.objects}


def is_total_order(domain: HDDLDomain, problem: HDDLProblem | None = None) -> bool:
    """True when every method (and the problem's task network) is totally ordered."""
    return all(m.ordered for m in domain.methods) and (problem is None or problem.ordered)


def refuse_partial_order(domain: HDDLDomain, problem: HDDLProblem | None = None) -> None:
    """Raise ``FileError`` naming every task network that is not totally ordered."""
    found: list[Problem] = []
    for method in domain.methods:
        if not method.ordered:
            why = _order(method.subtasks, method.ordering).why
            found.append(Problem(domain.file, method.line, method.col,
                                 f"method '{method.name}' is not totally ordered: {why}; only "
                                 "the total-order subset of HDDL is supported"))
    if problem is not None and not problem.ordered:
        why = _order(problem.htn_subtasks, problem.htn_ordering).why
        found.append(Problem(problem.file, problem.htn_line or problem.line,
                             problem.htn_col or problem.col,
                             f"the initial task network of problem '{problem.name}' is not "
                             f"totally ordered: {why}; only the total-order subset of HDDL is "
                             "supported"))
    if found:
        raise FileError(found)


class _Order(NamedTuple):
    order: list[int] | None
    """Indices of the subtasks in the total order, or None."""
    why: str
    """Why there is no total order (empty when there is one)."""
    cycle: list[int]
    """The subtasks on a cycle of the ordering constraints (then the ordering is wrong)."""


def _label(subtask: Subtask, index: int) -> str:
    return f"'{subtask.id}'" if subtask.id else f"subtask {index + 1} ({subtask.name})"


def _order(subtasks: tuple[Subtask, ...] | list[Subtask],
           ordering: Iterable[tuple[str, str]]) -> _Order:
    """Whether ``ordering`` (pairs of ids) orders ``subtasks`` totally (Kahn's algorithm)."""
    count = len(subtasks)
    pairs = list(ordering)
    if count <= 1:
        return _Order(list(range(count)), "", [])
    if not pairs:
        return _Order(None, f"its {count} subtasks have no ':ordering'", [])
    index = {s.id: i for i, s in enumerate(subtasks) if s.id is not None}
    after: list[set[int]] = [set() for _ in range(count)]
    for before, later in pairs:
        if before in index and later in index:
            after[index[before]].add(index[later])
    incoming = [0] * count
    for successors in after:
        for j in successors:
            incoming[j] += 1
    ready = [i for i in range(count) if incoming[i] == 0]
    heapq.heapify(ready)
    order: list[int] = []
    why = ""
    while ready:
        if len(ready) > 1 and not why:
            a, b = heapq.nsmallest(2, ready)
            why = (f"{_label(subtasks[a], a)} and {_label(subtasks[b], b)} are not ordered "
                   "by ':ordering'")
        current = heapq.heappop(ready)
        order.append(current)
        for j in after[current]:
            incoming[j] -= 1
            if incoming[j] == 0:
                heapq.heappush(ready, j)
    if len(order) < count:
        # What is left holds a cycle; peel off what only leads out of it.
        left = set(range(count)) - set(order)
        while True:
            ends = {i for i in left if not after[i] & left}
            if not ends:
                break
            left -= ends
        return _Order(None, "its ':ordering' has a cycle", sorted(left))
    return _Order(None if why else order, why, [])
