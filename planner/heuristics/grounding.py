"""The grounded model of an HDDL problem: what a relaxed analysis of it can reach.

The searches work on the lifted model: a method's variables are bound when the
search meets it, in one state.  A heuristic that looks *through* the hierarchy
(:mod:`planner.heuristics.relaxed`) needs the other view, the one PANDA's and Lilotane's
grounders build before they search: every ground action, method and task that
could ever take part in a plan.  Three passes:

1. **Relaxed reachability of facts** (the delete relaxation, negative
   preconditions ignored): every action whose positive precondition facts are
   reachable, from the initial state, until nothing new is added.
2. **Top-down grounding of tasks**: from the initial task network, each task's
   methods, their variables bound by the task's arguments, then by the
   reachable facts of their precondition and the ground actions among their
   subtasks (AssemblyHierarchical's ``c1 ?p1 ?p2 ?t`` finds ``?t`` through
   ``connect_1``'s precondition, as the search's binders do), any variable left
   by the objects of its type.
3. **Bottom-up pruning**: a task is kept when one of its methods has only kept
   subtasks (or it is a reachable action), and then only what the initial
   network still reaches through kept methods.

Every pass over-approximates (deletes, negations, disjunctions and quantified
conditions are ignored), so a ground task left out can be part of no plan: the
heuristic may call a task stack naming one a dead end.  The model is given up
(:func:`ground` returns None) when it would exceed :data:`LIMIT` ground actions
and methods, and for problems whose initial task network has parameters (the
best-first search binds those late, so its stacks name no ground task).
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass

from planner.io import hddl
from planner.model.formulas import conjuncts

LIMIT = 150_000
"""Ground actions plus ground methods (and the bindings tried for them) beyond which the
model is given up: grounding is in pure Python, and a heuristic that costs seconds before
the first node serves no problem of a 30 s budget."""
TIME_LIMIT_S = 3.0
"""Seconds of grounding beyond which the model is given up, for the same reason."""

Fact = tuple[str, tuple[str, ...]]
Atom = tuple[str, tuple[str, ...]]
"""A predicate (or ``@action``: a ground action, for matching subtasks) and its terms,
variables (``?x``) or constants."""


class TooLarge(Exception):
    """The grounding went beyond :data:`LIMIT` or :data:`TIME_LIMIT_S`."""


@dataclass
class Grounded:
    """The ground model: facts, actions (each a primitive task too), compound tasks and
    methods, each numbered; ``tasks`` gives the id of every ground task, primitive or
    compound, and ``primitive`` the action of each primitive task's id."""

    facts: dict[Fact, int]
    actions: list[Fact]
    action_pre: list[tuple[int, ...]]
    action_add: list[tuple[int, ...]]
    tasks: dict[Fact, int]
    primitive: dict[int, int]
    methods: list[tuple[int, tuple[int, ...], tuple[int, ...]]]
    """Each method as its task's id, its precondition's facts, its subtasks' task ids."""
    bindings: dict[Fact, dict[str, list[dict[str, str]]]]
    """For each ground compound task, by the name of each of its methods that leaves a
    variable to its type (:func:`enumerating`), the bindings of the method's variables
    (``?x``) that the model keeps, in the order they were found."""


def is_variable(term: str) -> bool:
    return term.startswith("?")


Reached = dict[str, list[tuple[tuple[str, ...], list[Fact], list[Fact]]]]
"""The relaxed-reachable ground actions, by name: arguments, precondition facts, added
facts (:meth:`_Grounder.reachable`)."""


def ground(domain: hddl.HDDLDomain, problem: hddl.HDDLProblem,
           reached: list[Reached] | None = None) -> Grounded | None:
    """The ground model of ``problem`` (see the module's docstring), or None when it is
    too large or the initial task network has parameters; ``reached``, when given, gets
    the first pass's actions once that pass is over, for the estimate that needs only
    them (:mod:`planner.heuristics.subgoals`) when the model is given up (Freecell: 1-5 s saved)."""
    if problem.htn_params:
        return None
    grounder = _Grounder(domain, problem)
    grounder.reached = reached
    try:
        return grounder.run()
    except TooLarge:
        return None


