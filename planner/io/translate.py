"""HDDL into the planner's own model, so that search, validator and rendering work on it.

:mod:`planner.io.hddl` reads and checks the files; this module compiles what it
read into a :class:`~planner.model.domain.Domain` and :class:`~planner.model.domain.Problem`:

* types become :class:`~planner.model.domain.EntityType` with their parent (the
  planner's type checks accept subtypes);
* a fact ``(on b1 b2)`` is the state key ``("on", ("b1", "b2"))`` mapped to
  True (deleted: None), so the search's copy-on-write states, the evaluator's
  causal links and the validator's replay need nothing new;
* preconditions, goals and effects become closures over ``(env, get)`` like the
  planner's own expressions (:class:`~planner.model.expr.Expr`,
  :class:`~planner.model.expr.Effect`), with PDDL's semantics (:mod:`planner.model.formulas`
  compiles them);
* a compound task becomes a :class:`~planner.model.domain.Method` whose parameters are
  the task's own (without the ``?``); each HDDL method is one of its
  decompositions, with the method's variables as its variables, a precondition
  that also checks that they match the task's arguments, and a binder
  (:mod:`planner.search.binding`) that proposes bindings from the state's facts;
* actions have no agent parameter: they are all the sole agent's
  (:data:`~planner.model.domain.SOLE_AGENT`); each costs 1.

A method's ``:constraints`` (``=``, ``not =``: conditions; ``sortof``: a
narrower type for a variable) are read by the reader and met like its
precondition.

An initial task network with ``:parameters`` becomes one task,
:data:`NETWORK`, whose one method has them as variables and the network as
subtasks (:func:`planner.io.ipc.write_ipc` leaves it out of the plans it writes).

Refused, by name and position, besides what the reader refuses: partial
order (:func:`planner.io.hddl.refuse_partial_order`) and goals other than a
conjunction of literals.
"""

from __future__ import annotations

import os
from typing import Any

from planner.io import hddl
from planner.model.domain import Action, Decomposition, Domain, EntityType, Method, Problem, Subtask
from planner.model.expr import Effect, Expr
from planner.model.formulas import Formulas, conjuncts, holds, is_literal, operand
from planner.model.statics import StaticFilter
from planner.search.binding import Atom, Test, args_of, compile_binder, is_variable
from planner.search.late import LateBinder
from userfiles.errors import FileError
from userfiles.errors import Problem as FileProblem

BUDGET_MS = 60_000
"""Default time budget of an HDDL problem (the files give none)."""
MAX_ENTRY = 32
"""The most entry conditions kept for one task (they are checked at every binding)."""
NETWORK = ":htn"
"""The task standing for an initial task network with ``:parameters``: its one method
binds them (no HDDL name starts with ':', so it cannot clash with the domain's)."""


def load_hddl(domain_path: str | os.PathLike[str],
              problem_path: str | os.PathLike[str]) -> Problem:
    """Read an HDDL domain and problem and translate them; ``FileError`` on any problem."""
    domain = hddl.read_domain(domain_path)
    problem = hddl.read_problem(problem_path, domain)
    return translate(domain, problem)


def translate(domain: hddl.HDDLDomain, problem: hddl.HDDLProblem) -> Problem:
    """The planner's problem (with its own domain) for a read HDDL domain and problem."""
    hddl.refuse_partial_order(domain, problem)
    _refuse(problem)
    return _Translator(domain, problem).problem()


def _refuse(problem: hddl.HDDLProblem) -> None:
    found = []
    for formula in conjuncts(problem.goal):
        if not is_literal(formula):
            found.append(FileProblem(problem.file, formula.line, formula.col,
                                     f"goal '{formula.kind}' is not supported: a goal is a "
                                     "conjunction of facts and negated facts"))
    if found:
        raise FileError(found)


