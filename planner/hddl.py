"""Reading HDDL, the HTN extension of PDDL (IPC 2020 HTN track): the total-order subset.

This is a *reader*: it turns a domain file and a problem file into a typed
syntax tree where every piece keeps the line and column it came from, and it
checks the meaning that can be checked without planning.  Translating the tree
into the planner's own model is :mod:`planner.translate`'s work.

Three layers, each usable alone:

1. :func:`tokenize` -- ``(``, ``)`` and atoms, with 1-based line and column
   (columns count characters; a tab is one column).  ``;`` starts a comment up
   to the end of the line.  HDDL is case-insensitive: every token has a
   lower-case ``value`` and keeps its original ``text`` for messages.
2. :func:`read_sexpr` -- the S-expressions of a text, as :class:`Symbol` and
   :class:`SList` nodes with positions.  The reader is iterative (hostile
   nesting cannot overflow the stack; it stops at :data:`MAX_DEPTH`) and
   reports every stray ``)`` and every ``(`` that is never closed at once.
3. :func:`read_domain` / :func:`read_problem` (and :func:`parse_domain` /
   :func:`parse_problem` for texts) -- the tree below, checked: undefined
   types, predicates, constants, tasks and actions; wrong arity; variables not
   declared; constants whose type does not fit a parameter; duplicate
   definitions; unsupported constructs refused *by name*.  Every problem found
   is reported at once as ``FILE:LINE:COL: error: ...`` in a
   :class:`~userfiles.errors.FileError`; never a traceback.

The tree
--------
Names are lower-case; variables keep their ``?``.  ``Params`` is a tuple of
``(variable, type)`` pairs (untyped parameters have type ``object``).  Every
node below has ``line`` and ``col`` (of its opening parenthesis).

* :class:`HDDLDomain`: ``types`` maps each type to its parent (``object`` maps
  to ``None``; a type used only as a parent is declared implicitly under
  ``object``, as in PDDL); ``constants`` maps object to type; ``predicates``
  and ``tasks`` map a name to its ``Params``; ``methods`` is a list of
  :class:`HMethod`; ``actions`` maps a name to its :class:`HAction`; ``where``
  maps ``(kind, name)`` -- kind ``type``, ``constant``, ``predicate``,
  ``task``, ``action``, ``method`` -- to the ``(line, col)`` of the definition.
* :class:`HMethod`: ``task`` is the :class:`Call` it decomposes;
  ``subtasks`` a tuple of :class:`Subtask` (``id`` or ``None``, ``name``,
  ``args``); ``ordered`` is ``True`` when the subtasks are totally ordered
  (``:ordered-subtasks``, or ``:subtasks`` whose ``:ordering`` is a total
  order -- the subtasks are then listed in that order -- or at most one
  subtask); ``ordering`` keeps the ``(before, after)`` ids as written.
* :class:`HDDLProblem`: ``objects`` (the problem's own; see :func:`all_objects`
  for the domain's constants too), ``init`` as :class:`Fact` (``pred``,
  ``args``; positive facts only), the initial task network (``htn_params``,
  ``htn_subtasks``, ``ordered``, ``htn_ordering``, at ``htn_line``/``htn_col``;
  no ``:htn`` is an empty network) and the ``goal``; ``where`` maps
  ``("object", name)`` to its position.
* :class:`Formula` ``(kind, children, line, col)``, a small tagged tree; the
  children by kind::

      "and" / "or"          (f1, f2, ...)        # may be empty: "(and)"
      "not"                 (f,)
      "imply"               (a, b)
      "="                   (term1, term2)
      "pred"                (name, (term, ...))
      "forall" / "exists"   (params, f)
      "when"                (condition, effect)

  Preconditions, effects and goals written ``()`` are ``None``.

Total order: :func:`is_total_order` tells, :func:`refuse_partial_order` raises a
``FileError`` naming each method (and the problem's task network) that is not
totally ordered, at its position.  Reading itself accepts partial orders (they
are recorded as ``ordered=False``) so that a caller can say why it refuses.

Refused by name (``FileError``): numeric fluents (``:functions``, ``increase``
..., numeric comparisons, ``(= (f) 3)`` in ``:init``), durative actions,
derived predicates, ``:constraints`` (problem trajectory constraints, and the
initial task network's; a method's ``:constraints`` are read: ``=``,
``(not (= ...))`` and ``(sortof ?v - type)``), preferences, ``:metric``,
``either`` types, method effects, abstract tasks with preconditions or effects,
causal links, timed initial literals, task insertion (``:tihtn``) and the
requirements that announce them.
"""

from __future__ import annotations

import difflib
import heapq
import os
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import NamedTuple

from userfiles.errors import FileError, Problem
from userfiles.yamlsafe import read_text

MAX_BYTES = 32 * 1024 * 1024
"""Largest HDDL file accepted by default (the largest problem of the suite here is 150 KB)."""
MAX_DEPTH = 256
"""Deepest nesting of parentheses accepted."""
MAX_PROBLEMS = 200
"""At most this many problems are reported for one file (then a count of the rest)."""

Params = tuple[tuple[str, str], ...]

# --------------------------------------------------------------------------- tokens


class Token(NamedTuple):
    """``kind`` is ``"("``, ``")"`` or ``"atom"``; ``value`` is ``text`` in lower case."""

    kind: str
    value: str
    text: str
    line: int
    col: int


_TOKEN = re.compile(r"\n|[()]|;[^\n]*|[^\s();]+")


def tokenize(text: str) -> list[Token]:
    """The tokens of an HDDL text, comments left out, each with its line and column."""
    tokens: list[Token] = []
    line, start = 1, 0
    for match in _TOKEN.finditer(text):
        word = match.group()
        if word == "\n":
            line, start = line + 1, match.end()
        elif word[0] != ";":
            kind = word if word in ("(", ")") else "atom"
            tokens.append(Token(kind, word.lower(), word, line, match.start() - start + 1))
    return tokens


# --------------------------------------------------------------------------- S-expressions


class Symbol(NamedTuple):
    """An atom: ``value`` in lower case, ``text`` as written."""

    value: str
    text: str
    line: int
    col: int


class SList(NamedTuple):
    """A parenthesised list; ``line``/``col`` are those of its ``(``, ``end_*`` of its ``)``."""

    items: tuple[Node, ...]
    line: int
    col: int
    end_line: int
    end_col: int


Node = Symbol | SList

_SECTION_WORDS = frozenset({
    ":requirements", ":types", ":constants", ":predicates", ":functions", ":task", ":action",
    ":method", ":durative-action", ":derived", ":objects", ":htn", ":init", ":goal",
    ":domain", ":constraints", ":metric",
})