class _Index:
    """Ground atoms, indexed by predicate and by (predicate, position, value)."""

    def __init__(self) -> None:
        self.present: set[Fact] = set()
        self.by_pred: dict[str, list[tuple[str, ...]]] = {}
        self.by_pos: dict[tuple[str, int, str], list[tuple[str, ...]]] = {}

    def add(self, pred: str, args: tuple[str, ...]) -> bool:
        if (pred, args) in self.present:
            return False
        self.present.add((pred, args))
        self.by_pred.setdefault(pred, []).append(args)
        for position, value in enumerate(args):
            self.by_pos.setdefault((pred, position, value), []).append(args)
        return True

    def matching(self, pred: str, known: list[tuple[int, str]]) -> list[tuple[str, ...]]:
        """The atoms of ``pred`` with these values at these positions (a snapshot)."""
        if not known:
            return list(self.by_pred.get(pred, ()))
        lists = [self.by_pos.get((pred, p, v), ()) for p, v in known]
        shortest = min(lists, key=len)
        if len(known) == 1:
            return list(shortest)
        return [args for args in shortest if all(args[p] == v for p, v in known)]


def reachable_actions(domain: hddl.HDDLDomain, problem: hddl.HDDLProblem, limit: int,
                      seconds: float) -> Reached | None:
    """The first pass alone (:meth:`_Grounder.reachable`: every relaxed-reachable ground
    action, by name, with its precondition's and its effect's facts), or None beyond
    ``limit`` ground actions (and bindings tried) or ``seconds``: the actions of problems
    whose methods are too many to ground (:mod:`planner.heuristics.subgoals`)."""
    try:
        return _Grounder(domain, problem, limit, seconds).reachable()
    except TooLarge:
        return None


