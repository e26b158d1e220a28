"""Binding a method's variables from the state's facts (HDDL methods).

An HDDL method names the task it decomposes with its own variables
(``:task (do_put_on ?x ?y)``) and often has variables that nothing but the
state determines: ``m7_do_clear``'s ``?y`` is whatever block is ``(on ?y ?x)``;
``m2_do_on_table``'s ``?y`` is only constrained by the first subtask,
``(unstack ?x ?y)``, whose precondition needs ``(on ?x ?y)``.  Trying every
object of the variable's type is a thousand tries per decomposition on a
1,000-block problem.

A binder is compiled once per method.  It unifies the method's task with the
task's arguments, then takes the conjuncts of the precondition, plus those of
the first subtask's precondition when that subtask is an action (it runs in
the same state, so a binding that makes them false fails at once: they only
narrow the choice), plus the static conjuncts of every later action's
precondition (those that read only facts no effect changes, or equalities: they
hold when the method is entered or never).  Their *positive facts* are looked
up, in a static order that takes the most-determined fact first, in the state's index
(:class:`~planner.model.state.FactState`), for the facts that match what is bound
so far; every other conjunct (negations, equalities, quantifiers) is tested as
soon as its variables are bound.  Variables that no positive fact mentions
take every object of their type, in name order.  What the binder proposes
therefore satisfies the method's precondition: the search does not test it
again (the validator does, independently).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any, NamedTuple

from planner.model.domain import Binder
from planner.model.state import FactState

Atom = tuple[str, tuple[str, ...]]
"""A predicate and its terms: variables (``?x``) or constants."""


class Test(NamedTuple):
    """A conjunct of the conditions a binding must meet, checked as soon as its
    variables are bound; ``atom`` is set when it is a plain fact (which a lookup may
    make true by construction)."""

    variables: frozenset[str]
    holds: Callable[[dict[str, Any], Any], bool]
    atom: Atom | None = None


_MATCH, _TEST, _EACH, _DEFER = 0, 1, 2, 3


def is_variable(term: str) -> bool:
    return term.startswith("?")


def plan_steps(variables: dict[str, str], bound: set[str], tests: list[Test]) -> list[tuple]:
    """The static order of a binder: lookups, tests and enumerations.

    ``bound`` are the variables the task's arguments bind.  A lookup is
    ``(_MATCH, pred, positions, known, free)``: ``positions`` are the argument
    positions known (``known`` gives, for each, a variable or a constant) and
    ``free`` the ``(position, variable)`` pairs it binds.  A test comes as soon
    as its variables are bound; the lookup that binds a fact's last variables
    makes that fact's test needless.
    """
    bound = set(bound)
    pending = list(tests)
    todo = [t.atom for t in tests if t.atom is not None]
    steps: list[tuple] = []

    def ready() -> None:
        for test in [t for t in pending if t.variables <= bound]:
            steps.append((_TEST, test.holds))
            pending.remove(test)

    def rank(atom: Atom) -> tuple[int, int]:
        terms = atom[1]
        known = sum(1 for t in terms if not is_variable(t) or t in bound)
        free = len({t for t in terms if is_variable(t) and t not in bound})
        return (-known, free)

    while True:
        ready()
        todo = [a for a in todo if any(is_variable(t) and t not in bound for t in a[1])]
        if not todo:
            break
        atom = min(todo, key=rank)  # min keeps the first of equals: file order
        pred, terms = atom
        positions = tuple(i for i, t in enumerate(terms) if not is_variable(t) or t in bound)
        known = tuple(terms[i] for i in positions)
        free = tuple((i, t) for i, t in enumerate(terms) if i not in positions)
        steps.append((_MATCH, pred, positions, known, free))
        bound.update(t for _, t in free)
        pending = [t for t in pending if t.atom != atom]
    for var in variables:
        if var not in bound:
            steps.append((_EACH, var))
            bound.add(var)
            ready()
    return steps


def compile_binder(variables: dict[str, str], head: list[tuple[str, str]], tests: list[Test],
                   typed: dict[str, list[str]]) -> tuple[Binder, set[tuple[str, tuple[int, ...]]]]:
    """A binder for a method, and the index patterns it needs.

    ``variables`` maps the method's variables to their types; ``head`` pairs each
    term of the method's task (a variable or a constant) with the name of the task
    parameter it receives; ``tests`` are the conjuncts every binding must meet;
    ``typed`` gives the objects of each type (subtypes included), sorted by name.
    """
    members = {var: frozenset(typed.get(kind, ())) for var, kind in variables.items()}
    steps = plan_steps(variables, {t for t, _ in head if is_variable(t)}, tests)
    patterns = {(s[1], s[2]) for s in steps if s[0] == _MATCH}
    compiled: list[tuple] = []
    for step in steps:
        if step[0] == _MATCH:
            compiled.append((_MATCH, step[1], step[2], args_of(step[3]), step[4]))
        elif step[0] == _TEST:
            compiled.append(step)
        else:
            compiled.append((_EACH, step[1], typed.get(variables[step[1]], [])))
    extend = stepper(compiled, members)
    terms = [(term, param, is_variable(term)) for term, param in head]

    def unify(env: dict[str, Any]) -> dict[str, Any] | None:
        """The binding the task's arguments give, or None when they do not fit."""
        binding: dict[str, Any] = {}
        for term, param, variable in terms:
            value = env[param]
            if not variable:
                if value != term:
                    return None
            elif term in binding:
                if binding[term] != value:
                    return None
            elif value in members[term]:
                binding[term] = value
            else:
                return None
        return binding

    if all(step[0] == _TEST for step in compiled):  # the task binds everything: no search
        tests = tuple(step[1] for step in compiled)

        def check(env: dict[str, Any], state: FactState) -> tuple[dict[str, Any], ...]:
            binding = unify(env)
            if binding is None:
                return ()
            get = state.get
            for test in tests:
                if not test(binding, get):
                    return ()
            return (binding,)

        return check, patterns

    def bind(env: dict[str, Any], state: FactState) -> Iterator[dict[str, Any]]:
        binding = unify(env)
        if binding is not None:
            yield from extend(0, binding, state)

    return bind, patterns