class _Translator:
    def __init__(self, domain: hddl.HDDLDomain, problem: hddl.HDDLProblem):
        self.hdomain = domain
        self.hproblem = problem
        self.objects = hddl.all_objects(domain, problem)
        self.types = {name: EntityType(name, {}, {}, parent=parent)
                      for name, parent in domain.types.items()}
        self.typed: dict[str, list[str]] = {}
        for name in domain.types:
            kinds = set()
            for kind in domain.types:
                if name in hddl.supertypes(domain, kind):
                    kinds.add(kind)
            self.typed[name] = sorted(o for o, t in self.objects.items() if t in kinds)
        self.formulas = Formulas(self.typed)
        self.changed = {pred for action in domain.actions.values()
                        for adding in (True, False)
                        for pred, _ in _effect_atoms(action.effect, adding)}
        """The predicates some action's effect may change (the others are static)."""
        self._touched: dict[str, frozenset[tuple[str, tuple[str, ...]]]] | None = None
        self._entry: dict[str, list[hddl.Formula]] = {}

    def problem(self) -> Problem:
        hdomain, hproblem = self.hdomain, self.hproblem
        goals: dict[tuple[str, Any], Any] = {}
        for formula in conjuncts(hproblem.goal):
            positive = formula.kind == "pred"
            pred, terms = (formula if positive else formula.children[0]).children
            goals[(pred, terms)] = True if positive else None
        protected = {pred for (pred, _), value in goals.items() if value is True}
        actions = {name: self.action(a, protected) for name, a in hdomain.actions.items()}
        patterns: dict[str, set[tuple[int, ...]]] = {}
        methods = {}
        for task, params in hdomain.tasks.items():
            decompositions = []
            for method in hdomain.methods:
                if method.task.name == task:
                    dec, needed = self.decomposition(method, params, hdomain)
                    decompositions.append(dec)
                    for pred, positions in needed:
                        patterns.setdefault(pred, set()).add(positions)
            methods[task] = Method(task, tuple((p[1:], k) for p, k in params),
                                   tuple(decompositions))
        initial: dict[tuple[str, Any], Any] = {(f.pred, f.args): True for f in hproblem.init}
        tasks = tuple((s.name, s.args) for s in hproblem.htn_subtasks)
        if hproblem.htn_params:  # the search binds them: one task, one method
            line, col = hproblem.htn_line, hproblem.htn_col
            network = hddl.HMethod(NETWORK, hproblem.htn_params, hddl.Call(NETWORK, (), line, col),
                                   None, hproblem.htn_subtasks, True, line, col,
                                   constraints=hproblem.htn_constraints)
            dec, needed = self.decomposition(network, (), hdomain)
            for pred, positions in needed:
                patterns.setdefault(pred, set()).add(positions)
            methods[NETWORK] = Method(NETWORK, (), (dec,),
                                      "the initial task network, its parameters bound")
            tasks = ((NETWORK, ()),)
        domain = Domain(hdomain.name, self.types, actions, methods, {}, "", hdomain.file,
                        dict(hdomain.predicates),
                        {p: tuple(sorted(s)) for p, s in patterns.items()}, self.additions())
        return Problem(hproblem.name, domain, dict(self.objects), initial, tasks, goals,
                       budget_ms=BUDGET_MS, file=hproblem.file,
                       spelling={**hdomain.spelling, **hproblem.spelling},
                       lifted=(hdomain, hproblem))

    # -- actions and methods ---------------------------------------------------------

    def additions(self) -> dict[str, dict[str, tuple[Pattern, ...]]]:
        """What each task may add (``Domain.adds``): the actions' additions, lifted to
        the compound tasks through their methods' subtasks until nothing changes.

        A method whose task names a constant, or whose precondition fixes a task
        parameter to one (``(= ?crew pcrew1)``), adds only for that argument: its
        patterns keep it as a guard, so that ``cstring_wire`` adds Monroe's
        observation fact for ``pcrew1`` only, and so does every task above it that
        passes ``?crew`` down.  A guard on a method variable the task does not pass
        (``m_get_in_load_in``'s ``?person``) is dropped, after :class:`StaticFilter`
        says the variable may take that value: a pattern whose guards the method's
        types and static facts rule out is not lifted at all."""
        statics = StaticFilter(self.hdomain, self.objects, self.typed,
                               [(f.pred, f.args) for f in self.hproblem.init], self.changed)
        found: dict[str, set[tuple[str, Pattern]]] = {}
        for name, action in self.hdomain.actions.items():
            index = {p: i for i, (p, _) in enumerate(action.params)}
            found[name] = {(pred, (tuple(index.get(t) if is_variable(t) else t
                                         for t in terms), ()))
                           for pred, terms in _effect_atoms(action.effect, True)}
        heads = []
        for method in self.hdomain.methods:
            head: dict[str, int] = {}
            guards: set[tuple[int, str]] = set()
            for position, term in enumerate(method.task.args):
                if is_variable(term):
                    head.setdefault(term, position)
                else:
                    guards.add((position, term))
            fixed = _fixed(method)
            guards |= {(head[var], value) for var, value in fixed.items() if var in head}
            heads.append((method, head, fixed, tuple(sorted(guards))))
        changed = True
        while changed:
            changed = False
            for method, head, fixed, guards in heads:
                target = found.setdefault(method.task.name, set())
                for sub in method.subtasks:
                    for pred, pattern in list(found.get(sub.name, ())):
                        lifted = _lift_pattern(pattern, sub.args, head, fixed, guards,
                                               method, statics)
                        if lifted is not None and (pred, lifted) not in target:
                            target.add((pred, lifted))
                            changed = True
        out: dict[str, dict[str, tuple[Pattern, ...]]] = {}
        for task, atoms in found.items():
            by_pred: dict[str, list[Pattern]] = {}
            for pred, pattern in sorted(atoms, key=repr):
                by_pred.setdefault(pred, []).append(pattern)
            out[task] = {pred: tuple(patterns) for pred, patterns in by_pred.items()}
        return out

    def action(self, action: hddl.HAction, protected: set[str]) -> Action:
        pre = self.expr(action.precondition, action.params)
        effects: tuple[Effect, ...] = ()
        if action.effect is not None:
            apply = self.formulas.effect(action.effect)
            preds = {f.children[0] for f in action.effect.walk() if f.kind == "pred"}
            effects = (Effect(str(action.effect), apply, ",".join(sorted(preds)),
                              frozenset(p for p, _ in action.params), frozenset(preds)),)
        threats = tuple((f.children[0].children[0], args_of(f.children[0].children[1]))
                        for f in conjuncts(action.effect)
                        if f.kind == "not" and f.children[0].children[0] in protected)
        needs = tuple((f.children[0], args_of(f.children[1]))
                      for f in conjuncts(action.precondition) if f.kind == "pred")
        removes = tuple((f.children[0].children[0], args_of(f.children[0].children[1]))
                        for f in conjuncts(action.effect)
                        if f.kind == "not" and f.children[0].kind == "pred")
        late = LateBinder(dict(action.params), [(p, p) for p, _ in action.params],
                            [self.test(f) for f in conjuncts(action.precondition)],
                            self.typed, defer="never")
        return Action(action.name, action.params, None, pre, effects, 1.0, 1.0,
                      deletes=threats, needs=needs, removes=removes, late=late)

    def decomposition(self, method: hddl.HMethod, task_params: hddl.Params,
                      domain: hddl.HDDLDomain
                      ) -> tuple[Decomposition, set[tuple[str, tuple[int, ...]]]]:
        head = [(term, param[1:]) for term, (param, _) in zip(method.task.args, task_params,
                                                              strict=True)]
        whole = method.precondition
        if method.constraints is not None:  # '=' and 'not =' constraints are conditions too
            whole = (method.constraints if whole is None else
                     hddl.Formula("and", (whole, method.constraints), whole.line, whole.col))
        condition = self.formulas.condition(whole) if whole else None

        def matches(env: dict, get: Any) -> bool:
            for term, param in head:
                if env[param] != (env[term] if is_variable(term) else term):
                    return False
            return condition is None or condition(env, get)

        call = f"({method.task.name} {' '.join(method.task.args)})".replace(" )", ")")
        text = f"task {call}, {whole or '()'}"
        reads = {f.children[0] for f in whole.walk() if f.kind == "pred"} if whole else set()
        pre = Expr(text, matches, frozenset(dict(method.params)), frozenset(reads), "bool")
        conditions = list(conjuncts(whole))
        for position, sub in enumerate(method.subtasks):
            action = domain.actions.get(sub.name)
            if action is None:
                continue
            rename = {p: t for (p, _), t in zip(action.params, sub.args, strict=True)}
            conditions += [_rename(f, rename) for f in conjuncts(action.precondition)
                           if position == 0 or self.static(f)]
        conditions += self.hoisted(method)
        unique: dict[str, hddl.Formula] = {}
        for formula in conditions:  # each once, at its first place
            unique.setdefault(str(formula), formula)
        tests = [self.test(f) for f in unique.values()]
        bind, patterns = compile_binder(dict(method.params), head, tests, self.typed)
        late = LateBinder(dict(method.params), head, tests, self.typed,
                          defer="always" if method.name == NETWORK else "choice")
        subtasks = tuple(Subtask(s.name, tuple(operand(t) for t in s.args),
                                 f"({' '.join((s.name, *s.args))})", args_of(s.args))
                         for s in method.subtasks)
        return (Decomposition(method.name, method.params, pre, subtasks, bind=bind, late=late),
                patterns)

    # -- entry conditions ---------------------------------------------------------------

    def touched(self, task: str) -> frozenset[tuple[str, tuple[str, ...]]]:
        """The facts ``task`` may add or delete, through every method below it: each a
        predicate and the types of its arguments, as the actions declare them (a
        quantifier's variable counts as ``object``).  Transport's ``get_to ?v`` moves
        vehicles: it may change ``(at vehicle location)``, never a package's ``at``."""
        if self._touched is None:
            found: dict[str, set[tuple[str, tuple[str, ...]]]] = {}
            for name, action in self.hdomain.actions.items():
                kinds = dict(action.params)
                found[name] = {(pred, tuple(self.kind(t, kinds) for t in terms))
                               for adding in (True, False)
                               for pred, terms in _effect_atoms(action.effect, adding)}
            changed = True
            while changed:
                changed = False
                for method in self.hdomain.methods:
                    target = found.setdefault(method.task.name, set())
                    for sub in method.subtasks:
                        extra = found.get(sub.name, set()) - target
                        if extra:
                            target |= extra
                            changed = True
            self._touched = {name: frozenset(preds) for name, preds in found.items()}
        return self._touched.get(task, frozenset())

    def entry(self, task: str) -> list[hddl.Formula]:
        """Literals over ``task``'s parameters that hold wherever ``task`` starts: an
        action's precondition literals; for a compound task, those every one of its
        methods requires (:meth:`method_entry`), over the task's own parameters.  A
        recursion met while computing them counts as requiring nothing (fewer
        conditions: still sound)."""
        known = self._entry.get(task)
        if known is not None:
            return known
        self._entry[task] = []
        action = self.hdomain.actions.get(task)
        if action is not None:
            found = [f for f in conjuncts(action.precondition) if _plain(f)]
        else:
            params = [p for p, _ in self.hdomain.tasks.get(task, ())]
            common: dict[str, hddl.Formula] | None = None
            for method in self.hdomain.methods:
                if method.task.name != task:
                    continue
                rename = _head_renaming(method.task.args, params)
                mine: dict[str, hddl.Formula] = {}
                if rename is not None:
                    for formula in self.method_entry(method):
                        if _free(formula) <= set(rename):
                            renamed = _rename(formula, rename)
                            mine[str(renamed)] = renamed
                common = mine if common is None else {k: v for k, v in common.items()
                                                      if k in mine}
                if not common:
                    break
            found = list((common or {}).values())
        found = found[:MAX_ENTRY]
        self._entry[task] = found
        return found

    def kind(self, term: str, kinds: dict[str, str]) -> str:
        """The type of a term: a variable's declared type, a constant's own."""
        if is_variable(term):
            return kinds.get(term, "object")
        return self.objects.get(term, "object")

    def may_change(self, formula: hddl.Formula, kinds: dict[str, str],
                   touched: set[tuple[str, tuple[str, ...]]]) -> bool:
        """Whether a fact ``formula`` reads may be one of ``touched`` (a predicate and
        argument types that may overlap: one type is the other or below it)."""
        for part in formula.walk():
            if part.kind != "pred":
                continue
            pred, terms = part.children
            mine = [self.kind(t, kinds) for t in terms]
            for other, types in touched:
                if other == pred and all(self.overlap(a, b)
                                         for a, b in zip(mine, types, strict=True)):
                    return True
        return False

    def overlap(self, a: str, b: str) -> bool:
        """Whether an object may be of both types ``a`` and ``b``."""
        return (a == b or a in hddl.supertypes(self.hdomain, b)
                or b in hddl.supertypes(self.hdomain, a))

    def method_entry(self, method: hddl.HMethod) -> list[hddl.Formula]:
        """The literals over a method's variables that must hold where it is entered: its
        precondition's, and each subtask's entry conditions that none of the subtasks
        before it may change (:meth:`hoisted`)."""
        whole = [f for f in conjuncts(method.precondition) if _plain(f)]
        return whole + self.hoisted(method)

    def hoisted(self, method: hddl.HMethod) -> list[hddl.Formula]:
        """The subtasks' entry conditions (:meth:`entry`), seen from ``method``, that
        hold at its entry already: those whose predicates no earlier subtask may change.
        A binder that checks them refuses, at once, a binding that would fail only at
        the subtask (Freecell's ``M241`` binds a card that ``SENDTOFREE-B``, three
        bookkeeping tasks later, needs clear and at the bottom of a column)."""
        out: list[hddl.Formula] = []
        kinds = dict(method.params)
        changed: set[tuple[str, tuple[str, ...]]] = set()
        for sub in method.subtasks:
            params = (self.hdomain.actions[sub.name].params if sub.name in self.hdomain.actions
                      else self.hdomain.tasks.get(sub.name, ()))
            rename = {p: t for (p, _), t in zip(params, sub.args, strict=True)}
            for formula in self.entry(sub.name):
                renamed = _rename(formula, rename)
                if not self.may_change(renamed, kinds, changed):
                    out.append(renamed)
            changed |= self.touched(sub.name)
        return out

    def static(self, formula: hddl.Formula) -> bool:
        """Whether no action can change what ``formula`` says (it reads only facts that no
        effect adds or deletes, or only equalities): a later action's conjunct like that
        holds when the method is entered or never."""
        return not any(f.kind == "pred" and f.children[0] in self.changed
                       for f in formula.walk())

    def test(self, formula: hddl.Formula) -> Test:
        """A conjunct for a binder, over the method's variables."""
        variables = frozenset(_free(formula))
        if formula.kind == "pred":
            pred, terms = formula.children
            return Test(variables, holds(pred, terms), (pred, terms))
        return Test(variables, self.formulas.condition(formula))

    # -- conditions --------------------------------------------------------------------

    def expr(self, formula: hddl.Formula | None, params: hddl.Params) -> Expr | None:
        if formula is None:
            return None
        reads = {f.children[0] for f in formula.walk() if f.kind == "pred"}
        return Expr(str(formula), self.formulas.condition(formula), frozenset(p for p, _ in params),
                    frozenset(reads), "bool")


