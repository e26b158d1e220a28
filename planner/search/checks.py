"""The checks of a decomposition where it is chosen: threats and goals out of reach.

The depth-first search (:mod:`planner.search.depthfirst`) refuses a decomposition that
cannot end well, before it searches below it:

* **doomed decompositions**: one of its actions (arguments bound) needs a fact
  that is false and that no subtask before it may add, or deletes a fact that an
  action among the :data:`LOOKAHEAD` tasks after it on the agenda needs, with no
  task in between that may add it again (a threat, in partial-order planning's
  words);
* **goals out of reach** (a problem with at most :data:`FEW_GOALS` goal facts):
  after it, no task left may add a false goal fact that the decomposed task may
  add (what a task may add is guarded by the constants its methods fix:
  ``Domain.may_add``).

They live apart from the search because they are a model of the domain (which
actions need or change which facts, which tasks may add them) built once per
problem, with its own caches; the search only asks them, and only after its
first plain pass (docs/planner.md).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from planner.heuristics.landmarks import Chains
from planner.model.domain import Decomposition, Domain
from planner.model.state import State

LOOKAHEAD = 64
"""How many tasks ahead on the agenda a deleted fact is looked for among the actions'
preconditions (threat detection; beyond, the branch fails where the action is met)."""
FEW_GOALS = 4
"""A problem with at most this many goal facts has its decompositions checked for a goal
fact no task left may add.  The check costs a look-up per goal fact and decomposition,
and pays when the goal says what the task network must reach (plan recognition: one
goal fact); with a goal fact per child or block it cost Childsnack and Blocksworld more
than it saved."""
MAX_KEPT = 1_000_000
"""The most answers :meth:`DecompositionChecks.may_come` keeps (then it forgets them all)."""


def task_call(name: str, args: tuple) -> str:
    """``name(a, b)``: a task or action with its arguments, as explanations write it."""
    return f"{name}({', '.join(str(a) for a in args)})"


class DecompositionChecks:
    """What the checks know of one problem's domain and goals (see the module's
    docstring)."""

    def __init__(self, domain: Domain, goals: tuple[tuple[str, tuple, Any], ...]):
        self.domain = domain
        changed = {pred for action in domain.actions.values()
                   for pred, _ in action.removes}
        changed |= {pred for adds in domain.adds.values() for pred in adds}
        self.needers: dict[str, dict[str, list[Callable[[dict[str, Any]], tuple]]]] = {}
        """For each predicate some action changes, the actions that need one of its facts
        (and the functions of their arguments giving those facts)."""
        for name, action in domain.actions.items():
            for pred, key in action.needs:
                if pred in changed:
                    self.needers.setdefault(pred, {}).setdefault(name, []).append(key)
        self.adders: dict[str, set[str]] = {}
        """For each predicate, the tasks that may add one of its facts."""
        for task, adds in domain.adds.items():
            for pred in adds:
                self.adders.setdefault(pred, set()).add(task)
        positive = [(pred, args) for pred, args, value in goals if value is True]
        self.few_goals = positive if len(positive) <= FEW_GOALS else []
        """The goal facts :meth:`unreachable` checks."""
        self.chains = Chains(domain, self.few_goals)
        """The chains of facts those goal facts need in order
        (:mod:`planner.heuristics.landmarks`)."""
        self.relevant: dict[str, dict[str, tuple[list[Callable[[dict[str, Any]], tuple]],
                                                  bool]]] = {}
        """For each predicate some action needs, the tasks :meth:`needed` looks at: the
        functions giving the facts of it each needs, and whether it may add one."""
        for pred, by_name in self.needers.items():
            adders = self.adders.get(pred, set())
            self.relevant[pred] = {name: (by_name.get(name, []), name in adders)
                                   for name in {*by_name, *adders}}
        self.coming: dict[tuple[int, str, tuple], bool] = {}
        """:meth:`may_come`'s answers, by the hash of an agenda's tail and a fact."""
        self.has_checks: dict[int, bool] = {}
        """For each decomposition (by id), :meth:`checked`'s answer."""
        self.checks: dict[str, tuple[tuple, tuple]] = {}
        """For each action, what :meth:`doomed` checks: the facts it needs that some
        action changes, and those it deletes that some action needs."""
        for name, action in domain.actions.items():
            needs = tuple((p, k) for p, k in action.needs if p in changed)
            removes = tuple((p, k) for p, k in action.removes if p in self.needers)
            if needs or removes:
                self.checks[name] = (needs, removes)

    def checked(self, dec: Decomposition) -> bool:
        """Whether :meth:`doomed` has anything to check in this decomposition: an action
        among its subtasks that needs a fact some action changes (after the first, whose
        precondition the binder checks) or deletes one some action needs."""
        known = self.has_checks.get(id(dec))
        if known is None:
            known = any(sub.task in self.checks and (position or self.checks[sub.task][1])
                        for position, sub in enumerate(dec.subtasks))
            self.has_checks[id(dec)] = known
        return known

    def risky(self, agenda: Any, count: int, state: State) -> bool:
        """Whether the first ``count`` tasks of ``agenda`` delete a true fact that an action
        among the :data:`LOOKAHEAD` tasks after them needs, though a task in between may
        add it again (which :meth:`doomed` lets pass): a threat that is not proved."""
        checks = self.checks
        entry = agenda
        for _ in range(count):
            name, args, _, _, rest = entry
            check = checks.get(name)
            if check is not None and check[1]:
                env = dict(zip(self.domain.actions[name].names, args, strict=True))
                for pred, key in check[1]:
                    fact = key(env)
                    if (state.get(pred, fact) is True
                            and self.needed(pred, fact, rest, past_adders=True)):
                        return True
            entry = rest
        return False

    def doomed(self, agenda: Any, count: int, state: State) -> str | None:
        """Why the first ``count`` tasks of ``agenda`` (a decomposition's subtasks) doom it,
        if they do: one of their actions needs a fact that is false and that no task
        before it may add, or deletes a fact that an action among the :data:`LOOKAHEAD`
        tasks after it needs, with no task in between that may add it again."""
        checks, may_add = self.checks, self.domain.may_add
        before: list[tuple[str, tuple]] = []
        entry = agenda
        for position in range(count):
            name, args, _, _, rest = entry
            check = checks.get(name)
            if check is not None:
                needs, removes = check
                env = dict(zip(self.domain.actions[name].names, args, strict=True))
                # The first action's precondition is the binder's: it holds already.
                for pred, key in needs if position else ():
                    fact = key(env)
                    if state.get(pred, fact) is not True:
                        adders = self.adders.get(pred, ())
                        if not any(n in adders and may_add(n, a, pred, fact)
                                   for n, a in before):
                            return (f"{task_call(name, args)} needs "
                                    f"({' '.join((pred, *fact))}), false, which no task "
                                    "before it can make true")
                for pred, key in removes:
                    fact = key(env)
                    if state.get(pred, fact) is not True:  # rarely needed: not checked
                        continue
                    why = self.needed(pred, fact, rest)
                    if why is not None:
                        return f"{task_call(name, args)} deletes {why}"
            before.append((name, args))
            entry = rest
        return None

    def unreachable(self, name: str, args: tuple, agenda: Any, state: State) -> str | None:
        """Which goal fact, false in ``state``, no task on ``agenda`` may add (``agenda`` is
        what decomposing ``name(args)`` leaves; checked when the problem has at most
        :data:`FEW_GOALS` goal facts).  Only the goal facts ``name(args)`` may add are
        looked at: the others, its subtasks cannot add either, and what follows is
        unchanged.  Monroe's plan recognition: its one goal says that the observed
        actions were all done, and only one of the ten top-level methods can do them.
        Then the chains of facts those goals need in order (:mod:`planner.heuristics.landmarks`):
        a task left must be able to do the observations still to come, in turn."""
        may_add, get = self.domain.may_add, state.get
        for pred, fact in self.few_goals:
            if (may_add(name, args, pred, fact) and get(pred, fact) is not True
                    and not self.may_come(agenda, pred, fact)):
                return f"no task left can make the goal ({' '.join((pred, *fact))}) true"
        if self.chains and self.chains.may_add_any(name, args):
            return self.chains.broken(agenda, get)
        return None

    def may_come(self, agenda: Any, pred: str, fact: tuple) -> bool:
        """Whether a task on ``agenda`` may add ``pred(fact)``: the answer for each tail of
        the agenda is kept (by its hash, which stands for its tasks), so that the
        decompositions that share what follows them only look at their own subtasks."""
        known = self.coming
        if len(known) > MAX_KEPT:
            known.clear()
        may_add = self.domain.may_add
        passed = []
        answer = False
        entry = agenda
        while entry is not None:
            name, args, _, tail, rest = entry
            found = known.get((tail, pred, fact))
            if found is not None:
                answer = found
                break
            if may_add(name, args, pred, fact):
                answer = True
                break
            passed.append(tail)
            entry = rest
        for tail in passed:
            known[(tail, pred, fact)] = answer
        return answer

    def needed(self, pred: str, fact: tuple, agenda: Any,
               past_adders: bool = False) -> str | None:
        """Which later action needs ``pred(fact)``, if one does among the
        :data:`LOOKAHEAD` next tasks on ``agenda`` with no task before it that may add a
        fact of that predicate (not only this one: the scan stays cheap, and ends where
        a long agenda of tasks of the same kind begins); ``past_adders``: whatever may
        add it before (:meth:`risky`)."""
        relevant, actions = self.relevant[pred], self.domain.actions
        for _ in range(LOOKAHEAD):
            if agenda is None:
                return None
            name, args, _, _, agenda = agenda
            found = relevant.get(name)
            if found is None:
                continue
            keys, adds = found
            if keys:
                env = dict(zip(actions[name].names, args, strict=True))
                if any(key(env) == fact for key in keys):
                    return (f"({' '.join((pred, *fact))}), which {task_call(name, args)} "
                            "needs later, and no task before it can make it true again")
            if adds and not past_adders:  # it may add a fact of this predicate
                return None
        return None
