"""Goal facts with no support left: a relaxed regression through the task stack's actions.

The goal-guided search (:mod:`planner.search.progression`) drops a node whose state has
a goal fact false that no task left may add (:mod:`planner.heuristics.reach`).  "May add"
is lifted and ignores the state: in Woodworking, ``method16`` of ``process``
colours *any* part (its ``do_colour`` takes a part of its own), so every
``process`` left may add any part's colour and treatment, and a part already
glazed when it should have been varnished is never seen as lost until the last
task: the search chooses machines and colours for every other part first, then
backtracks over all of them.  Yet varnishing needs the part ``untreated``, and
once it is glazed only its own ``process`` could make it so again.

This check looks one step further, still as a relaxation (deletions, negative
preconditions and the order of the tasks ignored), so a node it drops is
certainly a dead end.  Each task's actions are known lifted (:func:`below`: each
action's arguments as the task's parameters, constants of the methods, or any
value).  A false goal fact is **supported** when some action below some task of
the stack may add it and each positive fact of that action's precondition (its
variables bound by the goal fact where the effect names them) holds in the state,
may be any fact (an argument still free), or may be added by some action below a
task of the stack.  A node with a goal fact that has no support is dropped.
"""

from __future__ import annotations

from typing import Any

from planner.heuristics.grounding import added_atoms
from planner.io import hddl
from planner.io.translate import NETWORK, lift_term
from planner.model.formulas import conjuncts
from planner.search.late import Unbound

LIMIT = 50_000
"""The most lifted actions below all tasks beyond which the check is given up (their
computation and the node's look-ups would cost more than the search they spare)."""

TRIAL = 2_000
"""The nodes checked before the check is given up when it dropped none of them: where the
lifted "may add" already tells the dead ends (Multiarm-Blocksworld), it drops nothing
and would cost two to three times the search's time."""

Term = Any
"""An argument of a lifted action below a task: the index of a task parameter (int), a
constant (str) or None (any value)."""
Schema = tuple[tuple[tuple[str, tuple[Any, ...]], ...], tuple[tuple[str, tuple[Any, ...]], ...]]
"""An action's positive precondition facts and the facts it may add, each argument the
index of an action parameter (int), a constant (str) or None (a ``forall`` variable)."""


def below(domain: hddl.HDDLDomain, problem: hddl.HDDLProblem
          ) -> dict[str, set[tuple[str, tuple[Term, ...]]]] | None:
    """For each task, the actions its decompositions may contain, lifted: the action's
    name and its arguments seen from the task (a fixpoint over the methods; None past
    :data:`LIMIT`).  The initial task network is the task ``NETWORK``."""
    found: dict[str, set[tuple[str, tuple[Term, ...]]]] = {
        name: {(name, tuple(range(len(action.params))))}
        for name, action in domain.actions.items()}
    networks = [(method.task.name, method.task.args, method.subtasks)
                for method in domain.methods]
    networks.append((NETWORK, (), problem.htn_subtasks))
    total = len(found)
    changed = True
    while changed:
        changed = False
        for task, head_args, subtasks in networks:
            head = {term: i for i, term in reversed(list(enumerate(head_args)))
                    if term.startswith("?")}
            target = found.setdefault(task, set())
            for sub in subtasks:
                for action, terms in list(found.get(sub.name, ())):
                    lifted = (action, tuple(lift_term(term, sub.args, head, {}) for term in terms))
                    if lifted not in target:
                        target.add(lifted)
                        total += 1
                        changed = True
                        if total > LIMIT:
                            return None
    return found


def schemas(domain: hddl.HDDLDomain) -> dict[str, Schema]:
    """Each action's positive precondition facts and the facts it may add (conditional
    effects included), over its parameters' indexes."""
    out = {}
    for name, action in domain.actions.items():
        index = {var: i for i, (var, _) in enumerate(action.params)}

        def terms(args: tuple[str, ...], index: dict[str, int] = index) -> tuple[Any, ...]:
            return tuple(index.get(t) if t.startswith("?") else t for t in args)

        pre = tuple((f.children[0], terms(f.children[1]))
                    for f in conjuncts(action.precondition) if f.kind == "pred")
        adds = tuple((pred, terms(args)) for pred, args, _ in added_atoms(action.effect))
        out[name] = (pre, adds)
    return out