def _effect_atoms(formula: hddl.Formula | None, adding: bool) -> list[Atom]:
    """The facts an effect may add (or delete), conditional ones included."""
    if formula is None:
        return []
    kind, children = formula.kind, formula.children
    if kind == "pred":
        return [children] if adding else []
    if kind == "not":
        return [] if adding else [children[0].children]
    if kind == "and":
        return [atom for child in children for atom in _effect_atoms(child, adding)]
    return _effect_atoms(children[1], adding)  # when (condition, effect), forall (params, e)


Pattern = tuple[tuple[Any, ...], tuple[tuple[int, str], ...]]
"""A fact a task may add (``Domain.adds``): its arguments (a task parameter's index, a
constant or None) and the guards, ``(task parameter index, constant)``, that must hold."""


def _fixed(method: hddl.HMethod) -> dict[str, str]:
    """The method's variables that its precondition's top-level equalities fix to a
    constant."""
    whole = [*conjuncts(method.precondition), *conjuncts(method.constraints)]
    fixed: dict[str, str] = {}
    for formula in whole:
        if formula.kind != "=":
            continue
        a, b = formula.children
        if is_variable(a) and not is_variable(b):
            fixed[a] = b
        elif is_variable(b) and not is_variable(a):
            fixed[b] = a
    return fixed


