"""An admissible lower bound on the cost the tasks left on the agenda will add.

The branch and bound (:mod:`planner.search.branchbound`) abandons a partial plan when its
score so far, plus a lower bound on what is left, cannot beat the best plan
found.  With the cost so far alone, a partial plan is abandoned only when it
is nearly finished; this module bounds the rest: each task on the agenda
costs at least its *cheapest decomposition*, computed over a relaxation of
the problem:

- Each task on the agenda reads the state as it is now, except what the
  tasks before it may have written: those values are *unknown*.  What a task
  may write is a lifted analysis of the domain (:meth:`RemainingCost.writes`):
  ``obj.on`` of its own parameter ``obj``, ``at`` of any agent.
- Inside one task, each way of carrying it out (an *outcome*: a choice of
  decompositions and bindings) is followed with what it writes
  (:class:`Overlay`): after ``Move(jido, coffee-area)``, Jido is known to be
  in the coffee area; a value computed from an unknown one is unknown.
  Outcomes that write the same keep the cheapest; beyond
  :data:`MAX_OUTCOMES` they are merged into one that keeps only what they
  all agree on.
- A precondition is split into its top-level conjuncts; a conjunct that reads
  nothing unknown is decided exactly, and one false conjunct rules the
  decomposition (or action) out.  Anything else may hold.
- An argument that reads something unknown is unknown itself (any entity);
  an action cost that does is counted as 0.
- A task met again inside its own decomposition counts 0 (recursion).

Each step only widens what is possible, so the bound never exceeds the cost
of any real completion (costs are not negative: the search assumes that
already).  In the living room, it sees that a bottle out of the robot's reach
needs a human's Pick and Give, and that the robot, far from the first bottle,
must move there.

The bound of a task depends on its arguments and on the few values it read,
so it is kept, with those values, and reused while they are the same: the
top tasks far down the agenda are bounded once for many nodes.  HDDL domains
(``predicates``) are not bounded: their methods bind variables from facts.
"""

from __future__ import annotations

import itertools
import re
from typing import Any

from planner.model.domain import Action, ConditionalEffect, Method, Problem
from planner.model.expr import Expr, compile_expr

ANY = -1
"""In a lifted write: the entity written is not one of the task's parameters."""
MAX_BINDINGS = 1000
"""A decomposition with more variable bindings than this is not bounded (it counts 0)."""
MAX_DEPTH = 64
"""Deeper than this in one relaxed decomposition, a task counts 0."""
MAX_OUTCOMES = 16
"""Beyond this many outcomes of one step of a relaxed decomposition, they are merged."""
MAX_VARIANTS = 256
"""How many (values read, bound) variants are kept per task and arguments."""
INF = float("inf")


class _Wild:
    """An unknown argument: it may be any entity."""

    def __repr__(self) -> str:
        return "?"


WILD = _Wild()
_OWNER = re.compile(r"\s*([A-Za-z_]\w*)\s*\.\s*([A-Za-z_]\w*)\s*=(?!=)")


def conjuncts(text: str) -> list[str]:
    """The top-level ``and`` parts of a condition (one part when it has a top-level
    ``or``, which binds looser than ``and``)."""
    parts, depth, start, has_or = [], 0, 0, False
    for match in re.finditer(r"\"[^\"]*\"|'[^']*'|[()]|\band\b|\bor\b", text):
        token = match.group()
        if token == "(":
            depth += 1
        elif token == ")":
            depth -= 1
        elif depth == 0 and token == "or":
            has_or = True
        elif depth == 0 and token == "and":
            parts.append(text[start:match.start()])
            start = match.end()
    parts.append(text[start:])
    if has_or:
        return [text]
    return [p.strip() for p in parts if p.strip()]


UNKNOWN = _Wild()
"""A value in an overlay that the relaxation cannot know."""


class Overlay:
    """What a relaxed decomposition has written so far: values (or UNKNOWN) by
    (entity, attribute), and attributes written on unknown entities."""

    __slots__ = ("keys", "any", "_hash")

    def __init__(self, keys: dict[tuple, Any], any_: frozenset[str]):
        self.keys = keys
        self.any = any_
        self._hash: int | None = None

    def __hash__(self) -> int:
        if self._hash is None:
            self._hash = hash((frozenset(self.keys.items()), self.any))
        return self._hash

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Overlay) and self.any == other.any
                and self.keys == other.keys)


