"""The planning model: entity types, actions, methods, social rules, problems.

HATP's world is "a set of entities ... each entity is unique" with static and
dynamic attributes (Fig. 4); its domain is "a pair D = <T, R>" of tasks
(actions and methods, Fig. 5) and social rules.  Everything here is already
compiled: conditions, effects, costs and subtask arguments are
:mod:`planner.model.expr` closures.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from planner.model.expr import Effect, Expr

AGENT_KINDS = ("robot", "human")
SOLE_AGENT = "agent"
"""Who performs an action that names no agent (HDDL actions: one implicit executor)."""


@dataclass(frozen=True)
class EntityType:
    name: str
    static: dict[str, str]
    dynamic: dict[str, str]
    agent: bool = False
    doc: str = ""
    parent: str | None = None
    """The supertype (HDDL type hierarchies); an entity of this type is also one of its."""

    @property
    def attributes(self) -> dict[str, str]:
        return {**self.static, **self.dynamic}


@dataclass(frozen=True)
class ConditionalEffect:
    """Effects applied only when a condition holds in the state before the action."""

    condition: Expr
    effects: tuple[Effect, ...]


@dataclass(frozen=True)
class Action:
    """A primitive task, performed by the agent named by its ``agent`` parameter (or, when
    ``agent`` is None, by :data:`SOLE_AGENT`)."""

    name: str
    params: tuple[tuple[str, str], ...]
    agent: str | None
    pre: Expr | None
    effects: tuple[Effect | ConditionalEffect, ...]
    cost: Expr | float
    duration: Expr | float
    doc: str = ""
    deletes: tuple[tuple[str, Callable[[dict[str, Any]], tuple]], ...] = ()
    """HDDL: the goal facts it deletes whatever the state, as a predicate and a function
    of the arguments giving the fact's arguments (for the search's goal protection)."""
    needs: tuple[tuple[str, Callable[[dict[str, Any]], tuple]], ...] = ()
    """HDDL: the facts its precondition requires true (its top-level positive literals),
    as ``deletes`` gives them: a plan whose step deletes one of them before this action
    is on the agenda, with no task in between that may add it again, is doomed."""
    removes: tuple[tuple[str, Callable[[dict[str, Any]], tuple]], ...] = ()
    """HDDL: every fact its effect deletes whatever the state (``deletes`` are those of
    them that are goal facts)."""
    assigns: tuple[tuple[str, tuple[Subtask, ...]], ...] = ()
    """Conditional plans: tasks this action puts at the head of another agent's agenda
    (by the parameter naming that agent) -- asking someone for help gives them a task."""
    late: Any = None
    """HDDL: the binder of its precondition for arguments not bound yet
    (:func:`planner.search.late.compile_late`, used by the goal-guided search)."""
    names: tuple[str, ...] = field(init=False, repr=False, compare=False)
    """The parameters' names, in order (the search zips them with arguments)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "names", tuple(p for p, _ in self.params))

    def performer(self, env: dict[str, Any]) -> str:
        """The agent that carries out this action with these arguments."""
        return SOLE_AGENT if self.agent is None else env[self.agent]

    def apply(self, env: dict[str, Any], get: Any, set: Any) -> None:
        """Run the effects (conditional ones when their condition holds), reading the state
        before the action through ``get`` and writing through ``set``."""
        for effect in self.effects:
            if isinstance(effect, ConditionalEffect):
                if effect.condition(env, get):
                    for inner in effect.effects:
                        inner.fn(env, get, set)
            else:
                effect.fn(env, get, set)


@dataclass(frozen=True)
class Subtask:
    """A subtask of a decomposition: a task name and argument expressions."""

    task: str
    args: tuple[Expr, ...]
    text: str
    values: Callable[[dict[str, Any]], tuple] | None = None
    """HDDL: all the arguments' values at once, from the variables (they are variables
    and constants only): one call where ``args`` takes one per argument."""


Binder = Callable[[dict[str, Any], Any], Iterable[dict[str, Any]]]
"""``bind(env, state)``: candidate values for a decomposition's variables."""