def read_sexpr(text: str, file: str = "<string>") -> list[Node]:
    """Every top-level S-expression of ``text``; ``FileError`` on a syntax error."""
    problems: list[Problem] = []
    new = tuple.__new__  # builds the named tuples below without their slower __new__
    stack: list[list[Node]] = [[]]
    top = stack[0]
    opens: list[tuple[int, int]] = []
    line, start, end = 1, 0, (1, 1)
    for match in _TOKEN.finditer(text):
        word = match.group()
        if word == "\n":
            line, start = line + 1, match.end()
            continue
        col = match.start() - start + 1
        if word == "(":
            if len(opens) >= MAX_DEPTH:
                raise FileError([Problem(file, line, col,
                                         f"parentheses nested deeper than {MAX_DEPTH} levels")])
            opens.append((line, col))
            top = []
            stack.append(top)
        elif word == ")":
            if not opens:
                problems.append(Problem(file, line, col, "unexpected ')': no '(' is open here"))
                continue
            opened_line, opened_col = opens.pop()
            items = stack.pop()
            top = stack[-1]
            top.append(new(SList, (tuple(items), opened_line, opened_col, line, col)))
        elif word[0] != ";":
            top.append(new(Symbol, (word.lower(), word, line, col)))
        else:
            continue
        end = (line, col + len(word))
    if problems and len(stack[0]) > 1 and isinstance(stack[0][0], SList):
        first, after = stack[0][0], stack[0][1]
        problems.append(Problem(file, first.end_line, first.end_col,
                                f"the first list of the file ends here, but the file goes on at "
                                f"{after.line}:{after.col}: is this ')' one too many?"))
    if opens:
        for opened_line, opened_col in opens:
            problems.append(Problem(file, opened_line, opened_col,
                                    f"'(' is never closed (the file ends at {end[0]}:{end[1]})"))
        # A ')' missing in the middle leaves the outermost '(' open and nests the next
        # section inside the previous one: point at the first section that is too deep.
        for items in stack[1:]:
            for node in items:
                found = _nested_section(node)
                if found is not None:
                    inner, outer = found
                    problems.append(Problem(
                        file, inner.line, inner.col,
                        f"'({_head_text(inner)}' is inside '({_head_text(outer)}' opened at "
                        f"{outer.line}:{outer.col}: a ')' is probably missing before it"))
                    break
            else:
                continue
            break
    if problems:
        raise FileError(problems)
    return stack[0]


def _head_text(node: SList) -> str:
    head = node.items[0] if node.items else None
    return head.text if isinstance(head, Symbol) else ""


def _is_section(node: Node) -> bool:
    return (isinstance(node, SList) and bool(node.items) and isinstance(node.items[0], Symbol)
            and node.items[0].value in _SECTION_WORDS)


def _nested_section(node: Node) -> tuple[SList, SList] | None:
    """The first section list nested inside another section list, with that section."""
    if not isinstance(node, SList):
        return None
    todo: list[tuple[SList, SList | None]] = [(node, node if _is_section(node) else None)]
    while todo:
        current, section = todo.pop(0)
        for child in current.items:
            if not isinstance(child, SList):
                continue
            if _is_section(child) and section is not None:
                return child, section
            todo.append((child, section if section is not None else
                         (child if _is_section(child) else None)))
    return None


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


# --------------------------------------------------------------------------- public API


def read_domain(path: str | os.PathLike[str], *, max_bytes: int = MAX_BYTES) -> HDDLDomain:
    """Read and check an HDDL domain file; ``FileError`` with every problem found."""
    name = os.fspath(path)
    return parse_domain(read_text(name, max_bytes=max_bytes), name)


def read_problem(path: str | os.PathLike[str], domain: HDDLDomain, *,
                 max_bytes: int = MAX_BYTES) -> HDDLProblem:
    """Read and check an HDDL problem file against ``domain``."""
    name = os.fspath(path)
    return parse_problem(read_text(name, max_bytes=max_bytes), domain, name)


def parse_domain(text: str, file: str = "<string>") -> HDDLDomain:
    """:func:`read_domain` for a text already in memory."""
    reader = _DomainReader(file)
    domain = reader.read(_definition(text, file, "domain"))
    reader.finish()
    return domain


def parse_problem(text: str, domain: HDDLDomain, file: str = "<string>") -> HDDLProblem:
    """:func:`read_problem` for a text already in memory."""
    reader = _ProblemReader(file, domain)
    problem = reader.read(_definition(text, file, "problem"))
    reader.finish()
    return problem


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


# --------------------------------------------------------------------------- vocabulary

_NAME = re.compile(r"[a-z_][a-z0-9_\-]*\Z")
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?\Z")

_UNSUPPORTED_SECTIONS = {
    ":functions": "numeric fluents",
    ":durative-action": "durative actions",
    ":derived": "derived predicates",
    ":constraints": "state-trajectory constraints",
    ":metric": "plan metrics",
    ":tihtn": "task insertion",
    ":htnti": "task insertion",
    ":process": "PDDL+ processes",
    ":event": "PDDL+ events",
}
_UNSUPPORTED_REQUIREMENTS = {
    ":durative-actions": "durative actions",
    ":duration-inequalities": "durative actions",
    ":continuous-effects": "continuous effects",
    ":fluents": "numeric and object fluents",
    ":numeric-fluents": "numeric fluents",
    ":object-fluents": "object fluents",
    ":action-costs": "action costs (numeric fluents)",
    ":timed-initial-literals": "timed initial literals",
    ":preferences": "preferences",
    ":constraints": "state-trajectory constraints",
    ":derived-predicates": "derived predicates",
    ":time": "PDDL+ time",
}
_NUMERIC_EFFECTS = frozenset({"increase", "decrease", "assign", "scale-up", "scale-down"})
_COMPARISONS = frozenset({"<", ">", "<=", ">="})
_TEMPORAL = frozenset({"at", "over"})
_SUBTASK_KEYS = {":subtasks": ":subtasks", ":tasks": ":subtasks",
                 ":ordered-subtasks": ":ordered-subtasks", ":ordered-tasks": ":ordered-subtasks",
                 ":ordering": ":ordering", ":order": ":ordering"}
_NETWORK_UNSUPPORTED = {
    ":constraints": "task-network constraints (supported in methods only)",
    ":causal-links": "causal links",
    ":causallinks": "causal links",
}


