"""Late binding: a variable is bound when the first task that needs it comes to the front.

A method's binder (:mod:`planner.search.binding`) binds the variables its facts
constrain and tries *every object of its type* for the others.  Woodworking's
``process`` methods have up to a dozen such variables (the machine, board,
wood, colours and surfaces of subtasks further on): some 4,800 bindings a
decomposition, all alike until the subtask that uses the variable shows which
value works.  The goal-guided search (:mod:`planner.search.progression`) leaves them
unbound instead:

* a method variable that no condition of the binder reads is bound to an
  :class:`Unbound` placeholder, which the subtasks carry down;
* when a task whose arguments hold placeholders comes to the front of the task
  stack, the binder of each of its methods (or, for an action, of its
  precondition) treats them as free variables of the task's head: it binds them
  from the facts that constrain them, or leaves them unbound again (narrowed to
  the objects both types allow), and the values it chose replace the
  placeholders throughout the stack (:func:`substitute`);
* a placeholder still unbound when the plan is complete takes the first object
  it may be (no condition reads it: any does).

The initial task network's parameters (``:htn :parameters``) are placeholders
from the start, so they are bound the same way.  A placeholder equals anything
(``==`` is true, ``!=`` false): goal protection (``Domain.may_add``) then counts
a task that names one as a task that may add any fact of its kind, which keeps
it an over-approximation.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from functools import partial
from typing import Any

from planner.model.domain import Domain
from planner.model.state import FactState
from planner.search.binding import (
    _DEFER,
    _EACH,
    _MATCH,
    _TEST,
    Test,
    args_of,
    is_variable,
    plan_steps,
    stepper,
)

MOST_LATE = 8
"""The most head variables that may come unbound whose every subset's lookups are worked
out (:meth:`LateBinder.patterns`)."""

_serial = itertools.count(1)


class Unbound:
    """A variable not bound yet, with the objects it may still be (sorted by name)."""

    __slots__ = ("name", "objects", "members")

    def __init__(self, name: str, objects: tuple[str, ...]):
        self.name = name
        self.objects = objects
        self.members = frozenset(objects)

    def __eq__(self, other: object) -> bool:
        return True

    def __ne__(self, other: object) -> bool:
        return False

    def __hash__(self) -> int:
        return hash(("?", self.name))

    def __str__(self) -> str:
        return self.name

    def __repr__(self) -> str:
        return f"Unbound({self.name!r})"


def fresh(var: str, objects: tuple[str, ...]) -> Unbound:
    """A new placeholder for ``var`` (its name unique, so that two nodes whose stacks hold
    different placeholders are never taken for the same node)."""
    return Unbound(f"{var}#{next(_serial)}", objects)


def has_unbound(args: tuple) -> bool:
    return any(a.__class__ is Unbound for a in args)


def same(a: tuple, b: tuple) -> bool:
    """Whether two argument tuples that ``==`` found equal are the same arguments: a
    placeholder equals anything, so it is the same only as itself."""
    if not (has_unbound(a) or has_unbound(b)):
        return True
    return all(x is y or (x.__class__ is not Unbound and y.__class__ is not Unbound)
               for x, y in zip(a, b, strict=True))


def substitute(agenda: Any, subst: dict[str, Any]) -> Any:
    """The task stack with each placeholder named in ``subst`` replaced by its value
    (entries are ``(task, args, path, hash, rest)``; the hashes are made again)."""
    if not subst:
        return agenda
    entries = []
    while agenda is not None:
        entries.append(agenda)
        agenda = agenda[4]
    rebuilt = None
    for name, args, path, _, _ in reversed(entries):
        if has_unbound(args):
            args = tuple([subst.get(a.name, a) if a.__class__ is Unbound else a
                          for a in args])
        rebuilt = (name, args, path, hash((name, args, rebuilt[3] if rebuilt else 0)),
                   rebuilt)
    return rebuilt


def resolve(value: Any, subst: dict[str, Any]) -> Any:
    """``value`` after the substitutions ``subst`` (followed to their end)."""
    while value.__class__ is Unbound and value.name in subst:
        value = subst[value.name]
    return value


class LateBinder:
    """The late binder of a method or of an action's precondition.

    ``defer`` says whether it leaves unbound the variables its own conditions do not
    read: ``"never"`` (an action: every argument bound), ``"always"`` (the initial task
    network) or ``"choice"`` (a method: as the search asks, :meth:`__call__`).

    Built from what :func:`planner.search.binding.compile_binder` is given.  The order of the
    lookups depends on which head variables the task's arguments bind, so one plan is
    compiled for each set of them met; :meth:`patterns` says which fact indexes those
    plans may look up, for the states of the search that uses it."""

    def __init__(self, variables: dict[str, str], head: list[tuple[str, str]],
                 tests: list[Test], typed: dict[str, list[str]], *, defer: str):
        self.variables = variables
        self.head = head
        self.tests = tests
        self.typed = typed
        self.defer = defer
        self.members = {var: frozenset(typed.get(kind, ())) for var, kind in variables.items()}
        self.tested = frozenset(var for test in tests for var in test.variables)
        """The variables some condition reads: the binder binds them."""
        self.terms = [(term, param, is_variable(term)) for term, param in head]
        self.plans: dict[tuple[frozenset[str], bool], Any] = {}
        """The compiled plan (:func:`planner.search.binding.stepper`) for each set of head
        variables bound and choice of deferring."""

    def late_terms(self, params: list[str], positions: set[int]) -> set[str]:
        """The head variables that receive the task's parameters at ``positions``."""
        chosen = {params[i] for i in positions}
        return {term for term, param, variable in self.terms if variable and param in chosen}

    def leaves_unbound(self, late: set[str]) -> set[str]:
        """The variables a binding may leave unbound, when the head variables ``late``
        may come unbound (its subtasks may receive these as placeholders)."""
        if self.defer == "never":
            return set()
        head = {term for term, _, variable in self.terms if variable}
        return {var for var in self.variables
                if var not in self.tested and (var not in head or var in late)}

    def patterns(self, late: set[str]) -> set[tuple[str, tuple[int, ...]]]:
        """The fact indexes the plans may look up, when the head variables ``late`` may
        come unbound (for every subset of them; beyond :data:`MOST_LATE` of them, every
        pattern of the predicates read)."""
        head = {term for term, _, variable in self.terms if variable}
        fixed = head - late
        late_head = sorted(late & head)
        found: set[tuple[str, tuple[int, ...]]] = set()
        if len(late_head) > MOST_LATE:
            for test in self.tests:
                if test.atom is not None:
                    arity = len(test.atom[1])
                    found |= {(test.atom[0], pattern) for size in range(arity + 1)
                              for pattern in itertools.combinations(range(arity), size)}
            return found
        for size in range(len(late_head) + 1):
            for unbound in itertools.combinations(late_head, size):
                bound = fixed | (set(late_head) - set(unbound))
                found |= {(s[1], s[2]) for s in plan_steps(self.variables, bound, self.tests)
                          if s[0] == _MATCH}
        return found

    @property
    def may_defer(self) -> bool:
        """Whether a choice to leave variables unbound changes what this binder does."""
        return self.defer == "choice" and bool(self.leaves_unbound(set()))

    def _defers(self, choice: bool) -> bool:
        return self.defer == "always" or (self.defer == "choice" and choice)

    def _plan(self, bound: frozenset[str], defers: bool) -> Any:
        compiled: list[tuple] = []
        for step in plan_steps(self.variables, set(bound), self.tests):
            if step[0] == _MATCH:
                compiled.append((_MATCH, step[1], step[2], args_of(step[3]), step[4]))
            elif step[0] == _TEST:
                compiled.append(step)
            else:
                var = step[1]
                objects = tuple(self.typed.get(self.variables[var], ()))
                if defers and var not in self.tested and objects:
                    compiled.append((_DEFER, var, partial(fresh, var, objects)))
                else:
                    compiled.append((_EACH, var, objects))
        extend = self.plans[(bound, defers)] = stepper(compiled, self.members)
        return extend

    def __call__(self, env: dict[str, Any], state: FactState, defer: bool = True
                 ) -> Iterator[tuple[dict[str, Any], dict[str, Any]]]:
        """For each binding, the binding (placeholders for what it leaves unbound) and the
        substitution of the placeholders among ``env``'s values that it bound (their names
        to their values: objects or narrower placeholders); ``defer``: whether a method's
        variables that its own conditions do not read are left unbound."""
        binding: dict[str, Any] = {}
        late: dict[str, list[Unbound]] = {}
        given: dict[str, Any] = {}
        members = self.members
        for term, param, variable in self.terms:
            value = env[param]
            if value.__class__ is Unbound:
                if variable:
                    late.setdefault(term, []).append(value)
                elif term not in value.members:
                    return
                else:
                    given[value.name] = term
            elif not variable:
                if value != term:
                    return
            elif term in binding:
                if binding[term] != value:
                    return
            elif value in members[term]:
                binding[term] = value
            else:
                return
        for term in [t for t in late if t in binding]:  # bound by another argument
            value = binding[term]
            for placeholder in late.pop(term):
                if value not in placeholder.members:
                    return
                given[placeholder.name] = value
        key = frozenset(binding)
        defers = self._defers(defer)
        extend = self.plans.get((key, defers)) or self._plan(key, defers)
        for found in extend(0, binding, state):
            subst = dict(given)
            for term, placeholders in late.items():
                value = found[term]
                if value.__class__ is Unbound:  # left unbound here too: narrowed
                    objects = tuple(o for o in value.objects
                                    if all(o in p.members for p in placeholders))
                    if not objects:
                        break
                    if len(placeholders) == 1 and objects == placeholders[0].objects:
                        found[term] = placeholders[0]
                        continue
                    value = found[term] = fresh(term, objects)
                elif not all(value in p.members for p in placeholders):
                    break
                for placeholder in placeholders:
                    subst[placeholder.name] = value
            else:
                yield found, subst