def stepper(compiled: list[tuple], members: dict[str, frozenset[str]]
            ) -> Callable[[int, dict[str, Any], FactState], Iterator[dict]]:
    """The function giving every extension of a binding by the compiled steps from an
    index on (lookups keep only values of each variable's type, in ``members``).  A
    ``_DEFER`` step (:mod:`planner.search.late`) binds its variable to what its function makes:
    a placeholder the search binds later."""
    last = len(compiled)

    def extend(index: int, binding: dict[str, Any], state: FactState) -> Iterator[dict]:
        while index < last and compiled[index][0] == _TEST:
            if not compiled[index][1](binding, state.get):
                return
            index += 1
        if index == last:
            yield dict(binding)
            return
        step = compiled[index]
        if step[0] == _MATCH:
            _, pred, positions, known, free = step
            for args in state.matching(pred, positions, known(binding)):
                fresh = []
                for position, var in free:
                    value = args[position]
                    if var in binding:  # the variable occurs twice in this fact
                        if binding[var] != value:
                            break
                    elif value in members[var]:
                        binding[var] = value
                        fresh.append(var)
                    else:
                        break
                else:
                    yield from extend(index + 1, binding, state)
                for var in fresh:
                    del binding[var]
        elif step[0] == _EACH:
            var = step[1]
            for value in step[2]:
                binding[var] = value
                yield from extend(index + 1, binding, state)
            binding.pop(var, None)
        else:  # _DEFER
            var = step[1]
            binding[var] = step[2]()
            yield from extend(index + 1, binding, state)
            del binding[var]

    return extend


def args_of(terms: tuple[str, ...]) -> Callable[[dict[str, Any]], tuple[str, ...]]:
    """A function of the variables' values giving these terms' values (a fact's
    arguments)."""
    if all(is_variable(t) for t in terms):
        if len(terms) == 1:
            (a,) = terms
            return lambda b: (b[a],)
        if len(terms) == 2:
            a, c = terms
            return lambda b: (b[a], b[c])
        return lambda b: tuple([b[t] for t in terms])
    if not any(is_variable(t) for t in terms):
        return lambda b: terms
    flags = tuple((is_variable(t), t) for t in terms)
    return lambda b: tuple([b[t] if var else t for var, t in flags])