class _Entry:
    """What the actions below one task (its arguments as met) may do, worked out as the
    search asks: for each goal fact, the precondition facts of each action that may add
    it (those that name a free argument left out: they may hold); and whether some action
    may add a fact."""

    __slots__ = ("rows", "added", "needs", "adds")

    def __init__(self, rows: list[tuple[Schema, tuple]]):
        self.rows = rows
        """Each action below the task: its schema and its arguments (None: free)."""
        self.added: dict[str, list[tuple]] = {}
        for (_, adds), bound in rows:
            for pred, atom in adds:
                self.added.setdefault(pred, []).append(
                    tuple([bound[t] if t.__class__ is int else t for t in atom]))
        self.needs: dict[tuple[str, tuple], list[tuple[tuple[str, tuple], ...]]] = {}
        self.adds: dict[tuple[str, tuple], bool] = {}

    def needed(self, goal: tuple[str, tuple]) -> list[tuple[tuple[str, tuple], ...]]:
        """For each action below that may add ``goal``, the ground facts its precondition
        needs (an empty tuple: it needs none that could be false)."""
        known = self.needs.get(goal)
        if known is not None:
            return known
        pred, fact = goal
        out = set()
        for (pre, adds), bound in self.rows:
            for added_pred, atom in adds:
                if added_pred != pred:
                    continue
                binding = _unify(atom, fact, bound)
                if binding is None:
                    continue
                facts = []
                for p, terms in pre:
                    ground = tuple([binding[t] if t.__class__ is int else t for t in terms])
                    if None not in ground:
                        facts.append((p, ground))
                out.add(tuple(facts))
        known = self.needs[goal] = sorted(out, key=len)
        return known

    def may_add(self, pred: str, fact: tuple) -> bool:
        key = (pred, fact)
        known = self.adds.get(key)
        if known is None:
            known = self.adds[key] = any(
                all(a is None or a == v for a, v in zip(atom, fact, strict=True))
                for atom in self.added.get(pred, ()))
        return known


