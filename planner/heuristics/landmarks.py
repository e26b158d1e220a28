"""Chains of facts a goal needs in order, and the task stacks that cannot make them so.

Monroe's plan recognition (Monroe-Partially-Observable) has one goal fact, the
last observation's ``l_(n+1)``, added only by the observed action ``p_n``,
which needs ``l_n``, added only by ``p_(n-1)``, and so on down to ``l_1``,
true at the start: the observations must all be done, in order.  A goal check
("may a task left add ``l_(n+1)``?", :mod:`planner.heuristics.reach`,
:mod:`planner.search.checks`) sees only the last link; a top-level task that may do
the last observation but not the first passes it, and the search explores it in
full before the goal check at the end says no.

A **chain** is a sequence of facts ``c_0, ..., c_r`` (``c_r`` a goal fact) in
which every action that may add ``c_(j+1)`` needs ``c_j`` in its precondition
(the facts every achiever needs: landmarks, in planning's words, found on the
domain's actions with the achieved fact's arguments bound).  If ``c_s`` to
``c_r`` are all false in a state, a plan from it adds them in that order, each
by a task of the stack at or after the one that added the one before: the
stack must hold a subsequence of tasks that may add them (``Domain.may_add``,
an over-approximation, so a stack refused is certainly a dead end).  Which
suffix of a chain a stack may add is found from its last task up, greedily
(as far as each task may go), and kept by the hash of each stack met (stacks
share their tails).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from planner.model.domain import Domain

MAX_CHAINS = 16
"""The most chains kept (the longest): each costs a look-up per task a stack gains."""
MAX_LENGTH = 64
"""The most facts of one chain (a goal's landmarks are followed down that far)."""
ORDERED = 4096
"""The most successors of one decomposition :meth:`Chains.ordered` puts in order."""
MAX_KEPT = 1_000_000
"""The most answers kept per chain (then they are all forgotten)."""

Fact = tuple[str, tuple]


def _needs(domain: Domain, added: set[str], pred: str, fact: tuple) -> set[Fact] | None:
    """The facts (of the predicates ``added``, those some action adds) every action
    that may add ``pred(fact)`` needs, with the arguments the fact binds; None when no
    action may add it."""
    common: set[Fact] | None = None
    for name, action in domain.actions.items():
        for pattern, _ in domain.adds.get(name, {}).get(pred, ()):
            env: dict[str, Any] | None = {}
            for entry, value in zip(pattern, fact, strict=True):
                if entry is None:
                    continue
                if entry.__class__ is int:
                    known = env.setdefault(action.names[entry], value)
                    if known != value:
                        env = None
                        break
                elif entry != value:
                    env = None
                    break
            if env is None:
                continue
            needed: set[Fact] = set()
            for need, key in action.needs:
                if need not in added:
                    continue
                try:
                    needed.add((need, key(env)))
                except KeyError:  # a parameter the fact does not bind
                    continue
            common = needed if common is None else common & needed
    return common


def chains_of(domain: Domain, goals: list[Fact]) -> list[tuple[Fact, ...]]:
    """The chains ending in each goal fact, first fact first: each at least two facts
    long, none whose facts after its first are all in a longer one (Monroe: the chain
    of the observations, not each observation's own precondition before its part of
    it), the longest :data:`MAX_CHAINS`."""
    added = {pred for name in domain.actions for pred in domain.adds.get(name, {})}
    found: list[tuple[Fact, ...]] = []
    for goal in goals:
        pending: list[tuple[Fact, ...]] = [(goal,)]
        while pending and len(found) < 4 * MAX_CHAINS:
            path = pending.pop()
            below = _needs(domain, added, *path[-1]) if len(path) < MAX_LENGTH else None
            longer = [(*path, fact) for fact in sorted(below or (), key=repr)
                      if fact not in path]
            if longer:
                pending.extend(longer)
            elif len(path) > 1:
                found.append(tuple(reversed(path)))
    found.sort(key=len, reverse=True)
    kept: list[tuple[Fact, ...]] = []
    for chain in found:
        if not any(set(chain[1:]) <= set(other) for other in kept):
            kept.append(chain)
    return kept[:MAX_CHAINS]


class Chains:
    """The chains of one problem's goals, and what each stack met may add of them."""

    def __init__(self, domain: Domain, goals: list[Fact]):
        self.domain = domain
        self.chains = chains_of(domain, goals)
        self.facts = sorted({fact for chain in self.chains for fact in chain}, key=repr)
        bit = {fact: 1 << position for position, fact in enumerate(self.facts)}
        self.bits = [tuple(bit[fact] for fact in chain) for chain in self.chains]
        """Each chain's facts, as bits of :attr:`facts`."""
        self.masks: dict[tuple[str, tuple], tuple[int, int]] = {}
        """For each task met: the facts of :attr:`facts` it may add, and those it may
        add through a decomposition that names them (``Domain.may_add_named``)."""
        self.known: list[dict[int, int]] = [{} for _ in self.chains]
        """For each chain, by a stack's hash: the first fact of the chain from which
        the stack may add the rest, in order."""

    def __bool__(self) -> bool:
        return bool(self.chains)

    def _masks(self, name: str, args: tuple) -> tuple[int, int]:
        key = (name, args)
        known = self.masks.get(key)
        if known is None:
            if len(self.masks) > MAX_KEPT:
                self.masks.clear()
            may_add, named = self.domain.may_add, self.domain.may_add_named
            adds = names = 0
            for position, (pred, fact) in enumerate(self.facts):
                if may_add(name, args, pred, fact):
                    adds |= 1 << position
                    if named(name, args, pred, fact):
                        names |= 1 << position
            known = self.masks[key] = (adds, names)
        return known

    def may_add_any(self, name: str, args: tuple) -> bool:
        """Whether ``name(args)`` may add a fact of some chain (else a decomposition
        of it changes no chain's answer)."""
        return self._masks(name, args)[0] != 0

    def _starts(self, get: Any) -> list[tuple[int, int]]:
        """For each chain whose goal fact is false in the state read by ``get``: its
        index and that of its first fact still to be made true (the facts from it on
        are all false)."""
        out = []
        for index, chain in enumerate(self.chains):
            if get(*chain[-1]) is True:
                continue
            start = len(chain) - 1
            while start > 0 and get(*chain[start - 1]) is not True:
                start -= 1
            out.append((index, start))
        return out

    def ordered(self, successors: Iterator[tuple], rest: Any, get: Any) -> Iterator[tuple]:
        """The search nodes ``successors`` (a decomposition's, each ``(state, hash,
        agenda, trail)`` whose agenda ends in ``rest``) in a better order: those
        whose new tasks may add the next fact of a chain, and among them those whose
        tasks name the most facts still to come (``Domain.may_add_named``: through
        the constants a method fixes, not only through a variable that may be
        anything), else in their order, and last those whose stack cannot complete a
        chain (:meth:`broken`: the search refuses them once it checks decompositions);
        the first :data:`ORDERED` only, the rest follow as they come.  Monroe: the
        method that does the next observation (``prefix_2``) before the one that does
        the same action unobserved (``regular_2``); the riot quelled where the
        observed police drive to, of the 25 places the top-level method may choose."""
        starts = self._starts(get)
        if not starts:
            yield from successors
            return
        wanted = coming = 0
        for index, start in starts:
            bits = self.bits[index]
            wanted |= bits[start]
            for value in bits[start:]:
                coming |= value
        masks = self._masks
        keyed = []
        for count, node in enumerate(successors):
            adds = names = 0
            entry = node[2]
            while entry is not None and entry is not rest:
                mask, named = masks(entry[0], entry[1])
                adds |= mask
                names |= named
                entry = entry[4]
            broken = any(self._from(index, node[2]) > start for index, start in starts)
            keyed.append((broken, not adds & wanted, -(names & coming).bit_count(), count,
                          node))
            if count + 1 >= ORDERED:
                break
        keyed.sort(key=lambda item: item[:4])
        for *_, node in keyed:
            yield node
        yield from successors

    def broken(self, agenda: Any, get: Any) -> str | None:
        """Which chain the stack ``agenda`` cannot complete from the state read by
        ``get(pred, args)`` (entries are ``(task, args, path, hash, rest)``)."""
        for index, start in self._starts(get):
            if self._from(index, agenda) > start:
                chain = self.chains[index]
                pred, fact = chain[start]
                return (f"no order of the tasks left can make ({' '.join((pred, *fact))}) "
                        f"and the {len(chain) - start - 1} facts after it true in turn")
        return None

    def _from(self, index: int, agenda: Any) -> int:
        known = self.known[index]
        if len(known) > MAX_KEPT:
            known.clear()
        bits = self.bits[index]
        pending = []
        while agenda is not None and agenda[3] not in known:
            pending.append(agenda)
            agenda = agenda[4]
        first = len(bits) if agenda is None else known[agenda[3]]
        masks = self._masks
        for entry in reversed(pending):
            mask = masks(entry[0], entry[1])[0]
            while first > 0 and mask & bits[first - 1]:
                first -= 1
            known[entry[3]] = first
        return first