@dataclass(frozen=True)
class Decomposition:
    """One way to decompose a method.  Its variables are bound, for each choice, to
    every combination of entities of their types, in name order, and the precondition
    ``pre`` is checked; or, when ``bind`` is given (HDDL methods), to the bindings it
    proposes, which satisfy ``pre`` already (it looks facts up in the state's index and
    tests each conjunct as soon as it can: :mod:`planner.search.binding`)."""

    name: str
    vars: tuple[tuple[str, str], ...]
    pre: Expr | None
    subtasks: tuple[Subtask, ...]
    doc: str = ""
    bind: Binder | None = None
    late: Any = None
    """HDDL: the binder that leaves unconstrained variables, and takes arguments, not bound
    yet (:func:`planner.search.late.compile_late`, used by the goal-guided search)."""
    weight: float = 1.0
    """How likely an uncontrolled agent (a human) is to take this decomposition, relative
    to the others open at that point (conditional plans: :mod:`planner.conditional.exploration`)."""
    open: tuple[OpenVar, ...] = ()
    """The variables left open to execution time (AgentX, query parameters)."""
    abandon: str | None = None
    """Conditional plans: taking this decomposition drops what is left of the nearest
    enclosing task of this method from the agenda (its subtasks replace it): giving up
    the current way of doing it, as when the robot asks for help and plans again."""


@dataclass(frozen=True)
class OpenVar:
    """A decomposition variable bound at execution time, not by the search: an AgentX
    (``any-of``: whichever capable agent does it) or a SPARQL query parameter (``query``:
    what the query returns when the step starts).  The search plans over every candidate
    -- the entities of the variable's type (those ``any-of`` names, if given) for which
    the decomposition's precondition holds -- so that the plan holds whichever one it is."""

    var: str
    kind: str
    """``agentx`` or ``query``."""
    any_of: tuple[str, ...] = ()
    query: str = ""


@dataclass(frozen=True)
class Method:
    """A compound task and the ways it decomposes, tried in order."""

    name: str
    params: tuple[tuple[str, str], ...]
    decompositions: tuple[Decomposition, ...]
    doc: str = ""
    first: bool = False
    """Conditional plans: only the first decomposition and binding (in file, then name
    order) whose precondition holds is used -- a rule, not a choice (``choose: first``)."""


@dataclass(frozen=True)
class Rule:
    """A social rule of the domain (a problem selects it, with penalties and a weight)."""

    name: str
    kind: str
    vars: tuple[tuple[str, str], ...] = ()
    when: Expr | None = None
    during: bool = False
    first: tuple[str, str | None] | None = None
    then: tuple[str, str | None] | None = None
    link: tuple[tuple[str, str], ...] = ()
    agents: str = "any"
    immediately: bool = True
    method: str | None = None
    decomposition: str | None = None
    max_wait: float = 0.0
    doc: str = ""


@dataclass
class Domain:
    name: str
    types: dict[str, EntityType]
    actions: dict[str, Action]
    methods: dict[str, Method]
    rules: dict[str, Rule]
    doc: str = ""
    file: str = ""
    predicates: dict[str, tuple[tuple[str, str], ...]] = field(default_factory=dict)
    """HDDL predicates; a fact ``(pred, args)`` is a state key whose value is True while it
    holds (None otherwise).  Empty for HATP domains, whose states are attribute values."""
    patterns: dict[str, tuple[tuple[int, ...], ...]] = field(default_factory=dict)
    """For each predicate, the argument positions the binders look facts up by (the
    state keeps an index for each)."""

    adds: dict[str, dict[str, tuple[tuple[tuple[Any, ...], tuple[tuple[int, str], ...]], ...]]
               ] = field(default_factory=dict)
    """HDDL: for each task, by predicate, the facts its decompositions may add, lifted:
    each argument is the index of a task parameter (int), a constant (str), or None
    (any value), with the guards under which it may: ``(index of a task parameter,
    the constant it must be)``.  A task absent from it adds nothing."""

    uncontrolled: tuple[str, ...] = ("human",)
    """The agent kinds whose choices the robot does not control: in conditional plans
    their options are branches (AND nodes), the others' are the planner's (OR nodes)."""

    def task(self, name: str) -> Action | Method | None:
        return self.actions.get(name) or self.methods.get(name)

    def may_add(self, task: str, args: tuple, pred: str, fact: tuple) -> bool:
        """Whether some decomposition of ``task(args)`` may make the fact ``pred(fact)``
        true (a lifted over-approximation: False is a certainty)."""
        for pattern, guards in self.adds.get(task, {}).get(pred, ()):
            if guards and any(args[index] != constant for index, constant in guards):
                continue
            if fits(pattern, args, fact):
                return True
        return False

    def may_add_named(self, task: str, args: tuple, pred: str, fact: tuple) -> bool:
        """Whether ``task(args)`` may add ``pred(fact)`` through a decomposition that
        names some of its arguments (a pattern with guards: the constants its methods
        fix), not only because a variable below it may be anything."""
        for pattern, guards in self.adds.get(task, {}).get(pred, ()):
            if not guards or any(args[index] != constant for index, constant in guards):
                continue
            if fits(pattern, args, fact):
                return True
        return False

    def is_subtype(self, kind: str | None, wanted: str) -> bool:
        """Whether ``kind`` is ``wanted`` or one of its subtypes."""
        seen = 0
        while kind is not None and seen <= len(self.types):
            if kind == wanted:
                return True
            etype = self.types.get(kind)
            kind = etype.parent if etype is not None else None
            seen += 1
        return False