class _Grounder:
    def __init__(self, domain: hddl.HDDLDomain, problem: hddl.HDDLProblem,
                 limit: int | None = None, seconds: float | None = None):
        self.domain, self.problem = domain, problem
        objects = hddl.all_objects(domain, problem)
        self.of_type: dict[str, list[str]] = {kind: [] for kind in domain.types}
        for name, kind in sorted(objects.items()):
            for parent in hddl.supertypes(domain, kind):
                self.of_type.setdefault(parent, []).append(name)
        self.type_sets = {kind: set(names) for kind, names in self.of_type.items()}
        self.index = _Index()
        self.by_task: dict[str, list[hddl.HMethod]] = {}
        for method in domain.methods:
            self.by_task.setdefault(method.task.name, []).append(method)
        self.candidates: dict[str, bool] = {}
        """For each compound task asked, whether its possible arguments are known."""
        self.reached: list[Reached] | None = None
        """Where :meth:`run` puts the first pass's actions, when asked (:func:`ground`)."""
        self.work = 0
        self.limit = LIMIT if limit is None else limit
        self.deadline = time.perf_counter() + (TIME_LIMIT_S if seconds is None else seconds)

    def _count(self, n: int = 1) -> None:
        self.work += n
        if self.work > self.limit or (self.work % 1024 == 0
                                      and time.perf_counter() > self.deadline):
            raise TooLarge

    # -- bindings ----------------------------------------------------------------------

    def bindings(self, atoms: list[Atom], env: dict[str, str], kinds: dict[str, str],
                 tests: list[tuple[bool, str, str]]) -> Iterator[dict[str, str]]:
        """Every binding of ``kinds``' variables that extends ``env``, makes ``atoms``
        present in the index and meets the (in)equality ``tests``."""
        if atoms:
            def bound(atom: Atom) -> int:
                return sum(1 for t in atom[1] if not is_variable(t) or t in env)
            best = max(range(len(atoms)), key=lambda i: bound(atoms[i]))
            pred, terms = atoms[best]
            rest = atoms[:best] + atoms[best + 1:]
            known = [(i, env.get(t, t) if is_variable(t) else t) for i, t in enumerate(terms)
                     if not is_variable(t) or t in env]
            for args in self.index.matching(pred, known):
                self._count()
                new = dict(env)
                for term, value in zip(terms, args, strict=True):
                    if not is_variable(term) or term in new:
                        if new.get(term, term) != value:
                            break
                        continue
                    if term in kinds and value not in self.type_sets.get(kinds[term], ()):
                        break
                    new[term] = value
                else:
                    yield from self.bindings(rest, new, kinds, tests)
            return
        free = [var for var in kinds if var not in env]
        if free:
            var = free[0]
            for value in self.of_type.get(kinds[var], ()):
                self._count()
                yield from self.bindings([], {**env, var: value}, kinds, tests)
            return
        for equal, a, b in tests:
            if (env.get(a, a) == env.get(b, b)) != equal:
                return
        yield env

    # -- 1. relaxed reachability --------------------------------------------------------

    def reachable(self) -> dict[str, list[tuple[tuple[str, ...], list[Fact], list[Fact]]]]:
        """Every relaxed-reachable ground action, by name: its arguments, the facts its
        precondition needs and the facts it adds."""
        for fact in self.problem.init:
            self.index.add(fact.pred, fact.args)
        compiled = {name: (_positives(a.precondition), _tests(a.precondition),
                           added_atoms(a.effect), dict(a.params))
                    for name, a in self.domain.actions.items()}
        found: dict[str, dict[tuple[str, ...], tuple[list[Fact], list[Fact]]]] = {
            name: {} for name in compiled}
        changed = True
        while changed:
            changed = False
            for name, (atoms, tests, adds, kinds) in compiled.items():
                action = self.domain.actions[name]
                mine = found[name]
                for env in list(self.bindings(atoms, {}, kinds, tests)):
                    args = tuple(env[p] for p, _ in action.params)
                    if args in mine:
                        continue
                    self._count()
                    added = [fact for pred, terms, extra in adds
                             for fact in self._instances(pred, terms, extra, env)]
                    mine[args] = ([_apply(pred, terms, env) for pred, terms in atoms], added)
                    for pred, fact_args in added:
                        changed |= self.index.add(pred, fact_args)
        for name, mine in found.items():
            for args in mine:
                self.index.add("@" + name, args)
        return {name: [(args, pre, add) for args, (pre, add) in mine.items()]
                for name, mine in found.items()}

    def _instances(self, pred: str, terms: tuple[str, ...], extra: dict[str, str],
                   env: dict[str, str]) -> Iterator[Fact]:
        """An added atom's ground facts: a ``forall``'s variables take every object."""
        for full in self.bindings([], env, extra, []):
            yield _apply(pred, terms, full)

    # -- 2. top-down grounding ------------------------------------------------------------

    def run(self) -> Grounded:
        actions = self.reachable()
        if self.reached is not None:
            self.reached.append(actions)
        by_task = self.by_task
        ground_actions = {(name, args): (pre, add)
                          for name, rows in actions.items() for args, pre, add in rows}
        methods: list[tuple[Fact, list[Fact], list[Fact]]] = []
        named: list[tuple[str, dict[str, str]]] = []
        initial = [(s.name, tuple(s.args)) for s in self.problem.htn_subtasks]
        seen: set[Fact] = set(initial)
        queue = deque(t for t in initial if t[0] not in self.domain.actions)
        compiled = {m.name: self._method(m) for m in self.domain.methods}
        while queue:
            name, args = queue.popleft()
            for method in by_task.get(name, ()):
                atoms, tests, kinds = compiled[method.name]
                env = _unify(method.task.args, args)
                if env is None:
                    continue
                for full in self.bindings(atoms, env, kinds, tests):
                    self._count()
                    subtasks = [(s.name, tuple(full.get(t, t) for t in s.args))
                                for s in method.subtasks]
                    named.append((method.name, {v: full[v] for v, _ in method.params}))
                    methods.append(((name, args),
                                    [_apply(p, t, full) for p, t in atoms if p[0] not in "@#"],
                                    subtasks))
                    for sub in subtasks:
                        if sub not in seen:
                            seen.add(sub)
                            if sub[0] not in self.domain.actions:
                                queue.append(sub)
        return _prune(initial, methods, named, ground_actions, enumerating(self.domain),
                      self.by_task)

    def _base(self, method: hddl.HMethod) -> tuple[list[Atom], list[tuple[bool, str, str]],
                                                   dict[str, str]]:
        """A method's atoms to match: its precondition's positive facts, and its action
        subtasks as ``@action`` atoms (matched with the reachable ground actions)."""
        atoms = _positives(method.precondition)
        atoms += [("@" + s.name, tuple(s.args)) for s in method.subtasks
                  if s.name in self.domain.actions]
        tests = _tests(method.precondition) + _tests(method.constraints)
        return atoms, tests, dict(method.params)

    def _method(self, method: hddl.HMethod) -> tuple[list[Atom], list[tuple[bool, str, str]],
                                                     dict[str, str]]:
        """:meth:`_base`, and a ``#task`` atom for each compound subtask with a variable
        that neither the method's task nor those atoms bind, when the subtask's possible
        arguments are known (:meth:`_candidates`): AssemblyHierarchical's ``m1`` binds
        ``connect ?p1 ?p2`` to the pairs of ports some ``connect_k`` may join, not to
        every pair of ports."""
        atoms, tests, kinds = self._base(method)
        covered = {t for t in method.task.args if is_variable(t)}
        covered |= {t for _, terms in atoms for t in terms if is_variable(t)}
        extra = [("#" + sub.name, tuple(sub.args)) for sub in method.subtasks
                 if sub.name not in self.domain.actions
                 and any(is_variable(t) and t not in covered for t in sub.args)
                 and self._candidates(sub.name)]
        return atoms + extra, tests, kinds

    def _candidates(self, task: str) -> bool:
        """Whether the arguments ``task`` can have are known, as ``#task`` atoms of the
        index: those of its methods' bindings through their own atoms alone (an
        over-approximation of the ground tasks some method ends).  Not known when a
        method leaves an argument to a compound subtask or to its type."""
        known = self.candidates.get(task)
        if known is not None:
            return known
        self.candidates[task] = False  # a recursion through the task knows nothing
        rows: set[tuple[str, ...]] = set()
        for method in self.by_task.get(task, ()):
            atoms, tests, kinds = self._base(method)
            covered = {t for _, terms in atoms for t in terms if is_variable(t)}
            if any(is_variable(t) and t not in covered for t in method.task.args):
                return False
            mine = [(equal, a, b) for equal, a, b in tests
                    if all(not is_variable(x) or x in covered for x in (a, b))]
            for env in self.bindings(atoms, {}, {v: k for v, k in kinds.items()
                                                 if v in covered}, mine):
                rows.add(tuple(env.get(t, t) if is_variable(t) else t
                               for t in method.task.args))
        for args in rows:
            self.index.add("#" + task, args)
        self.candidates[task] = True
        return True


