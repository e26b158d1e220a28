"""HDDL formulas compiled into closures over ``(env, get)``, with PDDL's semantics.

:mod:`planner.io.translate` turns a read HDDL domain into the planner's model;
the formulas it meets (preconditions, goals, method constraints, effects) are
compiled here, once, into the closures the search calls millions of times.
This is its own module because it changes for its own reasons: what a formula
*means* (PDDL's semantics) and how fast it runs, not how a domain maps onto the
planner's tasks and methods.

* A condition is ``fn(env, get) -> bool``: ``env`` maps variables to objects,
  ``get(pred, args)`` is True when the fact holds.  ``forall`` and ``exists``
  range over the objects of the type and its subtypes (``typed``).
* An effect is ``fn(env, get, set)``: the conditions of conditional effects are
  read in the state before the action, deletions are applied before additions
  (``set(pred, args, None)`` deletes, ``set(pred, args, True)`` adds).
* The common shapes get closures of their own: a flat conjunction of literals
  as one closure, a fact over one or two variables without a key builder.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any

from planner.io import hddl
from planner.model.expr import Expr
from planner.search.binding import args_of, is_variable

Condition = Callable[[dict[str, Any], Any], bool]
Write = Callable[[dict[str, Any], Any, Any], None]


class Formulas:
    """Compiles the formulas of one problem: quantifiers range over ``typed`` (each type's
    objects, its subtypes' included)."""

    def __init__(self, typed: dict[str, list[str]]):
        self.typed = typed

    # -- conditions --------------------------------------------------------------------

    def condition(self, formula: hddl.Formula) -> Condition:
        """A closure telling whether ``formula`` holds, given the variables and the state."""
        kind, children = formula.kind, formula.children
        if kind == "pred":
            return holds(*children)
        if kind == "=":
            left, right = (operand(t) for t in children)
            return lambda env, get: left.fn(env, get) == right.fn(env, get)
        if kind == "not":
            inner = self.condition(children[0])
            return lambda env, get: not inner(env, get)
        if kind in ("and", "or"):
            parts = tuple(self.condition(c) for c in children)
            if len(parts) == 1:
                return parts[0]
            if kind == "and":

                def conjunction(env: dict, get: Any) -> bool:
                    for part in parts:
                        if not part(env, get):
                            return False
                    return True

                return conjunction

            def disjunction(env: dict, get: Any) -> bool:
                for part in parts:
                    if part(env, get):
                        return True
                return False

            return disjunction
        if kind == "imply":
            a, b = (self.condition(c) for c in children)
            return lambda env, get: not a(env, get) or b(env, get)
        params, body = children
        test = self.condition(body)
        names = [v for v, _ in params]
        domains = [self.typed.get(t, []) for _, t in params]
        every = kind == "forall"

        def quantified(env: dict, get: Any) -> bool:
            local = dict(env)
            for values in itertools.product(*domains):
                local.update(zip(names, values, strict=True))
                if test(local, get) is not every:
                    return not every
            return every

        return quantified

    # -- effects ---------------------------------------------------------------------------

    def effect(self, formula: hddl.Formula) -> Write:
        """A closure applying an effect: deletions first, then additions."""
        literals = conjuncts(formula)
        if all(is_literal(f) for f in literals):  # the common case, in one flat closure
            deletes = tuple((f.children[0].children[0], args_of(f.children[0].children[1]))
                            for f in literals if f.kind == "not")
            adds = tuple((f.children[0], args_of(f.children[1]))
                         for f in literals if f.kind == "pred")

            def flat(env: dict, get: Any, set: Any) -> None:
                for pred, key in deletes:
                    set(pred, key(env), None)
                for pred, key in adds:
                    set(pred, key(env), True)

            return flat
        deleting, adding = self.write(formula, False), self.write(formula, True)

        def apply(env: dict, get: Any, set: Any) -> None:
            deleting(env, get, set)
            adding(env, get, set)

        return apply

    def write(self, formula: hddl.Formula, adding: bool) -> Write:
        """A closure making the additions (or the deletions) of an effect."""
        kind, children = formula.kind, formula.children
        if kind == "pred":
            if not adding:
                return _nothing
            pred, key = children[0], args_of(children[1])
            return lambda env, get, set: set(pred, key(env), True)
        if kind == "not":
            if adding:
                return _nothing
            pred, key = children[0].children[0], args_of(children[0].children[1])
            return lambda env, get, set: set(pred, key(env), None)
        if kind == "and":
            parts = tuple(self.write(c, adding) for c in children)
            parts = tuple(p for p in parts if p is not _nothing)
            if not parts:
                return _nothing

            def every(env: dict, get: Any, set: Any) -> None:
                for part in parts:
                    part(env, get, set)

            return every
        if kind == "when":
            condition, inner = self.condition(children[0]), self.write(children[1], adding)
            if inner is _nothing:
                return _nothing

            def when(env: dict, get: Any, set: Any) -> None:
                if condition(env, get):
                    inner(env, get, set)

            return when
        params, body = children  # forall
        inner = self.write(body, adding)
        if inner is _nothing:
            return _nothing
        names = [v for v, _ in params]
        domains = [self.typed.get(t, []) for _, t in params]

        def each(env: dict, get: Any, set: Any) -> None:
            local = dict(env)
            for values in itertools.product(*domains):
                local.update(zip(names, values, strict=True))
                inner(local, get, set)

        return each


def conjuncts(formula: hddl.Formula | None) -> list[hddl.Formula]:
    """The top-level conjuncts of a formula (nested 'and's flattened)."""
    if formula is None:
        return []
    if formula.kind != "and":
        return [formula]
    return [part for child in formula.children for part in conjuncts(child)]


def is_literal(formula: hddl.Formula) -> bool:
    """A fact or a negated fact."""
    return formula.kind == "pred" or (formula.kind == "not"
                                      and formula.children[0].kind == "pred")


def _nothing(env: dict, get: Any, set: Any) -> None:
    """An effect part with nothing to write in this pass."""


def operand(term: str) -> Expr:
    """A subtask argument or an '=' operand: a variable's value or a constant."""
    if is_variable(term):
        return Expr(term, lambda env, get: env[term], frozenset({term}), frozenset(), None)
    return Expr(term, lambda env, get: term, frozenset(), frozenset(), None)


def holds(pred: str, terms: tuple[str, ...]) -> Condition:
    """Whether a fact holds; the common shapes get a closure of their own (the search
    checks preconditions millions of times)."""
    if not terms:
        return lambda env, get: get(pred, ()) is True
    if all(is_variable(t) for t in terms):
        if len(terms) == 1:
            (a,) = terms
            return lambda env, get: get(pred, (env[a],)) is True
        if len(terms) == 2:
            a, b = terms
            return lambda env, get: get(pred, (env[a], env[b])) is True
    key = args_of(terms)
    return lambda env, get: get(pred, key(env)) is True