def fits(pattern: tuple, args: tuple, fact: tuple) -> bool:
    """Whether a fact a task may add (``Domain.adds``: each entry the index of a task
    argument, a constant, or None for any value) is ``fact``, given the task's ``args``."""
    for entry, value in zip(pattern, fact, strict=True):
        if entry is not None and (args[entry] if entry.__class__ is int else entry) != value:
            return False
    return True


@dataclass(frozen=True)
class SelectedRule:
    """A rule as a problem uses it: penalty by agent name, agent kind or default."""

    rule: Rule
    penalties: dict[str, float]
    weight: float = 1.0

    def penalty(self, agent: str | None, kind: str | None) -> float:
        table = self.penalties
        if agent is not None and agent in table:
            return table[agent]
        if kind is not None and kind in table:
            return table[kind]
        return table.get("default", 1.0)


@dataclass(frozen=True)
class Assignment:
    """"This agent does this step": every ``action`` whose arguments include all of
    ``things`` is performed by ``agent`` (a person said "I'll take the bottle myself":
    ``Assignment("Pick", ("bottle",), "alice")``).  The search never applies an action
    that breaks one."""

    action: str
    things: tuple[str, ...]
    agent: str

    def breaks(self, action: str, args: tuple[Any, ...], performer: str) -> bool:
        return (action == self.action and performer != self.agent
                and all(thing in args for thing in self.things))


@dataclass
class Problem:
    name: str
    domain: Domain
    entities: dict[str, str]
    initial: dict[tuple[str, str], Any]
    tasks: tuple[tuple[str, tuple[Any, ...]], ...]
    goals: dict[tuple[str, str], Any] = field(default_factory=dict)
    rules: dict[str, SelectedRule] = field(default_factory=dict)
    weights: dict[str, float] = field(default_factory=dict)
    scale: dict[str, float] = field(default_factory=dict)
    budget_ms: int = 1000
    doc: str = ""
    file: str = ""
    agendas: tuple[tuple[str, tuple[tuple[str, tuple[Any, ...]], ...]], ...] = ()
    """Conditional problems: each agent's own tasks, in turn order (HATP/EHDA's agents
    each with an agenda); empty for the total-order planner's ``tasks``."""
    policy: dict[str, Any] = field(default_factory=dict)
    """Conditional problems: ``mode`` (expected or worst), ``idle_cost``, ``wait_cost``,
    ``max_steps``."""
    spelling: dict[str, str] = field(default_factory=dict)
    """HDDL problems: names the files spell otherwise than in lower case, with that
    spelling (:func:`planner.io.ipc.write_ipc` writes them so: the IPC verifier compares
    names case-sensitively)."""
    lifted: tuple[Any, Any] | None = None
    """HDDL problems: the domain and problem as read (:mod:`planner.io.hddl`), for the
    analyses that ground them (:mod:`planner.heuristics.grounding`)."""
    assigned: tuple[Assignment, ...] = ()
    """Steps given to an agent (:class:`Assignment`): a plan honours every one (the
    total-order search; plan negotiation, docs/communication.md)."""

    def select_rules(self, names: list[str]) -> None:
        """Keep only these social rules: the problem's settings for those it selected,
        a penalty of 1 for the others; KeyError names a rule the domain lacks."""
        chosen = {}
        for name in names:
            if name not in self.domain.rules:
                known = ", ".join(self.domain.rules) or "none"
                raise KeyError(f"the domain has no rule {name!r}; its rules: {known}")
            chosen[name] = self.rules.get(name) or SelectedRule(self.domain.rules[name],
                                                                {"default": 1.0})
        self.rules = chosen
        if self.weights:
            self.weights = {k: v for k, v in self.weights.items()
                            if k in chosen or k not in self.domain.rules}

    def of_type(self, type_name: str) -> list[str]:
        """The entities of a type (or of its subtypes), sorted by name (the search's
        deterministic order)."""
        return sorted(e for e, t in self.entities.items()
                      if t == type_name or self.domain.is_subtype(t, type_name))

    def is_a(self, entity: Any, type_name: str) -> bool:
        """Whether ``entity`` is an entity of ``type_name`` (or of one of its subtypes)."""
        return self.domain.is_subtype(self.entities.get(entity), type_name)

    def kind(self, agent: str) -> str | None:
        value = self.initial.get((agent, "kind"))
        return value if isinstance(value, str) else None