def search_patterns(domain: Domain, tasks: tuple[tuple[str, tuple], ...]
                    ) -> dict[str, tuple[tuple[int, ...], ...]]:
    """The fact indexes a search with late binding needs: the domain's (its binders'),
    and those the late binders may look up, given where placeholders may come.

    A placeholder comes to a subtask's argument from a variable its method may leave
    unbound (:meth:`LateBinder.leaves_unbound`), which depends on the placeholders the
    method's own task may receive: a fixpoint over the task names, from the problem's
    ``tasks`` (whose arguments are objects)."""
    maybe: dict[str, set[int]] = {name: set() for name in (*domain.methods, *domain.actions)}
    changed = True
    while changed:
        changed = False
        for name, method in domain.methods.items():
            params = [p for p, _ in method.params]
            for dec in method.decompositions:
                late = dec.late
                if late is None:
                    continue
                unbound = late.leaves_unbound(late.late_terms(params, maybe[name]))
                for sub in dec.subtasks:
                    for position, arg in enumerate(sub.args):
                        if arg.text in unbound and position not in maybe[sub.task]:
                            maybe[sub.task].add(position)
                            changed = True
    found: dict[str, set[tuple[int, ...]]] = {p: set(s) for p, s in domain.patterns.items()}
    binders = [(late, [p for p, _ in method.params], maybe[name])
               for name, method in domain.methods.items()
               for late in (dec.late for dec in method.decompositions)]
    binders += [(action.late, list(action.names), maybe[name])
                for name, action in domain.actions.items()]
    for late, params, positions in binders:
        if late is not None:
            for pred, pattern in late.patterns(late.late_terms(params, positions)):
                found.setdefault(pred, set()).add(pattern)
    return {pred: tuple(sorted(s)) for pred, s in found.items()}