EMPTY = Overlay({}, frozenset())


def merge(overlays: list[Overlay]) -> Overlay:
    """One overlay that every given one agrees with: a value all of them wrote alike
    stays, any other written value is unknown."""
    keys: dict[tuple, Any] = {}
    for overlay in overlays:
        for key, value in overlay.keys.items():
            if keys.get(key, value) != value or any(key not in o.keys for o in overlays):
                keys[key] = UNKNOWN
            else:
                keys.setdefault(key, value)
    return Overlay(keys, frozenset().union(*(o.any for o in overlays)))


class _Reader:
    """Reads the state for one relaxed evaluation: what a relaxed decomposition wrote
    first, unknown where an earlier task may have written, and remembers what it read
    from the state (the memo's dependencies)."""

    __slots__ = ("state", "outer_any", "outer_keys", "deps", "unknown", "dynamic")

    def __init__(self, state: Any, outer_any: set[str], outer_keys: set[tuple],
                 dynamic: frozenset[str]):
        self.state = state
        self.outer_any = outer_any
        self.outer_keys = outer_keys
        self.dynamic = dynamic
        self.deps: dict[tuple[str, str], tuple[bool, Any]] = {}
        self.unknown = False

    def getter(self, overlay: Overlay) -> Any:
        keys, any_ = overlay.keys, overlay.any

        def get(entity: Any, attribute: str) -> Any:
            if entity is WILD:
                self.unknown = True
                return None
            if attribute not in self.dynamic:  # static: never written
                return self.state.get(entity, attribute)
            key = (entity, attribute)
            value = keys.get(key, WILD)
            if value is not WILD:
                if value is UNKNOWN:
                    self.unknown = True
                    return None
                return value
            if attribute in any_:
                self.unknown = True
                return None
            if attribute in self.outer_any or key in self.outer_keys:
                self.deps[key] = (True, None)
                self.unknown = True
                return None
            value = self.state.get(entity, attribute)
            self.deps[key] = (False, value)
            return value

        return get