def _hint(word: str, choices: Iterable[str]) -> str:
    pool = list(choices)
    if not pool or len(pool) > 5000:
        return ""
    close = difflib.get_close_matches(word, pool, n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""


def _a(word: str) -> str:
    return f"{'an' if word[:1] in 'aeiou' else 'a'} {word}"


def _show(node: Node) -> str:
    return f"'{node.text}'" if isinstance(node, Symbol) else "a list"


def _definition(text: str, file: str, kind: str) -> tuple[SList, Symbol]:
    """The ``(define (KIND NAME) ...)`` form of a text and its name."""
    forms = read_sexpr(text, file)
    if not forms:
        raise FileError([Problem(file, 1, 1, f"empty file: expected '(define ({kind} NAME) ...)'")])
    problems: list[Problem] = []
    first = forms[0]
    for extra in forms[1:]:
        if isinstance(first, SList):
            where = f"the definition ends at {first.end_line}:{first.end_col}"
            problems.append(Problem(file, extra.line, extra.col,
                                    f"{_show(extra)} after the end of the definition ({where}; "
                                    "is there a ')' too many before it?)"))
        else:
            problems.append(Problem(file, extra.line, extra.col, f"unexpected {_show(extra)}"))
    expected = f"expected '(define ({kind} NAME) ...)'"
    if not isinstance(first, SList):
        raise FileError([*problems, Problem(file, first.line, first.col,
                                            f"{expected}, found {_show(first)}")])
    items = first.items
    if not items or not isinstance(items[0], Symbol) or items[0].value != "define":
        at = items[0] if items else first
        raise FileError([*problems, Problem(file, at.line, at.col,
                                            f"{expected}, found {_show(at)}")])
    header = items[1] if len(items) > 1 else None
    if (not isinstance(header, SList) or len(header.items) != 2
            or not all(isinstance(i, Symbol) for i in header.items)):
        at = header or items[0]
        raise FileError([*problems, Problem(file, at.line, at.col,
                                            f"{expected}: '({kind} NAME)' must follow 'define'")])
    word, name = header.items
    assert isinstance(word, Symbol) and isinstance(name, Symbol)
    if word.value != kind:
        other = "problem" if kind == "domain" else "domain"
        message = (f"this file defines a {other}, not a {kind}" if word.value == other else
                   f"{expected}, found '({word.text} ...)'")
        raise FileError([*problems, Problem(file, word.line, word.col, message)])
    if problems:
        raise FileError(problems)
    return first, name


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


# --------------------------------------------------------------------------- checking reader


class _Reader:
    """What domains and problems share: problems, names, parameters, formulas, networks."""

    def __init__(self, file: str):
        self.file = file
        self.problems: list[Problem] = []
        self.types: dict[str, str | None] = {"object": None}
        self.predicates: dict[str, Params] = {}
        self.tasks: dict[str, Params] = {}
        self.action_params: dict[str, Params] = {}
        self.objects: dict[str, str] = {}
        """Every name a term may be: constants (and, in a problem, objects)."""
        self.object_word = "constant"

    # -- problems

    def error(self, at: Node | Token | Subtask, message: str) -> None:
        self.problems.append(Problem(self.file, at.line, at.col, message))

    def finish(self) -> None:
        if not self.problems:
            return
        found = sorted(set(self.problems))
        if len(found) > MAX_PROBLEMS:
            rest = found[MAX_PROBLEMS]
            found = [*found[:MAX_PROBLEMS],
                     Problem(self.file, rest.line, rest.col,
                             f"... and {len(found) - MAX_PROBLEMS} more problems")]
        raise FileError(found)

    # -- names

    def name(self, node: Node, what: str) -> str | None:
        """A valid name (lower case), or None after reporting why it is not one."""
        if not isinstance(node, Symbol):
            self.error(node, f"expected the name of {what}, found a list")
            return None
        if not _NAME.match(node.value):
            if node.value.startswith("?"):
                self.error(node, f"expected the name of {what}, found the variable '{node.text}'")
            elif node.value.startswith(":"):
                self.error(node, f"expected the name of {what}, found the keyword '{node.text}'")
            else:
                self.error(node, f"'{node.text}' is not a valid name for {what} (a name starts "
                                 "with a letter and has letters, digits, '-' and '_')")
            return None
        return node.value

    def variable(self, node: Symbol) -> str | None:
        if not node.value.startswith("?") or not _NAME.match(node.value[1:]):
            if _NAME.match(node.value):
                self.error(node, f"expected a variable, found '{node.text}' (variables start "
                                 "with '?')")
            else:
                self.error(node, f"'{node.text}' is not a valid variable (a variable is '?' "
                                 "and a name)")
            return None
        return node.value

    def known_type(self, node: Node | None, kind: str) -> bool:
        if kind in self.types:
            return True
        self.error(node, f"unknown type '{node.text if isinstance(node, Symbol) else kind}'"
                         f"{_hint(kind, self.types)}")
        return False

    # -- typed lists

    def typed_list(self, node: SList, variables: bool, what: str = "a variable"
                   ) -> list[tuple[Symbol, str, Node | None]]:
        """``a b - t c`` as (symbol, type, type node); untyped names are ``object``.

        ``what`` names the items (``a type``, ``an object``...) when they are not variables.
        """
        out: list[tuple[Symbol, str, Node | None]] = []
        pending: list[Symbol] = []
        items = node.items
        i = 0
        while i < len(items):
            item = items[i]
            if isinstance(item, Symbol) and item.value == "-":
                if i + 1 >= len(items):
                    self.error(item, "'-' must be followed by a type")
                    break
                kind_node = items[i + 1]
                kind = "object"
                if isinstance(kind_node, SList):
                    head = kind_node.items[0] if kind_node.items else None
                    if isinstance(head, Symbol) and head.value == "either":
                        self.error(kind_node, "'either' types are not supported")
                    else:
                        self.error(kind_node, "expected a type after '-', found a list")
                else:
                    checked = self.name(kind_node, "a type")
                    if checked is not None:
                        kind = checked
                if not pending:
                    self.error(item, "'-' must follow the names it gives a type to")
                out.extend((p, kind, kind_node) for p in pending)
                pending = []
                i += 2
                continue
            if isinstance(item, SList):
                self.error(item, f"expected {what}, found a list")
            elif self.variable(item) if variables else self.name(item, what):
                pending.append(item)
            i += 1
        out.extend((p, "object", None) for p in pending)
        return out

    def params(self, node: Node | None, what: str) -> Params:
        """A parameter list ``(?a ?b - t ...)``: no duplicates, known types."""
        if node is None:
            return ()
        if not isinstance(node, SList):
            self.error(node, f"the parameters of {what} must be a list like '(?x - type)', "
                             f"found {_show(node)}")
            return ()
        seen: dict[str, Symbol] = {}
        out: list[tuple[str, str]] = []
        for symbol, kind, kind_node in self.typed_list(node, variables=True):
            if symbol.value in seen:
                first = seen[symbol.value]
                self.error(symbol, f"duplicate parameter '{symbol.text}' of {what} (first at "
                                   f"{first.line}:{first.col})")
                continue
            seen[symbol.value] = symbol
            if kind_node is not None and not self.known_type(kind_node, kind):
                kind = "object"
            out.append((symbol.value, kind))
        return tuple(out)

    def fits(self, kind: str, wanted: str) -> bool:
        current: str | None = kind
        seen = set()
        while current is not None and current not in seen:
            if current == wanted:
                return True
            seen.add(current)
            current = self.types.get(current)
        return wanted == "object"

    # -- terms and atoms

    def terms(self, items: Iterable[Node], scope: dict[str, str],
              signature: Params | None, what: str) -> tuple[str, ...] | None:
        """Terms (variables of ``scope``, or constants) given to ``signature``'s parameters."""
        out: list[str] = []
        good = True
        for index, item in enumerate(items):
            if isinstance(item, SList):
                self.error(item, "expected a variable or a constant, found a list (function "
                                 "terms are not supported)")
                good = False
                continue
            value = item.value
            if value.startswith("?"):
                if value not in scope:
                    known = (f"declared: {', '.join(scope)}" if scope else
                             "no variables are in scope here")
                    self.error(item, f"variable '{item.text}' is not declared ({known})"
                                     f"{_hint(value, scope)}")
                    good = False
            elif _NUMBER.match(value):
                self.error(item, f"number '{item.text}' where a constant is expected (numeric "
                                 "fluents are not supported)")
                good = False
            elif value not in self.objects:
                if _NAME.match(value):
                    self.error(item, f"unknown {self.object_word} '{item.text}'"
                                     f"{_hint(value, self.objects)}")
                else:
                    self.error(item, f"expected a variable or a constant, found '{item.text}'")
                good = False
            elif signature is not None and index < len(signature):
                wanted = signature[index][1]
                kind = self.objects[value]
                if not self.fits(kind, wanted):
                    self.error(item, f"'{item.text}' is {_a(kind)}, but argument {index + 1} of "
                                     f"{what} is {_a(wanted)}")
                    good = False
            out.append(value)
        return tuple(out) if good else None

    def arity(self, at: Node, what: str, signature: Params, given: int) -> bool:
        if len(signature) == given:
            return True
        self.error(at, f"{what} takes {len(signature)} argument(s), given {given}")
        return False

    def atom(self, node: SList, scope: dict[str, str]) -> Formula | None:
        head = node.items[0]
        assert isinstance(head, Symbol)
        name = head.value
        if name not in self.predicates:
            if name in self.tasks or name in self.action_params:
                kind = "task" if name in self.tasks else "action"
                self.error(head, f"'{head.text}' is an {kind}, not a predicate")
            elif name.startswith("?"):
                self.error(head, f"expected a predicate, found the variable '{head.text}'")
            else:
                self.error(head, f"unknown predicate '{head.text}'"
                                 f"{_hint(name, self.predicates)}")
            self.terms(node.items[1:], scope, None, "")
            return None
        signature = self.predicates[name]
        args = node.items[1:]
        ok = self.arity(head, f"predicate '{head.text}'", signature, len(args))
        terms = self.terms(args, scope, signature, f"'{head.text}'")
        if not ok or terms is None:
            return None
        return Formula("pred", (name, terms), node.line, node.col)

    # -- conditions and effects

    def condition(self, node: Node | None, scope: dict[str, str]) -> Formula | None:
        """A precondition or goal; ``()`` is None."""
        if node is None or (isinstance(node, SList) and not node.items):
            return None
        return self.gd(node, scope)

    def gd(self, node: Node, scope: dict[str, str]) -> Formula | None:
        if isinstance(node, Symbol):
            self.error(node, f"expected a condition in parentheses, found {_show(node)}")
            return None
        if not node.items:
            return Formula("and", (), node.line, node.col)
        head, args = node.items[0], node.items[1:]
        if isinstance(head, SList):
            self.error(head, "expected a predicate or 'and', 'or', 'not', 'imply', 'exists', "
                             "'forall', '=', found a list")
            return None
        word = head.value
        if word in ("and", "or"):
            parts = [self.gd(a, scope) for a in args]
            if any(p is None for p in parts):
                return None
            return Formula(word, tuple(parts), node.line, node.col)
        if word == "not":
            if not self.count(node, head, args, 1):
                return None
            inner = self.gd(args[0], scope)
            return None if inner is None else Formula("not", (inner,), node.line, node.col)
        if word == "imply":
            if not self.count(node, head, args, 2):
                return None
            a, b = self.gd(args[0], scope), self.gd(args[1], scope)
            return None if a is None or b is None else Formula("imply", (a, b), node.line,
                                                               node.col)
        if word in ("forall", "exists"):
            return self.quantified(node, head, args, scope, self.gd)
        if word == "=":
            if not self.count(node, head, args, 2):
                return None
            terms = self.terms(args, scope, None, "'='")
            return None if terms is None else Formula("=", terms, node.line, node.col)
        if self.unsupported(head, args):
            return None
        if word == "when":
            self.error(head, "'when' is a conditional effect; it cannot appear in a condition")
            return None
        return self.atom(node, scope)

    def effect(self, node: Node | None, scope: dict[str, str], top: bool = False
               ) -> Formula | None:
        if node is None:
            return None
        if isinstance(node, Symbol):
            self.error(node, f"expected an effect in parentheses, found {_show(node)}")
            return None
        if not node.items:
            return None if top else Formula("and", (), node.line, node.col)
        head, args = node.items[0], node.items[1:]
        if isinstance(head, SList):
            self.error(head, "expected a predicate or 'and', 'not', 'forall', 'when', found a "
                             "list")
            return None
        word = head.value
        if word == "and":
            parts = [self.effect(a, scope) for a in args]
            if any(p is None for p in parts):
                return None
            return Formula("and", tuple(parts), node.line, node.col)
        if word == "not":
            if not self.count(node, head, args, 1):
                return None
            inner = args[0]
            if (not isinstance(inner, SList) or not inner.items
                    or not isinstance(inner.items[0], Symbol)
                    or inner.items[0].value in ("and", "or", "not", "forall", "exists", "when",
                                                "imply", "=")):
                self.error(inner, "'not' in an effect must hold a single predicate, like "
                                  "'(not (p ?x))'")
                return None
            if self.unsupported(inner.items[0], inner.items[1:]):
                return None
            atom = self.atom(inner, scope)
            return None if atom is None else Formula("not", (atom,), node.line, node.col)
        if word == "forall":
            return self.quantified(node, head, args, scope, self.effect)
        if word == "when":
            if not self.count(node, head, args, 2):
                return None
            condition = self.condition(args[0], scope)
            if condition is None and isinstance(args[0], SList) and not args[0].items:
                condition = Formula("and", (), args[0].line, args[0].col)
            result = self.effect(args[1], scope)
            if condition is None or result is None:
                return None
            return Formula("when", (condition, result), node.line, node.col)
        if word in ("or", "exists", "imply", "="):
            self.error(head, f"'{head.text}' is not allowed in an effect")
            return None
        if self.unsupported(head, args):
            return None
        return self.atom(node, scope)

    def unsupported(self, head: Symbol, args: tuple[Node, ...]) -> bool:
        """Report a construct refused by name (numeric, temporal, preferences...)."""
        word = head.value
        if word in _NUMERIC_EFFECTS:
            self.error(head, f"numeric effect '{head.text}' is not supported (numeric fluents)")
        elif word in _COMPARISONS:
            self.error(head, f"numeric comparison '{head.text}' is not supported (numeric "
                             "fluents)")
        elif word == "preference":
            self.error(head, "preferences ('preference') are not supported")
        elif word in ("sortof", "typeof"):
            self.error(head, f"'{head.text}' constraints are not supported")
        elif (word in _TEMPORAL and word not in self.predicates and args
              and isinstance(args[0], Symbol) and args[0].value in ("start", "end", "all")):
            self.error(head, f"temporal '({head.text} {args[0].text} ...)' is not supported "
                             "(durative actions)")
        else:
            return False
        return True

    def count(self, node: SList, head: Symbol, args: tuple[Node, ...], wanted: int) -> bool:
        if len(args) == wanted:
            return True
        self.error(head if args else node,
                   f"'{head.text}' takes {wanted} argument(s), given {len(args)}")
        return False

    def quantified(self, node: SList, head: Symbol, args: tuple[Node, ...],
                   scope: dict[str, str], body_reader) -> Formula | None:
        if not self.count(node, head, args, 2):
            return None
        if not isinstance(args[0], SList):
            self.error(args[0], f"'{head.text}' needs its variables in a list, like "
                                "'(?x - type)'")
            return None
        params = self.params(args[0], f"'{head.text}'")
        inner_scope = {**scope, **dict(params)}
        body = body_reader(args[1], inner_scope)
        if body is None:
            return None
        return Formula(head.value, (params, body), node.line, node.col)

    # -- keyed lists: (:action NAME :key value ...)

    def keyed(self, items: tuple[Node, ...], allowed: dict[str, str],
              unsupported: dict[str, str], what: str) -> dict[str, tuple[Symbol, Node]]:
        out: dict[str, tuple[Symbol, Node]] = {}
        i = 0
        while i < len(items):
            key = items[i]
            if not isinstance(key, Symbol) or not key.value.startswith(":"):
                keys = ", ".join(sorted({k for k in allowed}))
                self.error(key, f"expected a keyword of {what} ({keys}), found {_show(key)}")
                i += 1
                continue
            value = items[i + 1] if i + 1 < len(items) else None
            if value is None or (isinstance(value, Symbol) and value.value.startswith(":")):
                self.error(key, f"'{key.text}' of {what} has no value")
                i += 1
                continue
            i += 2
            if key.value in unsupported:
                self.error(key, f"'{key.text}' is not supported in {what} "
                                f"({unsupported[key.value]})")
                continue
            if key.value not in allowed:
                self.error(key, f"unknown keyword '{key.text}' in {what}"
                                f"{_hint(key.value, allowed)}")
                continue
            canonical = allowed[key.value]
            if canonical in out:
                first = out[canonical][0]
                self.error(key, f"'{key.text}' given twice in {what} (first at "
                                f"{first.line}:{first.col})")
                continue
            out[canonical] = (key, value)
        return out

    # -- task networks

    def network(self, keys: dict[str, tuple[Symbol, Node]], scope: dict[str, str], what: str
                ) -> tuple[tuple[Subtask, ...], bool, tuple[tuple[str, str], ...]]:
        """Subtasks, whether they are totally ordered, and the ordering as written."""
        plain, ordered_key = keys.get(":subtasks"), keys.get(":ordered-subtasks")
        ordering_key = keys.get(":ordering")
        if plain and ordered_key:
            self.error(ordered_key[0], f"{what} has both '{plain[0].text}' and "
                                       f"'{ordered_key[0].text}'")
        entry = ordered_key or plain
        subtasks = self.subtasks(entry[1], scope) if entry else []
        pairs = self.ordering(ordering_key[1]) if ordering_key else []
        if ordered_key and pairs:
            self.error(ordering_key[0], f"'{ordering_key[0].text}' cannot be used with "
                                        f"'{ordered_key[0].text}', which is already ordered")
            return tuple(subtasks), True, ()
        ids: dict[str, Subtask] = {}
        for subtask in subtasks:
            if subtask.id is None:
                continue
            if subtask.id in ids:
                first = ids[subtask.id]
                self.error(subtask, f"duplicate subtask id '{subtask.id}' in {what} (first at "
                                    f"{first.line}:{first.col})")
            ids[subtask.id] = subtask
        written: list[tuple[str, str]] = []
        for before, after in pairs:
            good = True
            for symbol in (before, after):
                if symbol.value not in ids:
                    known = ", ".join(ids) or "none"
                    self.error(symbol, f"unknown subtask id '{symbol.text}' in the ordering of "
                                       f"{what} (ids: {known}){_hint(symbol.value, ids)}")
                    good = False
            if good and before.value == after.value:
                self.error(before, f"subtask '{before.text}' cannot come before itself")
                good = False
            if good:
                written.append((before.value, after.value))
        if ordered_key:
            return tuple(subtasks), True, ()
        result = _order(subtasks, written)
        if result.cycle:
            names = ", ".join(_label(subtasks[i], i) for i in result.cycle)
            assert ordering_key is not None
            self.error(ordering_key[0], f"the ordering of {what} has a cycle through {names}")
            return tuple(subtasks), False, tuple(written)
        if result.order is not None:
            return tuple(subtasks[i] for i in result.order), True, tuple(written)
        return tuple(subtasks), False, tuple(written)

    def subtasks(self, node: Node, scope: dict[str, str]) -> list[Subtask]:
        if not isinstance(node, SList):
            self.error(node, f"expected subtasks like '(and (t1 (task ?x)) ...)', found "
                             f"{_show(node)}")
            return []
        if not node.items:
            return []
        head = node.items[0]
        entries = (node.items[1:] if isinstance(head, Symbol) and head.value == "and"
                   else (node,))
        out = []
        for entry in entries:
            subtask = self.subtask(entry, scope)
            if subtask is not None:
                out.append(subtask)
        return out

    def subtask(self, entry: Node, scope: dict[str, str]) -> Subtask | None:
        if not isinstance(entry, SList) or not entry.items:
            self.error(entry, f"expected a subtask like '(task ?x)' or '(id (task ?x))', found "
                              f"{_show(entry) if isinstance(entry, Symbol) else '()'}")
            return None
        ident: str | None = None
        call = entry
        if len(entry.items) == 2 and isinstance(entry.items[1], SList):
            ident = self.name(entry.items[0], "a subtask id")
            call = entry.items[1]
            if ident is None:
                return None
            if not call.items:
                self.error(call, "expected a task like '(task ?x)', found '()'")
                return None
        head = call.items[0]
        if not isinstance(head, Symbol):
            self.error(head, "expected the name of a task or an action, found a list")
            return None
        name = head.value
        signature = self.tasks.get(name, self.action_params.get(name))
        if signature is None:
            known = [*self.tasks, *self.action_params]
            what = "predicate" if name in self.predicates else None
            if what:
                self.error(head, f"'{head.text}' is a predicate, not a task or an action")
            else:
                self.error(head, f"unknown task or action '{head.text}'{_hint(name, known)}")
            self.terms(call.items[1:], scope, None, "")
            # Kept (the file is refused anyway) so that its id does not look unknown.
            return Subtask(ident, name, (), entry.line, entry.col)
        kind = "task" if name in self.tasks else "action"
        ok = self.arity(head, f"{kind} '{head.text}'", signature, len(call.items) - 1)
        args = self.terms(call.items[1:], scope, signature, f"{kind} '{head.text}'")
        return Subtask(ident, name, args if ok and args is not None else (), entry.line,
                       entry.col)

    def ordering(self, node: Node) -> list[tuple[Symbol, Symbol]]:
        if not isinstance(node, SList):
            self.error(node, f"expected ordering constraints like '(and (< t1 t2))', found "
                             f"{_show(node)}")
            return []
        if not node.items:
            return []
        head = node.items[0]
        entries = (node.items[1:] if isinstance(head, Symbol) and head.value == "and"
                   else (node,))
        out: list[tuple[Symbol, Symbol]] = []
        for entry in entries:
            items = entry.items if isinstance(entry, SList) else ()
            if len(items) == 3 and all(isinstance(i, Symbol) for i in items):
                a, b, c = items
                assert isinstance(a, Symbol) and isinstance(b, Symbol) and isinstance(c, Symbol)
                if a.value == "<":
                    out.append((b, c))
                    continue
                if b.value == "<":
                    out.append((a, c))
                    continue
                if a.value == ">" or b.value == ">":
                    self.error(entry, "only '<' orders subtasks: write '(< t1 t2)'")
                    continue
            self.error(entry, "expected an ordering constraint like '(< t1 t2)', found "
                              f"{_show(entry) if isinstance(entry, Symbol) else 'a list'}")
        return out

    # -- sections

    def requirements(self, node: SList) -> list[str]:
        out = []
        for item in node.items[1:]:
            if not isinstance(item, Symbol) or not item.value.startswith(":"):
                self.error(item, f"expected a requirement like ':typing', found {_show(item)}")
                continue
            if item.value in _UNSUPPORTED_REQUIREMENTS:
                self.error(item, f"requirement '{item.text}' is not supported "
                                 f"({_UNSUPPORTED_REQUIREMENTS[item.value]})")
            out.append(item.value)
        return out

    def sections(self, define: SList, allowed: Iterable[str]
                 ) -> list[tuple[str, SList]]:
        """The sections after the header, as (keyword, list); others are reported."""
        known = set(allowed)
        out: list[tuple[str, SList]] = []
        for node in define.items[2:]:
            head = node.items[0] if isinstance(node, SList) and node.items else None
            if not isinstance(head, Symbol) or not head.value.startswith(":"):
                self.error(node, f"expected a section like '({sorted(known)[0]} ...)', found "
                                 f"{_show(node) if isinstance(node, Symbol) else 'a list'}")
                continue
            assert isinstance(node, SList)
            if head.value in _UNSUPPORTED_SECTIONS:
                self.error(head, f"'{head.text}' is not supported "
                                 f"({_UNSUPPORTED_SECTIONS[head.value]})")
                continue
            if head.value not in known:
                self.error(head, f"unknown section '{head.text}'{_hint(head.value, known)}"
                                 f"; expected one of {', '.join(sorted(known))}")
                continue
            out.append((head.value, node))
        return out


class _DomainReader(_Reader):
    def read(self, definition: tuple[SList, Symbol]) -> HDDLDomain:
        define, name_node = definition
        domain_name = self.name(name_node, "the domain") or name_node.value
        sections = self.sections(define, (":requirements", ":types", ":constants", ":predicates",
                                          ":task", ":action", ":method"))
        where: dict[tuple[str, str], tuple[int, int]] = {}
        requirements: list[str] = []
        for word, node in sections:
            if word == ":requirements":
                requirements.extend(self.requirements(node))
        self.read_types([n for w, n in sections if w == ":types"], where)
        for word, node in sections:
            if word == ":constants":
                self.read_constants(node, where)
        for word, node in sections:
            if word == ":predicates":
                self.read_predicates(node, where)
        declared: list[tuple[str, SList, dict[str, tuple[Symbol, Node]], str]] = []
        for word, node in sections:
            if word in (":task", ":action"):
                found = self.declare(word, node, where)
                if found is not None:
                    declared.append(found)
        actions: dict[str, HAction] = {}
        for word, node, keys, name in declared:
            if word == ":action":
                scope = dict(self.action_params[name])
                pre = keys.get(":precondition")
                eff = keys.get(":effect")
                actions[name] = HAction(
                    name, self.action_params[name],
                    self.condition(pre[1], scope) if pre else None,
                    self.effect(eff[1], scope, top=True) if eff else None,
                    node.line, node.col)
        methods: list[HMethod] = []
        for word, node in sections:
            if word == ":method":
                method = self.read_method(node, where)
                if method is not None:
                    methods.append(method)
        return HDDLDomain(domain_name, tuple(requirements), dict(self.types), dict(self.objects),
                          dict(self.predicates), dict(self.tasks), methods, actions, self.file,
                          define.line, define.col, where)

    def read_types(self, nodes: list[SList], where: dict) -> None:
        explicit: dict[str, tuple[str, Symbol, Node | None]] = {}
        implicit: dict[str, Node] = {}
        for node in nodes:
            body = node._replace(items=node.items[1:])
            for symbol, parent, parent_node in self.typed_list(body, False, "a type"):
                name = symbol.value
                if name == "object":
                    if parent != "object":
                        self.error(symbol, "'object' is the root type; it has no parent")
                    continue
                if name in explicit:
                    first = explicit[name][1]
                    self.error(symbol, f"duplicate type '{symbol.text}' (first at "
                                       f"{first.line}:{first.col})")
                    continue
                explicit[name] = (parent, symbol, parent_node)
                if parent_node is not None and parent != "object":
                    implicit.setdefault(parent, parent_node)
        for name, (parent, symbol, _) in explicit.items():
            self.types[name] = parent
            where[("type", name)] = (symbol.line, symbol.col)
        for name, node in implicit.items():
            if name not in self.types:
                self.types[name] = "object"
                where[("type", name)] = (node.line, node.col)
        for name, (_, symbol, _) in explicit.items():
            seen = [name]
            current = self.types.get(name)
            while current is not None:
                if current == name:
                    self.error(symbol, f"type '{symbol.text}' is its own ancestor ("
                                       f"{' - '.join([*seen, name])})")
                    self.types[name] = "object"
                    break
                if current in seen:
                    break
                seen.append(current)
                current = self.types.get(current)

    def read_constants(self, node: SList, where: dict) -> None:
        body = node._replace(items=node.items[1:])
        for symbol, kind, kind_node in self.typed_list(body, False, "a constant"):
            if kind_node is not None and not self.known_type(kind_node, kind):
                kind = "object"
            if symbol.value in self.objects:
                line, col = where[("constant", symbol.value)]
                self.error(symbol, f"duplicate constant '{symbol.text}' (first at {line}:{col})")
                continue
            self.objects[symbol.value] = kind
            where[("constant", symbol.value)] = (symbol.line, symbol.col)

    def read_predicates(self, node: SList, where: dict) -> None:
        for item in node.items[1:]:
            if not isinstance(item, SList) or not item.items:
                self.error(item, f"expected a predicate like '(on ?x ?y - block)', found "
                                 f"{_show(item) if isinstance(item, Symbol) else '()'}")
                continue
            name = self.name(item.items[0], "a predicate")
            if name is None:
                continue
            params = self.params(item._replace(items=item.items[1:]), f"predicate '{name}'")
            if name in self.predicates:
                line, col = where[("predicate", name)]
                self.error(item.items[0], f"duplicate predicate '{item.items[0].text}' (first "
                                          f"at {line}:{col})")
                continue
            self.predicates[name] = params
            where[("predicate", name)] = (item.items[0].line, item.items[0].col)

    def declare(self, word: str, node: SList, where: dict
                ) -> tuple[str, SList, dict[str, tuple[Symbol, Node]], str] | None:
        """A task or an action: its name and parameters (bodies are read later)."""
        kind = word[1:]
        if len(node.items) < 2:
            self.error(node, f"'({word}' needs a name")
            return None
        label = node.items[1]
        name = self.name(label, "a task" if kind == "task" else "an action")
        if name is None or not isinstance(label, Symbol):
            return None
        what = f"{kind} '{label.text}'"
        if kind == "task":
            keys = self.keyed(node.items[2:], {":parameters": ":parameters"}, {
                ":precondition": "abstract tasks with preconditions",
                ":effect": "abstract tasks with effects",
            }, what)
        else:
            keys = self.keyed(node.items[2:], {":parameters": ":parameters",
                                               ":precondition": ":precondition",
                                               ":effect": ":effect"}, {
                ":duration": "durative actions",
                ":condition": "durative actions",
                ":cost": "action costs",
            }, what)
        params = self.params(keys[":parameters"][1] if ":parameters" in keys else None, what)
        for other in ("task", "action"):
            if (other, name) in where:
                line, col = where[(other, name)]
                article = "an" if other == "action" else "a"
                self.error(label, f"duplicate {kind} '{label.text}' (already defined as "
                                  f"{article} {other} at {line}:{col})")
                return None
        where[(kind, name)] = (node.line, node.col)
        if kind == "task":
            self.tasks[name] = params
        else:
            self.action_params[name] = params
        return word, node, keys, name

    def read_method(self, node: SList, where: dict) -> HMethod | None:
        if len(node.items) < 2:
            self.error(node, "'(:method' needs a name")
            return None
        label = node.items[1]
        name = self.name(label, "a method")
        if name is None or not isinstance(label, Symbol):
            return None
        text = label.text
        what = f"method '{text}'"
        keys = self.keyed(node.items[2:], {":parameters": ":parameters", ":task": ":task",
                                           ":precondition": ":precondition",
                                           ":constraints": ":constraints", **_SUBTASK_KEYS},
                          {":effect": "method effects", **{
                              k: v for k, v in _NETWORK_UNSUPPORTED.items()
                              if k != ":constraints"}}, what)
        duplicate = ("method", name) in where
        if duplicate:
            line, col = where[("method", name)]
            self.error(label, f"duplicate method '{text}' (first at {line}:{col})")
        else:
            where[("method", name)] = (node.line, node.col)
        params = self.params(keys[":parameters"][1] if ":parameters" in keys else None, what)
        scope = dict(params)
        constraints, narrowed = (self.constraints(keys[":constraints"][1], scope)
                                 if ":constraints" in keys else (None, {}))
        params = tuple((var, narrowed.get(var, kind)) for var, kind in params)
        scope = dict(params)
        task = self.method_task(keys.get(":task"), scope, what, node)
        pre = keys.get(":precondition")
        precondition = self.condition(pre[1], scope) if pre else None
        subtasks, ordered, ordering = self.network(keys, scope, what)
        if task is None or duplicate:
            return None
        return HMethod(name, params, task, precondition, subtasks, ordered, node.line, node.col,
                       ordering, constraints)

    def constraints(self, node: Node, scope: dict[str, str]
                    ) -> tuple[Formula | None, dict[str, str]]:
        """A method's ``:constraints``: ``(= a b)``, ``(not (= a b))`` and
        ``(sortof ?v - type)`` (``?v`` must be of ``type``, a subtype of its own), in an
        ``and`` or alone.  The conditions, and the narrowed type of each variable."""
        if not isinstance(node, SList):
            self.error(node, f"expected constraints like '(and (sortof ?x - type))', found "
                             f"{_show(node)}")
            return None, {}
        items = node.items
        if items and isinstance(items[0], Symbol) and items[0].value == "and":
            items = items[1:]
        elif items:
            items = (node,)
        parts: list[Formula] = []
        narrowed: dict[str, str] = {}
        for item in items:
            head = item.items[0] if isinstance(item, SList) and item.items else None
            word = head.value if isinstance(head, Symbol) else ""
            inner = (item.items[1] if word == "not" and isinstance(item, SList)
                     and len(item.items) == 2 else None)
            if word == "=" or (isinstance(inner, SList) and inner.items
                               and isinstance(inner.items[0], Symbol)
                               and inner.items[0].value == "="):
                formula = self.gd(item, scope)
                if formula is not None:
                    parts.append(formula)
            elif word == "sortof":
                assert isinstance(item, SList) and isinstance(head, Symbol)
                self.sortof(item, head, scope, narrowed)
            else:
                at = head if head is not None else item
                self.error(at, f"'{_show(at)[1:-1] if isinstance(at, Symbol) else 'a list'}' "
                               "is not a supported method constraint (supported: '=', "
                               "'(not (= ...))' and 'sortof')")
        formula = Formula("and", tuple(parts), node.line, node.col) if parts else None
        return formula, narrowed

    def sortof(self, item: SList, head: Symbol, scope: dict[str, str],
               narrowed: dict[str, str]) -> None:
        """``(sortof ?v - type)``: record ``type`` for ``?v`` when it fits."""
        args = item.items[1:]
        if (len(args) != 3 or not all(isinstance(a, Symbol) for a in args)
                or args[1].value != "-"):
            self.error(head, "expected '(sortof ?variable - type)'")
            return
        var, _, kind = args
        assert isinstance(var, Symbol) and isinstance(kind, Symbol)
        if var.value not in scope:
            self.error(var, f"variable '{var.text}' is not a parameter of the method"
                            f"{_hint(var.value, scope)}")
        elif self.known_type(kind, kind.value):
            if not self.fits(kind.value, scope[var.value]):
                self.error(kind, f"'{kind.text}' is not a subtype of {var.text}'s type "
                                 f"'{scope[var.value]}'")
            else:
                narrowed[var.value] = kind.value

    def method_task(self, entry: tuple[Symbol, Node] | None, scope: dict[str, str], what: str,
                    node: SList) -> Call | None:
        if entry is None:
            self.error(node, f"{what} has no ':task' (the task it decomposes)")
            return None
        key, value = entry
        if not isinstance(value, SList) or not value.items or not isinstance(value.items[0],
                                                                             Symbol):
            self.error(value, f"':task' of {what} must be a task like '(task ?x)'")
            return None
        head = value.items[0]
        assert isinstance(head, Symbol)
        if head.value not in self.tasks:
            if head.value in self.action_params:
                self.error(head, f"{what} decomposes '{head.text}', which is an action, not a "
                                 "task")
            else:
                self.error(head, f"unknown task '{head.text}'{_hint(head.value, self.tasks)}")
            self.terms(value.items[1:], scope, None, "")
            return None
        signature = self.tasks[head.value]
        ok = self.arity(head, f"task '{head.text}'", signature, len(value.items) - 1)
        args = self.terms(value.items[1:], scope, signature, f"task '{head.text}'")
        if not ok or args is None:
            return None
        return Call(head.value, args, value.line, value.col)


class _ProblemReader(_Reader):
    def __init__(self, file: str, domain: HDDLDomain):
        super().__init__(file)
        self.domain = domain
        self.types = dict(domain.types)
        self.predicates = dict(domain.predicates)
        self.tasks = dict(domain.tasks)
        self.action_params = {name: a.params for name, a in domain.actions.items()}
        self.objects = dict(domain.constants)
        self.object_word = "object"

    def read(self, definition: tuple[SList, Symbol]) -> HDDLProblem:
        define, name_node = definition
        problem_name = self.name(name_node, "the problem") or name_node.value
        sections = self.sections(define, (":domain", ":requirements", ":objects", ":htn",
                                          ":init", ":goal"))
        where: dict[tuple[str, str], tuple[int, int]] = {}
        first: dict[str, SList] = {}
        for word, node in sections:
            if word in (":domain", ":htn", ":goal", ":init") and word in first:
                earlier = first[word]
                self.error(node, f"section '{word}' given twice (first at "
                                 f"{earlier.line}:{earlier.col})")
            first.setdefault(word, node)
        domain_name = self.domain.name
        if ":domain" not in first:
            self.error(define, f"the problem does not say its domain: add '(:domain "
                               f"{self.domain.name})'")
        else:
            node = first[":domain"]
            if len(node.items) != 2 or not isinstance(node.items[1], Symbol):
                self.error(node, "expected '(:domain NAME)'")
            else:
                domain_name = node.items[1].value
                if domain_name != self.domain.name:
                    self.error(node.items[1], f"the problem is for domain "
                                              f"'{node.items[1].text}', but the domain read is "
                                              f"'{self.domain.name}' ({self.domain.file})")
        requirements: list[str] = []
        for word, node in sections:
            if word == ":requirements":
                requirements.extend(self.requirements(node))
        own: dict[str, str] = {}
        for word, node in sections:
            if word == ":objects":
                self.read_objects(node, own, where)
        init: list[Fact] = []
        if ":init" in first:
            init = self.read_init(first[":init"])
        params: Params = ()
        subtasks: tuple[Subtask, ...] = ()
        ordered, ordering = True, ()
        htn_line = htn_col = 0
        if ":htn" in first:
            node = first[":htn"]
            htn_line, htn_col = node.line, node.col
            keys = self.keyed(node.items[1:], {":parameters": ":parameters", **_SUBTASK_KEYS},
                              _NETWORK_UNSUPPORTED,
                              "the initial task network (':htn')")
            params = self.params(keys[":parameters"][1] if ":parameters" in keys else None,
                                 "':htn'")
            subtasks, ordered, ordering = self.network(keys, dict(params),
                                                       "the initial task network")
        goal = None
        if ":goal" in first:
            node = first[":goal"]
            if len(node.items) != 2:
                self.error(node, f"'(:goal' needs exactly one condition, given "
                                 f"{len(node.items) - 1}")
            else:
                goal = self.condition(node.items[1], {})
        return HDDLProblem(problem_name, domain_name, own, tuple(init), params, subtasks, ordered,
                           goal, self.file, define.line, define.col, tuple(requirements),
                           ordering, htn_line, htn_col, where)

    def read_objects(self, node: SList, own: dict[str, str], where: dict) -> None:
        body = node._replace(items=node.items[1:])
        for symbol, kind, kind_node in self.typed_list(body, False, "an object"):
            if kind_node is not None and not self.known_type(kind_node, kind):
                kind = "object"
            name = symbol.value
            if name in own:
                line, col = where[("object", name)]
                self.error(symbol, f"duplicate object '{symbol.text}' (first at {line}:{col})")
                continue
            if name in self.domain.constants and self.domain.constants[name] != kind:
                line, col = self.domain.where.get(("constant", name), (1, 1))
                self.error(symbol, f"'{symbol.text}' is {_a(kind)} here but "
                                   f"{_a(self.domain.constants[name])} as a constant of the domain "
                                   f"({self.domain.file}:{line}:{col})")
                continue
            own[name] = kind
            self.objects[name] = kind
            where[("object", name)] = (symbol.line, symbol.col)

    def read_init(self, node: SList) -> list[Fact]:
        facts: list[Fact] = []
        for item in node.items[1:]:
            if not isinstance(item, SList) or not item.items:
                self.error(item, f"expected a fact like '(on a b)', found "
                                 f"{_show(item) if isinstance(item, Symbol) else '()'}")
                continue
            head = item.items[0]
            if not isinstance(head, Symbol):
                self.error(head, "expected a predicate, found a list")
                continue
            if head.value == "=":
                self.error(head, "numeric fluents ('=' in ':init') are not supported")
                continue
            if head.value == "not":
                self.error(head, "'not' in ':init': the initial state lists only the facts that "
                                 "hold")
                continue
            if (head.value == "at" and len(item.items) > 1 and isinstance(item.items[1], Symbol)
                    and _NUMBER.match(item.items[1].value)):
                self.error(head, "timed initial literals ('(at TIME ...)') are not supported")
                continue
            if head.value in ("and", "or", "forall", "exists", "when", "imply"):
                self.error(head, f"'{head.text}' in ':init': the initial state lists facts only")
                continue
            variables = [i for i in item.items[1:]
                         if isinstance(i, Symbol) and i.value.startswith("?")]
            if variables:
                self.error(variables[0], f"variable '{variables[0].text}' in ':init': facts "
                                         "are about objects")
                continue
            fact = self.atom(item, {})
            if fact is not None:
                name, args = fact.children
                facts.append(Fact(name, args, item.line, item.col))
        return facts
