"""Reading HDDL, the HTN extension of PDDL (IPC 2020 HTN track): the total-order subset.

This is a *reader*: it turns a domain file and a problem file into a typed
syntax tree where every piece keeps the line and column it came from, and it
checks the meaning that can be checked without planning.  Translating the tree
into the planner's own model is :mod:`planner.io.translate`'s work.

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
derived predicates, state-trajectory ``:constraints`` (a method's and the
initial task network's ``:constraints`` are read: ``=``, ``(not (= ...))`` and
``(sortof ?v - type)``; others are refused by name), preferences, ``:metric``,
``either`` types, method effects, abstract tasks with (non-empty) preconditions
or effects, causal links, timed initial literals, task insertion (``:tihtn``)
and the requirements that announce them.

The modules: :mod:`~planner.io.hddl.lexer` (tokens, S-expressions),
:mod:`~planner.io.hddl.model` (the tree, types, total order),
:mod:`~planner.io.hddl.reader` (what both readers share),
:mod:`~planner.io.hddl.networks` (task networks and their constraints),
:mod:`~planner.io.hddl.domain_reader`, :mod:`~planner.io.hddl.problem_reader`.
"""


from __future__ import annotations

import os

from planner.io.hddl.domain_reader import _DomainReader
from planner.io.hddl.lexer import MAX_DEPTH, Node, SList, Symbol, Token, read_sexpr, tokenize
from planner.io.hddl.model import (
    Call,
    Fact,
    Formula,
    HAction,
    HDDLDomain,
    HDDLProblem,
    HMethod,
    Params,
    Subtask,
    all_objects,
    is_total_order,
    refuse_partial_order,
    supertypes,
)
from planner.io.hddl.problem_reader import _ProblemReader
from planner.io.hddl.reader import MAX_PROBLEMS, _definition
from userfiles.yamlsafe import read_text

__all__ = [
    "MAX_BYTES", "MAX_DEPTH", "MAX_PROBLEMS", "Call", "Fact", "Formula", "HAction", "HDDLDomain",
    "HDDLProblem", "HMethod", "Node", "Params", "SList", "Subtask", "Symbol", "Token",
    "all_objects", "is_total_order", "parse_domain", "parse_problem", "read_domain",
    "read_problem", "read_sexpr", "refuse_partial_order", "supertypes", "tokenize",
]

MAX_BYTES = 8 * 1024 * 1024
"""Largest HDDL file accepted by default (the largest problem of the suite here is 150 KB;
the reader takes about a second per megabyte on a loaded machine, and a refusal must take
under 10 s)."""


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