class Support:
    """The support check of one problem's goal facts (see the module's docstring)."""

    def __init__(self, lifted: dict[str, set[tuple[str, tuple[Term, ...]]]],
                 actions: dict[str, Schema], goals: list[tuple[str, tuple]]):
        self.lifted = {task: sorted(rows, key=repr) for task, rows in lifted.items()}
        self.actions = actions
        self.goals = goals
        self.entries: dict[tuple[str, tuple], _Entry] = {}
        """The entry of each task and arguments met (a placeholder as None)."""
        self.made: list[_Entry] = []
        """The entries in the order they were made."""
        self.stacks: dict[int, frozenset[_Entry]] = {}
        """The entries of each task stack met, by its hash."""
        self.fact_adders: dict[tuple[str, tuple], list] = {}
        """For each fact asked about, the entries that may add it (and how many of
        ``made`` were looked at)."""
        self.goal_adders: dict[int, list] = {}
        """For each goal fact, the entries with an action that may add it (idem)."""
        self.supports: dict[int, tuple[_Entry, tuple[tuple[str, tuple], ...]]] = {}
        """What supported each goal fact last: an entry, and the facts its action needs."""
        self.adding: dict[tuple[str, tuple], _Entry] = {}
        """The entry that could add each fact asked about, last."""
        self.checked = 0
        self.dropped = 0

    @property
    def useful(self) -> bool:
        """Whether the check is still worth its cost: it dropped a node, or has not been
        tried on :data:`TRIAL` nodes yet."""
        return self.dropped > 0 or self.checked < TRIAL

    @classmethod
    def of(cls, domain: hddl.HDDLDomain, problem: hddl.HDDLProblem,
           goals: list[tuple[str, tuple]]) -> Support | None:
        """The check for ``goals`` (the positive goal facts), or None when the actions
        below the tasks are too many (:data:`LIMIT`)."""
        lifted = below(domain, problem)
        return None if lifted is None else cls(lifted, schemas(domain), goals)

    def _entry(self, task: str, args: tuple) -> _Entry:
        key = (task, tuple([None if a.__class__ is Unbound else a for a in args]))
        known = self.entries.get(key)
        if known is None:
            values = key[1]
            known = self.entries[key] = _Entry([
                (self.actions[action],
                 tuple([values[t] if t.__class__ is int else t for t in terms]))
                for action, terms in self.lifted.get(task, ())])
            self.made.append(known)
        return known

    def _stack(self, agenda: Any) -> frozenset[_Entry]:
        """The entries of a task stack's tasks, kept by the hash of each stack met (stacks
        share their tails)."""
        known = self.stacks
        pending = []
        while agenda is not None and agenda[3] not in known:
            pending.append(agenda)
            agenda = agenda[4]
        found: frozenset[_Entry] = frozenset() if agenda is None else known[agenda[3]]
        for entry in reversed(pending):
            mine = self._entry(entry[0], entry[1])
            if mine not in found:
                found = found | {mine}
            known[entry[3]] = found
        return found

    def _which(self, index: dict, key: Any, test: Any) -> list[_Entry]:
        """The entries made so far that pass ``test``, kept in ``index`` by ``key`` and
        brought up to date with the entries made since."""
        known = index.get(key)
        made = self.made
        if known is None:
            known = index[key] = [0, []]
        if known[0] < len(made):
            known[1].extend(entry for entry in made[known[0]:] if test(entry))
            known[0] = len(made)
        return known[1]

    def unsupported(self, false: frozenset[int], state: Any, agenda: Any) -> int | None:
        """The index of a goal fact among ``false`` (indexes into ``goals``) that no
        action below the stack ``agenda`` can add from ``state``, relaxed; or None.  What
        supported a fact last (an entry, and the facts its action needs) is tried first:
        from one node to the next, most supports stay."""
        self.checked += 1
        entries = self._stack(agenda)
        get = state.get
        which = self._which
        holding: dict[tuple[str, tuple], bool] = {}
        fact_adders, adding = self.fact_adders, self.adding

        def holds(pred: str, fact: tuple) -> bool:
            if get(pred, fact):
                return True
            key = (pred, fact)
            known = holding.get(key)
            if known is None:
                witness = adding.get(key)
                if witness is not None and witness in entries:
                    known = True
                else:
                    known = False
                    for entry in which(fact_adders, key,
                                       lambda entry: entry.may_add(pred, fact)):
                        if entry in entries:
                            adding[key] = entry
                            known = True
                            break
                holding[key] = known
            return known

        goals, goal_adders, supports = self.goals, self.goal_adders, self.supports
        for index in sorted(false):
            witness = supports.get(index)
            if witness is not None and witness[0] in entries and all(
                    holds(p, f) for p, f in witness[1]):
                continue
            goal = goals[index]
            for entry in which(goal_adders, index,
                               lambda entry, goal=goal: bool(entry.needed(goal))):
                if entry in entries:
                    facts = next((facts for facts in entry.needed(goal)
                                  if all(holds(p, f) for p, f in facts)), None)
                    if facts is not None:
                        supports[index] = (entry, facts)
                        break
            else:
                self.dropped += 1
                return index
        return None


def _unify(atom: tuple, fact: tuple, bound: tuple) -> list | None:
    """The action's arguments ``bound`` with those its added ``atom`` names set to the
    fact's values, or None when the atom cannot be the fact."""
    binding = list(bound)
    for term, value in zip(atom, fact, strict=True):
        if term.__class__ is int:
            current = binding[term]
            if current is None:
                binding[term] = value
            elif current != value:
                return None
        elif term is not None and term != value:
            return None
    return binding