def _lift_pattern(pattern: Pattern, args: tuple[str, ...], head: dict[str, int],
                  fixed: dict[str, str], guards: tuple[tuple[int, str], ...],
                  method: hddl.HMethod, statics: StaticFilter) -> Pattern | None:
    """A subtask's pattern seen from the method's task (None when the subtask's guards
    cannot hold in this method): an argument is the index of the task parameter it is,
    a constant, or None (a variable the task does not fix); a guard on a subtask
    argument the task does not fix is dropped (it may hold) once ``statics`` says
    that the method's variables may take the guards' values."""
    entries, inner = pattern
    lifted: set[tuple[int, str]] = set(guards)
    binding: dict[str, str] = {}
    for index, value in inner:
        term = args[index]
        if is_variable(term) and term not in fixed:
            if binding.setdefault(term, value) != value:
                return None
            if term in head:
                lifted.add((head[term], value))
            continue
        if fixed.get(term, term) != value:
            return None
    if binding and not statics.may_be(method, binding):
        return None
    return (tuple(lift_term(entry, args, head, fixed) for entry in entries),
            tuple(sorted(lifted)))


def lift_term(entry: Any, args: tuple[str, ...], head: dict[str, int],
              fixed: dict[str, str]) -> Any:
    """A subtask's lifted argument seen from the method's task: the index of the task
    parameter it is, a constant, or None (a variable the task does not fix)."""
    if entry.__class__ is not int:
        return entry
    term = args[entry]
    if not is_variable(term):
        return term
    return head[term] if term in head else fixed.get(term)