def enumerating(domain: hddl.HDDLDomain) -> set[str]:
    """The methods with a variable that neither their task, nor their precondition's
    facts, nor their first subtask (when it is an action, whose precondition the
    search's binders look up) bind: the binders try every object of its type for it,
    where the ground model knows the few that can serve (AssemblyHierarchical's ``m1``,
    whose ``?p1 ?p2`` only the compound ``connect`` constrains)."""
    out = set()
    for method in domain.methods:
        bound = {t for t in method.task.args if is_variable(t)}
        bound |= {t for _, terms in _positives(method.precondition) for t in terms}
        if method.subtasks and method.subtasks[0].name in domain.actions:
            bound |= set(method.subtasks[0].args)
        if any(var not in bound for var, _ in method.params):
            out.add(method.name)
    return out


def _unify(pattern: tuple[str, ...], args: tuple[str, ...]) -> dict[str, str] | None:
    env: dict[str, str] = {}
    for term, value in zip(pattern, args, strict=True):
        if is_variable(term):
            if env.setdefault(term, value) != value:
                return None
        elif term != value:
            return None
    return env


def _apply(pred: str, terms: tuple[str, ...], env: dict[str, str]) -> Fact:
    return pred, tuple(env.get(t, t) if is_variable(t) else t for t in terms)


def _positives(formula: hddl.Formula | None) -> list[Atom]:
    """The positive facts of a condition's top-level conjunction (the rest is relaxed)."""
    return [(f.children[0], tuple(f.children[1])) for f in conjuncts(formula)
            if f.kind == "pred"]


