"""Which goal facts a task stack may still make true: the goal-guided search's dead ends.

A node of the goal-guided search (:mod:`planner.search.progression`) whose state has a
goal fact false that no task left on its stack may add can never reach the
goal: after the last task, the fact is still false.  Woodworking shows why it
matters: a part cut from the wrong board has the wrong wood for good (only
cutting an unused part sets ``wood``), yet the search, which sees only how many
goal facts are unmet, would go on choosing colours and machines for every other
part before the goal check at the end says no.

What a task may add is the lifted over-approximation ``Domain.may_add`` (an
argument not bound yet, a placeholder of :mod:`planner.search.late`, may be anything),
so a node dropped is certainly a dead end.  The goal facts are indexed by
predicate and argument, and what a stack may add is kept by the hash of each
stack met (stacks share their tails), so a node pays for the tasks its
decomposition put on the stack only.
"""

from __future__ import annotations

from typing import Any

from planner.model.domain import Domain, fits
from planner.search.late import Unbound


class GoalReach:
    """The goal facts (``pred``, ``args``) each task stack may add (by their index)."""

    def __init__(self, domain: Domain, goals: list[tuple[str, tuple]]):
        self.domain = domain
        self.goals = goals
        self.by_pred: dict[str, list[int]] = {}
        self.by_arg: dict[tuple[str, int, Any], list[int]] = {}
        for index, (pred, fact) in enumerate(goals):
            self.by_pred.setdefault(pred, []).append(index)
            for position, value in enumerate(fact):
                self.by_arg.setdefault((pred, position, value), []).append(index)
        self.stacks: dict[int, frozenset[int]] = {}
        """What each stack met may add, by the stack's hash."""

    def addable(self, agenda: Any) -> frozenset[int]:
        """The goal facts some task of the stack ``agenda`` may add (entries are
        ``(task, args, path, hash, rest)``)."""
        known = self.stacks
        pending = []
        while agenda is not None and agenda[3] not in known:
            pending.append(agenda)
            agenda = agenda[4]
        found = frozenset() if agenda is None else known[agenda[3]]
        for entry in reversed(pending):
            extra = self._task(entry[0], entry[1], found)
            if extra:
                found = found | extra
            known[entry[3]] = found
        return found

    def _task(self, name: str, args: tuple, known: frozenset[int]) -> set[int]:
        """The goal facts not in ``known`` that ``name(args)`` may add."""
        out: set[int] = set()
        goals = self.goals
        for pred, patterns in self.domain.adds.get(name, {}).items():
            if pred not in self.by_pred:
                continue
            for pattern, guards in patterns:
                if guards and any(args[index] != constant for index, constant in guards):
                    continue
                candidates = None
                for position, entry in enumerate(pattern):
                    value = args[entry] if entry.__class__ is int else entry
                    if value is not None and value.__class__ is not Unbound:
                        candidates = self.by_arg.get((pred, position, value), ())
                        break
                if candidates is None:
                    candidates = self.by_pred[pred]
                for index in candidates:
                    if index in known or index in out:
                        continue
                    if fits(pattern, args, goals[index][1]):
                        out.add(index)
        return out