def _plain(formula: hddl.Formula) -> bool:
    """A fact, a negated fact or an (in)equality: a conjunct that can be renamed into
    another scope safely (a quantifier's own variables could be captured there)."""
    if formula.kind == "not":
        formula = formula.children[0]
    return formula.kind in ("pred", "=")


def _head_renaming(terms: tuple[str, ...], params: list[str]) -> dict[str, str] | None:
    """How a method's task terms become the task's own parameters (``?x`` of the method
    is the task's ``?a``), or None when a term is a constant or a variable repeated (the
    method then says more than the task: its conditions are not the task's)."""
    rename: dict[str, str] = {}
    for term, param in zip(terms, params, strict=True):
        if not is_variable(term) or term in rename:
            return None
        rename[term] = param
    return rename


def _free(formula: hddl.Formula) -> set[str]:
    """The variables a formula leaves to be bound (its quantifiers bind the others)."""
    kind, children = formula.kind, formula.children
    if kind == "pred":
        return {t for t in children[1] if is_variable(t)}
    if kind == "=":
        return {t for t in children if is_variable(t)}
    if kind in ("forall", "exists"):
        return _free(children[1]) - {v for v, _ in children[0]}
    return set().union(*(_free(c) for c in children))


def _rename(formula: hddl.Formula, rename: dict[str, str]) -> hddl.Formula:
    """``formula`` with its free variables replaced by the terms ``rename`` gives them (an
    action's precondition seen from the method that calls it); a quantifier's own
    variables are left alone."""
    kind, children = formula.kind, formula.children
    if kind == "pred":
        children = (children[0], tuple(rename.get(t, t) for t in children[1]))
    elif kind == "=":
        children = tuple(rename.get(t, t) for t in children)
    elif kind in ("forall", "exists"):
        params, body = children
        inner = {v: t for v, t in rename.items() if v not in dict(params)}
        children = (params, _rename(body, inner))
    else:
        children = tuple(_rename(c, rename) for c in children)
    return hddl.Formula(kind, children, formula.line, formula.col)