class RemainingCost:
    """The lower bound on the cost of an agenda's tasks (see the module's docstring)."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self.domain = problem.domain
        self.enabled = not self.domain.predicates
        self.dynamic = frozenset(a for t in self.domain.types.values() for a in t.dynamic)
        self.lifted = self._lifted_writes()
        self.parts: dict[int, list[Expr]] = {}
        self.memo: dict[tuple[str, tuple], list[tuple[tuple, float]]] = {}
        self.typed: dict[str, list[str]] = {}

    # -- what a task may write ---------------------------------------------------------

    def _lifted_writes(self) -> dict[str, set[tuple[int, str]]]:
        """For each task, the (parameter index or ANY, attribute) it may write."""
        writes: dict[str, set[tuple[int, str]]] = {}
        for action in self.domain.actions.values():
            found: set[tuple[int, str]] = set()
            effects = []
            for effect in action.effects:
                effects.extend(effect.effects if isinstance(effect, ConditionalEffect)
                               else [effect])
            for effect in effects:
                match = _OWNER.match(getattr(effect, "text", ""))
                attr = getattr(effect, "target_attribute", None)
                if attr is None:
                    continue
                owner = match.group(1) if match and match.group(2) == attr else None
                found.add((action.names.index(owner) if owner in action.names else ANY,
                           attr))
            writes[action.name] = found
        for method in self.domain.methods.values():
            writes[method.name] = set()
        changed = True
        while changed:
            changed = False
            for method in self.domain.methods.values():
                params = [p for p, _ in method.params]
                known = writes[method.name]
                for dec in method.decompositions:
                    for sub in dec.subtasks:
                        where = [params.index(a.text.strip()) if a.text.strip() in params
                                 else ANY for a in sub.args]
                        for index, attr in writes.get(sub.task, ()):
                            item = (ANY if index == ANY or index >= len(where)
                                    else where[index], attr)
                            if item not in known:
                                known.add(item)
                                changed = True
        return writes

    def writes(self, name: str, args: tuple, into_any: set[str],
               into_keys: set[tuple]) -> None:
        """Add what ``name(args)`` may write to the two sets (any entity's attribute; one
        entity's attribute)."""
        for index, attr in self.lifted.get(name, ()):
            value = ANY if index == ANY else args[index]
            if value is ANY or value is WILD:
                into_any.add(attr)
            else:
                into_keys.add((value, attr))

    # -- the bound -------------------------------------------------------------------------

    def bound(self, agenda: Any, state: Any, enough: float = INF) -> float:
        """A lower bound on the cost of the agenda's tasks from ``state``; it stops adding
        once it reaches ``enough``."""
        total = 0.0
        dirty_any: set[str] = set()
        dirty_keys: set[tuple] = set()
        while agenda is not None and total < enough:
            (name, args, _), agenda = agenda
            total += self._entry(name, args, state, dirty_any, dirty_keys)
            if agenda is not None:
                self.writes(name, args, dirty_any, dirty_keys)
        return total

    def _entry(self, name: str, args: tuple, state: Any, dirty_any: set[str],
               dirty_keys: set[tuple]) -> float:
        key = (name, args)
        variants = self.memo.get(key)
        if variants:
            get = state.get
            for deps, value in variants:
                for (entity, attr), (dirty, seen) in deps:
                    if (attr in dirty_any or (entity, attr) in dirty_keys) != dirty:
                        break
                    if not dirty and get(entity, attr) != seen:
                        break
                else:
                    return value
        reader = _Reader(state, dirty_any, dirty_keys, self.dynamic)
        value = min((price for price, _ in self._task(name, args, reader, EMPTY, ())),
                    default=INF)
        variants = self.memo.setdefault(key, [])
        if len(variants) >= MAX_VARIANTS:
            variants.pop(0)
        variants.append((tuple(reader.deps.items()), value))
        return value

    def _truth(self, expr: Expr, env: dict, reader: _Reader, get: Any) -> bool:
        """False only when a conjunct of ``expr`` is certainly false."""
        parts = self.parts.get(id(expr))
        if parts is None:
            parts = self.parts[id(expr)] = self._split(expr)
        for part in parts:
            if any(env.get(v) is WILD for v in part.variables):
                continue
            reader.unknown = False
            try:
                value = part.fn(env, get)
            except Exception:  # an evaluation error (null arithmetic): it may hold
                continue
            if not reader.unknown and not value:
                return False
        reader.unknown = False
        return True

    def _split(self, expr: Expr) -> list[Expr]:
        texts = conjuncts(expr.text)
        if len(texts) <= 1:
            return [expr]
        variables = {name: None for name in expr.variables}
        try:
            return [compile_expr(text, dict(variables)) for text in texts]
        except Exception:  # a part that does not compile alone: decide the whole
            return [expr]

    def _value(self, expr: Expr, env: dict, reader: _Reader, get: Any) -> Any:
        """The value of ``expr``, or WILD when it reads anything unknown."""
        if any(env.get(v) is WILD for v in expr.variables):
            return WILD
        reader.unknown = False
        try:
            value = expr.fn(env, get)
        except Exception:
            return WILD
        if reader.unknown:
            reader.unknown = False
            return WILD
        return value

    def _task(self, name: str, args: tuple, reader: _Reader, overlay: Overlay,
              stack: tuple) -> list[tuple[float, Overlay]]:
        """The outcomes of ``name(args)`` in the relaxation: each a lower bound on the
        cost of one way to carry it out, and what that way writes on top of
        ``overlay`` (outcomes with the same writes keep the cheapest)."""
        action = self.domain.actions.get(name)
        if action is not None:
            return self._action(action, args, reader, overlay)
        method = self.domain.methods.get(name)
        if method is None or (name, args) in stack or len(stack) >= MAX_DEPTH:
            return [(0.0, self._unknown_writes(name, args, overlay))]
        return self._method(method, args, reader, overlay, stack + ((name, args),))

    def _unknown_writes(self, name: str, args: tuple, overlay: Overlay) -> Overlay:
        """``overlay`` after ``name(args)`` wrote what it may, values unknown."""
        more_any: set[str] = set()
        more_keys: set[tuple] = set()
        self.writes(name, args, more_any, more_keys)
        keys = dict(overlay.keys)
        for key in more_keys:
            keys[key] = UNKNOWN
        if more_any:
            for key in [k for k in keys if k[1] in more_any]:
                keys[key] = UNKNOWN
        return Overlay(keys, overlay.any | more_any)

    def _action(self, action: Action, args: tuple, reader: _Reader,
                overlay: Overlay) -> list[tuple[float, Overlay]]:
        env = dict(zip(action.names, args, strict=True))
        get = reader.getter(overlay)
        if action.pre is not None and not self._truth(action.pre, env, reader, get):
            return []
        if not callable(action.cost):
            price = float(action.cost)
        else:
            value = self._value(action.cost, env, reader, get)
            price = float(value) if isinstance(value, int | float) and value > 0 else 0.0
        if any(a is WILD for a in args):
            return [(price, self._unknown_writes(action.name, args, overlay))]
        written: list[tuple[Any, str, Any]] = []
        unknown_any: set[str] = set()

        def put(entity: Any, attribute: str, value: Any) -> None:
            written.append((entity, attribute, UNKNOWN if reader.unknown else value))

        for effect in action.effects:
            inner = [effect]
            if isinstance(effect, ConditionalEffect):
                holds = self._truth(effect.condition, env, reader, get)
                if not holds:
                    continue
                inner = list(effect.effects)
                reader.unknown = False
                certain = bool(effect.condition.fn(env, get)) and not reader.unknown
                if not certain:  # it may or may not apply: its targets are unknown
                    for each in inner:
                        self._effect(each, env, reader, get, put, unknown_any, True)
                    continue
            for each in inner:
                self._effect(each, env, reader, get, put, unknown_any, False)
        keys = dict(overlay.keys)
        if unknown_any:
            for key in [k for k in keys if k[1] in unknown_any]:
                keys[key] = UNKNOWN
        for entity, attribute, value in written:
            if attribute not in unknown_any:
                keys[(entity, attribute)] = value
        return [(price, Overlay(keys, overlay.any | unknown_any))]

    def _effect(self, effect: Any, env: dict, reader: _Reader, get: Any, put: Any,
                unknown_any: set[str], uncertain: bool) -> None:
        """Apply one effect in the relaxation (an effect whose target cannot be found
        makes its attribute unknown on every entity)."""
        reader.unknown = False
        try:
            if uncertain:
                effect.fn(env, get, lambda e, a, v: put(e, a, UNKNOWN))
            else:
                effect.fn(env, get, put)
        except Exception:
            unknown_any.add(effect.target_attribute)
        reader.unknown = False

    def _method(self, method: Method, args: tuple, reader: _Reader, overlay: Overlay,
                stack: tuple) -> list[tuple[float, Overlay]]:
        env = {p: a for (p, _), a in zip(method.params, args, strict=True)}
        outcomes: dict[Overlay, float] = {}
        get = reader.getter(overlay)
        for dec in method.decompositions:
            choices = [self._of_type(t) for _, t in dec.vars]
            count = 1
            for choice in choices:
                count *= len(choice)
            if dec.bind is not None or count > MAX_BINDINGS:
                return [(0.0, self._unknown_writes(method.name, args, overlay))]
            names = [v for v, _ in dec.vars]
            for values in itertools.product(*choices):
                local = {**env, **dict(zip(names, values, strict=True))}
                if dec.pre is not None and not self._truth(dec.pre, local, reader, get):
                    continue
                partial: dict[Overlay, float] = {overlay: 0.0}
                for sub in dec.subtasks:
                    following: dict[Overlay, float] = {}
                    for before, spent in partial.items():
                        sub_get = reader.getter(before)
                        sub_args = tuple(self._value(a, local, reader, sub_get)
                                         for a in sub.args)
                        for price, after in self._task(sub.task, sub_args, reader, before,
                                                       stack):
                            total = spent + price
                            if total < following.get(after, INF):
                                following[after] = total
                    partial = _collapse(following)
                    if not partial:
                        break
                for after, total in partial.items():
                    if total < outcomes.get(after, INF):
                        outcomes[after] = total
        return [(total, after) for after, total in _collapse(outcomes).items()]

    def _of_type(self, kind: str) -> list[str]:
        found = self.typed.get(kind)
        if found is None:
            found = self.typed[kind] = self.problem.of_type(kind)
        return found


def _collapse(outcomes: dict[Overlay, float]) -> dict[Overlay, float]:
    """At most :data:`MAX_OUTCOMES` outcomes: beyond, one, at the cheapest cost, with
    what they all agree on."""
    if len(outcomes) <= MAX_OUTCOMES:
        return outcomes
    return {merge(list(outcomes)): min(outcomes.values())}
