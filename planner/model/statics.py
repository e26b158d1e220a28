"""Which values a method's variables may take in one problem: its types and static facts.

What a task may add (``Domain.adds``) is lifted: a fact that a subtask adds for
one object (Monroe's observation ``p_2`` is person ``person_121967`` climbing
into ``pvan2``) is added by the task above it *for that object* only while the
object is one of the task's own arguments, whose value the pattern can name.
Where it is a method variable instead (``m_get_in_load_in``'s ``?person``, who
walks to the cargo; ``m_set_up_shelter``'s ``?leader``), the lifted analysis
cannot say which value it takes and so says "any task of this kind may add it":
every one of Monroe's ten top-level tasks then "may add" the observations, and
the goal-guided prunings (:mod:`planner.search.checks`, :mod:`planner.heuristics.reach`) see no
difference between them.

Yet most such variables cannot take the value: ``?leader`` is a
``shelter_leader`` and ``person_121967`` is not; ``m_get_in_load_in`` needs
``(can_lift ?person ?obj)``, a fact no action changes, and nobody is lifted by
``person_121967``.  :class:`StaticFilter` answers that question for one
problem: whether some binding of a method can give its variables these values,
judged by their types and by the *static* conjuncts (predicates no action
changes) of the method's precondition and of its actions' preconditions, which
hold when the method is entered or never.  It over-approximates (the other
variables may be anything, fluent conditions may hold), so a pattern it drops
is certainly never added that way.
"""

from __future__ import annotations

from typing import Any

from planner.io import hddl
from planner.model.formulas import conjuncts

Literal = tuple[str, tuple[str, ...]]
"""A static conjunct: its predicate and its terms (variables start with '?')."""


class StaticFilter:
    """The types and static facts of one problem, asked about a method's variables."""

    def __init__(self, domain: hddl.HDDLDomain, objects: dict[str, str],
                 typed: dict[str, list[str]], facts: list[tuple[str, tuple[str, ...]]],
                 changed: set[str]):
        self.actions = {action.name: action for action in domain.actions.values()}
        self.typed = {kind: frozenset(names) for kind, names in typed.items()}
        self.objects = objects
        self.changed = changed
        self.facts: dict[str, list[tuple[str, ...]]] = {}
        for pred, args in facts:
            if pred not in changed:
                self.facts.setdefault(pred, []).append(args)
        self.literals: dict[int, tuple[dict[str, str], tuple[Literal, ...]]] = {}
        """For each method (by id): its variables' types and its static conjuncts."""
        self.matches: dict[tuple[str, tuple[Any, ...]], bool] = {}
        """Whether some static fact fits a pattern (None: any value)."""
        self.answers: dict[tuple[int, tuple[tuple[str, str], ...]], bool] = {}

    def may_be(self, method: hddl.HMethod, binding: dict[str, str]) -> bool:
        """Whether some binding of ``method`` gives its variables ``binding``'s values:
        each value of its variable's type, and every static conjunct of the method's
        precondition and of its actions' preconditions true in the problem with the
        values given (the other variables free)."""
        key = (id(method), tuple(sorted(binding.items())))
        known = self.answers.get(key)
        if known is None:
            known = self._may_be(method, binding)
            self.answers[key] = known
        return known

    def _may_be(self, method: hddl.HMethod, binding: dict[str, str]) -> bool:
        types, literals = self._literals(method)
        for var, value in binding.items():
            kind = types.get(var)
            if kind is not None and value not in self.typed.get(kind, ()):
                return False
        for pred, terms in literals:
            if not any(term in binding for term in terms):
                continue
            pattern = tuple(binding.get(term) if term.startswith("?") else term
                            for term in terms)
            if not self._match(pred, pattern):
                return False
        return True

    def _literals(self, method: hddl.HMethod) -> tuple[dict[str, str], tuple[Literal, ...]]:
        known = self.literals.get(id(method))
        if known is not None:
            return known
        found: list[Literal] = []
        found += self._static(conjuncts(method.precondition), {})
        found += self._static(conjuncts(method.constraints), {})
        for sub in method.subtasks:
            action = self.actions.get(sub.name)
            if action is not None:
                rename = {var: term for (var, _), term in zip(action.params, sub.args,
                                                               strict=True)}
                found += self._static(conjuncts(action.precondition), rename)
        known = (dict(method.params), tuple(found))
        self.literals[id(method)] = known
        return known

    def _static(self, formulas: list[hddl.Formula], rename: dict[str, str]) -> list[Literal]:
        """The positive conjuncts of a static predicate, their terms renamed."""
        out = []
        for formula in formulas:
            if formula.kind != "pred":
                continue
            pred, terms = formula.children
            if pred in self.changed:
                continue
            out.append((pred, tuple(rename.get(t, t) for t in terms)))
        return out

    def _match(self, pred: str, pattern: tuple[Any, ...]) -> bool:
        key = (pred, pattern)
        known = self.matches.get(key)
        if known is None:
            known = any(len(args) == len(pattern)
                        and all(want is None or want == have
                                for want, have in zip(pattern, args, strict=True))
                        for args in self.facts.get(pred, ()))
            self.matches[key] = known
        return known