def _tests(formula: hddl.Formula | None) -> list[tuple[bool, str, str]]:
    """The (in)equalities of a condition's top-level conjunction: (equal?, a, b)."""
    out = []
    for f in conjuncts(formula):
        if f.kind == "=":
            out.append((True, f.children[0], f.children[1]))
        elif f.kind == "not" and f.children[0].kind == "=":
            out.append((False, f.children[0].children[0], f.children[0].children[1]))
    return out


def added_atoms(formula: hddl.Formula | None, extra: dict[str, str] | None = None
                ) -> list[tuple[str, tuple[str, ...], dict[str, str]]]:
    """The atoms an effect may add, conditional ones included, with the variables of the
    ``forall`` they are under."""
    if formula is None:
        return []
    extra = extra or {}
    kind, children = formula.kind, formula.children
    if kind == "pred":
        return [(children[0], tuple(children[1]), extra)]
    if kind == "and":
        return [atom for child in children for atom in added_atoms(child, extra)]
    if kind == "when":
        return added_atoms(children[1], extra)
    if kind == "forall":
        return added_atoms(children[1], {**extra, **dict(children[0])})
    return []


def _prune(initial: list[Fact], methods: list[tuple[Fact, list[Fact], list[Fact]]],
           named: list[tuple[str, dict[str, str]]],
           actions: dict[Fact, tuple[list[Fact], list[Fact]]], free: set[str],
           methods_of: dict[str, list[hddl.HMethod]]) -> Grounded:
    """Keep the tasks some decomposition ends (bottom up), then those the initial network
    reaches through kept methods (top down), and number what is left."""
    done = {task for task in actions}
    users: dict[Fact, list[int]] = {}
    missing = []
    for i, (_, _, subtasks) in enumerate(methods):
        needed = {s for s in subtasks if s not in done}
        missing.append(len(needed))
        for sub in needed:
            users.setdefault(sub, []).append(i)
    todo = [i for i, n in enumerate(missing) if n == 0]
    while todo:
        task = methods[todo.pop()][0]
        if task in done:
            continue
        done.add(task)
        for i in users.get(task, ()):
            missing[i] -= 1
            if missing[i] == 0:
                todo.append(i)
    by_task: dict[Fact, list[int]] = {}
    for i, (task, _, _) in enumerate(methods):
        if missing[i] == 0:
            by_task.setdefault(task, []).append(i)
    reached: set[Fact] = set()
    queue = [t for t in initial if t in done]
    kept: list[int] = []
    while queue:
        task = queue.pop()
        if task in reached:
            continue
        reached.add(task)
        for i in by_task.get(task, ()):
            kept.append(i)
            queue.extend(s for s in methods[i][2] if s not in reached)
    facts: dict[Fact, int] = {}
    tasks: dict[Fact, int] = {}
    out_actions: list[Fact] = []
    action_pre: list[tuple[int, ...]] = []
    action_add: list[tuple[int, ...]] = []
    primitive: dict[int, int] = {}

    def fact_id(fact: Fact) -> int:
        return facts.setdefault(fact, len(facts))

    for task in sorted(reached, key=repr):
        tasks[task] = len(tasks)
        if task in actions:
            pre, add = actions[task]
            primitive[tasks[task]] = len(out_actions)
            out_actions.append(task)
            action_pre.append(tuple(dict.fromkeys(fact_id(f) for f in pre)))
            action_add.append(tuple(dict.fromkeys(fact_id(f) for f in add)))
    ground_methods = [(tasks[task], tuple(dict.fromkeys(fact_id(f) for f in pre)),
                       tuple(tasks[s] for s in subtasks))
                      for task, pre, subtasks in (methods[i] for i in sorted(kept))]
    bindings: dict[Fact, dict[str, list[dict[str, str]]]] = {
        task: {m.name: [] for m in methods_of.get(task[0], ()) if m.name in free}
        for task in tasks if task not in actions}
    for i in sorted(kept):
        name, env = named[i]
        if name in free:
            bindings[methods[i][0]][name].append(env)
    return Grounded(facts, out_actions, action_pre, action_add, tasks, primitive,
                    ground_methods, bindings)
