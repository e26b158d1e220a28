"""The model of a communication scheme: states, transitions and actions.

This is the statechart as the user wrote it, with names resolved and document
order recorded (SCXML's semantics depend on it).  It knows nothing of
execution: :mod:`shary.statechart.semantics` computes steps from it and
:mod:`shary.statechart.compiler` puts them onto ``transitions``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from shary.statechart.acts import ActRegistry, ActType
from shary.statechart.expressions import Expression, Location

ATOMIC, COMPOUND, PARALLEL, FINAL, HISTORY = "atomic", "compound", "parallel", "final", "history"

def descriptor_matches(descriptor: str, event: str) -> bool:
    """SCXML event matching: ``foo`` matches ``foo`` and ``foo.bar``; ``*`` matches all."""
    if descriptor == "*":
        return True
    if descriptor.endswith(".*"):
        descriptor = descriptor[:-2]
    return event == descriptor or event.startswith(descriptor + ".")


def covers(earlier: tuple[str, ...] | None, later: tuple[str, ...] | None) -> bool:
    """True when descriptors ``earlier`` match every event that ``later`` matches.

    ``None`` stands for an eventless transition, which only another eventless
    one covers.  Used to find transitions that can never be taken.
    """
    if later is None or earlier is None:
        return later is None and earlier is None
    return all(any(d1 == "*" or (d2 != "*" and descriptor_matches(
        d1, d2[:-2] if d2.endswith(".*") else d2)) for d1 in earlier) for d2 in later)


class Coverage:
    """The events taken so far by earlier unguarded transitions, to find dead ones fast.

    ``covers`` compares two transitions; a state with thousands of transitions
    would need millions of those comparisons.  Here each earlier descriptor is
    kept in a dictionary (``foo.*`` as ``foo``), and a later descriptor is
    covered when ``*`` or one of its dotted prefixes is there: one lookup per
    prefix.  The union of all earlier transitions counts, so a transition on
    ``a b`` after one on ``a`` and one on ``b`` is found dead too.
    """

    def __init__(self) -> None:
        self._taken: dict[str | None, object] = {}

    def add(self, events: tuple[str, ...] | None, item: object) -> None:
        """Record the descriptors of an unguarded transition (``None``: eventless)."""
        for d in (None,) if events is None else events:
            self._taken.setdefault(d[:-2] if d is not None and d.endswith(".*") else d, item)

    def covering(self, events: tuple[str, ...] | None) -> object | None:
        """The earlier item taking the first of ``events``, if every one of them is taken."""
        first = None
        for d in (None,) if events is None else events:
            found = self._lookup(d)
            if found is None:
                return None
            first = first or found
        return first

    def _lookup(self, descriptor: str | None) -> object | None:
        taken = self._taken
        if descriptor is None:
            return taken.get(None)
        if "*" in taken:
            return taken["*"]
        if descriptor == "*":
            return None
        name = descriptor[:-2] if descriptor.endswith(".*") else descriptor
        parts = name.split(".")
        for end in range(1, len(parts) + 1):
            found = taken.get(".".join(parts[:end]))
            if found is not None:
                return found
        return None


@dataclass(frozen=True)
class Raise:
    """Put an event on the instance's internal queue (handled before any outside event)."""

    event: str


@dataclass(frozen=True)
class Send:
    """Send an event after ``delay`` seconds on the instance's clock.

    ``to`` is None for the instance itself, :data:`PARENT` for the scheme that
    invoked it, or the id of an invoke of this scheme for that child: the
    events between parent and child that SCXML's ``<send target="#_parent">``
    and ``"#_ID"`` carry.
    """

    event: str
    delay: float = 0.0
    id: str | None = None
    to: str | None = None
    computed: SendParts | None = None
    """What the data model computes when the send runs (None: a fixed send, as above)."""


@dataclass(frozen=True)
class SendParts:
    """The parts of a send that the data model computes, as SCXML's ``<send>`` has them.

    ``target`` is an SCXML target (``#_parent``, ``#_ID``, ``#_internal``,
    ``#_scxml_SESSION``); a computed one overrides the send's ``to``.
    """

    event: Expression | None = None
    target: str | None = None
    target_expr: Expression | None = None
    type: str | None = None
    type_expr: Expression | None = None
    delay_expr: Expression | None = None
    id_location: Location | None = None
    type_expr: Expression | None = None
    """The invoke's type, computed when it starts: a scheme's, or the invoke fails."""
    params: tuple[tuple[str, Expression | Location], ...] = ()
    namelist: tuple[Location, ...] = ()
    content: Expression | None = None


IN_STATE = "in "
"""A guard ``in STATE`` holds while STATE is active: SCXML's ``In()``, the one predicate of
its null data model, needs no registered condition (it reads the configuration only)."""
EXPR_GUARD = "="
"""How a guard over the data model starts (``=`` and its text), to key it apart from
registered conditions, which are names."""
PARENT = "parent"
"""The ``to:`` of a send that goes to the invoking scheme (no invoke id may take this name)."""


@dataclass(frozen=True)
class Cancel:
    """Cancel a delayed send by its id."""

    id: str


@dataclass(frozen=True)
class Log:
    """Tell the instance's listener something (for traces and tests), with a value if any."""

    text: str
    expr: Expression | None = None


@dataclass(frozen=True)
class Assign:
    """Set a variable (or a key or item below one) of the data model."""

    location: Location
    expr: Expression


@dataclass(frozen=True)
class If:
    """Run the actions of the first branch whose condition holds (None: ``else``)."""

    branches: tuple[tuple[Expression | None, tuple[Action, ...]], ...]


@dataclass(frozen=True)
class Foreach:
    """Run actions once per item of a list (or tuple), with the item and its index set."""

    array: Expression
    item: Location
    index: Location | None
    actions: tuple[Action, ...]


@dataclass(frozen=True)
class Block:
    """Actions that an error stops without stopping the actions around them (SCXML's
    separate ``<onentry>`` handlers of one state)."""

    actions: tuple[Action, ...]


@dataclass(frozen=True)
class CancelComputed:
    """Cancel a delayed send whose id an expression computes."""

    id: Expression


Action = Raise | Send | Cancel | Log | Assign | If | Foreach | Block | CancelComputed


@dataclass(frozen=True)
class Variable:
    """A variable of the data model and how it starts (None: unbound until assigned)."""

    name: str
    expr: Expression | None
    mark: tuple[int, int] = (1, 1)
    state: str | None = None
    """The state that declares it (None: the scheme)."""


@dataclass(frozen=True)
class DataModel:
    """A scheme's variables, in document order, set when an instance starts; with ``late``
    binding, a state's own variables are set when the state is first entered instead."""

    variables: tuple[Variable, ...] = ()
    late: bool = False


@dataclass(frozen=True)
class DoneData:
    """The data of a final state's done event: named values, or one value (``content``)."""

    params: tuple[tuple[str, Expression | Location], ...] = ()
    content: Expression | None = None


@dataclass(frozen=True)
class Invoke:
    """A child scheme that a state starts (SCXML ``<invoke>``), as an act starts a sub-task.

    ``scheme`` is the child's :class:`Scheme`, resolved and checked when the
    parent is loaded.  The child starts at the end of the macrostep that
    entered the state (if the state is still active then), runs on the
    parent's clock, is cancelled when the state is left, and tells the parent
    ``done.invoke.ID.OUTCOME`` when it reaches a final state at its top.  With
    ``autoforward``, every outside event the parent takes is passed on to it.
    """

    id: str
    scheme: Scheme
    autoforward: bool = False
    mark: tuple[int, int] = (1, 1)
    params: tuple[tuple[str, Expression | Location], ...] = ()
    """Values the child's variables of those names start with (params and namelist)."""
    finalize: tuple[Action, ...] = ()
    """Actions run on each event from the child, before the parent takes it."""
    id_location: Location | None = None
    type_expr: Expression | None = None
    """The invoke's type, computed when it starts: a scheme's, or the invoke fails."""


@dataclass(eq=False)
class Transition:
    """A transition of a state: on events (or none: eventless), guarded, to targets."""

    source: State
    events: tuple[str, ...] | None
    targets: tuple[str, ...] = ()
    guard: str | None = None
    cond: Expression | None = None
    """A guard over the data model (``guard`` is then its key for the compiler)."""
    internal: bool = False
    actions: tuple[Action, ...] = ()
    after: float | None = None
    order: int = 0
    mark: tuple[int, int] = (1, 1)
    target_mark: tuple[int, int] = (1, 1)

    @property
    def negated(self) -> bool:
        return self.guard is not None and self.guard.startswith("not ")

    @property
    def condition(self) -> str | None:
        """The registered condition the guard names (without ``not``)."""
        return self.guard[4:] if self.negated else self.guard

    @property
    def in_state(self) -> str | None:
        """The state a guard ``in STATE`` names (see :data:`IN_STATE`), else None."""
        condition = self.condition
        return condition[len(IN_STATE):] if condition and condition.startswith(IN_STATE) \
            else None

    def matches(self, event: str | None) -> bool:
        if self.events is None or event is None:
            return self.events is None and event is None
        return any(descriptor_matches(d, event) for d in self.events)

    def label(self) -> str:
        """How diagrams name the transition: ``event [guard] / actions``."""
        if self.after is not None:
            trigger = self.events[0].split("@")[0] if self.events else ""
        else:
            trigger = " ".join(self.events) if self.events is not None else "always"
        guard = self.cond.source if self.cond is not None else self.guard
        text = trigger + (f" [{guard}]" if guard else "")
        if self.actions:
            text += " / " + "; ".join(_action_label(a) for a in self.actions)
        return text


def _action_label(action: Action) -> str:
    if isinstance(action, Raise):
        return f"raise {action.event}"
    if isinstance(action, Send):
        return f"send {action.event}" + (f" to {action.to}" if action.to else "") \
            + (f" after {action.delay:g}s" if action.delay else "")
    if isinstance(action, Cancel):
        return f"cancel {action.id}"
    if isinstance(action, Assign):
        return f"{action.location.source} = {action.expr.source}"
    if isinstance(action, If):
        return f"if {action.branches[0][0].source if action.branches[0][0] else ''}"
    if isinstance(action, Foreach):
        return f"foreach {action.item.source} in {action.array.source}"
    if isinstance(action, CancelComputed):
        return f"cancel {action.id.source}"
    if isinstance(action, Block):
        return "; ".join(_action_label(a) for a in action.actions)
    return f"log {action.text!r}"


@dataclass(eq=False)
class State:
    """A state of a scheme; ``act`` and ``act_type`` say which act it carries out, by whom."""

    name: str
    kind: str
    parent: State | None = None
    children: list[State] = field(default_factory=list)
    initial: tuple[str, ...] = ()
    history: str | None = None
    default: tuple[str, ...] = ()
    act: str | None = None
    by: str | None = None
    act_type: ActType | None = None
    outcome: str = "done"
    doc: str = ""
    transitions: list[Transition] = field(default_factory=list)
    on_entry: tuple[Action, ...] = ()
    on_exit: tuple[Action, ...] = ()
    initial_actions: tuple[Action, ...] = ()
    """Actions of the initial transition (or of a history's default transition)."""
    invokes: tuple[Invoke, ...] = ()
    donedata: DoneData | None = None
    order: int = 0
    depth: int = 0
    mark: tuple[int, int] = (1, 1)

    def __repr__(self) -> str:
        return f"<State {self.name or '(root)'} {self.kind}>"

    def ancestors(self) -> list[State]:
        """Proper ancestors, nearest first, the root included."""
        out = []
        node = self.parent
        while node is not None:
            out.append(node)
            node = node.parent
        return out

    def is_descendant_of(self, other: State) -> bool:
        node = self.parent
        while node is not None:
            if node is other:
                return True
            node = node.parent
        return False

    @property
    def is_atomic(self) -> bool:
        return self.kind in (ATOMIC, FINAL)

    @property
    def is_compound(self) -> bool:
        return self.kind == COMPOUND

    def proper_children(self) -> list[State]:
        """Children that are real states (history pseudo-states left out)."""
        return [c for c in self.children if c.kind != HISTORY]


@dataclass(eq=False)
class Scheme:
    """A whole communication scheme: its root state and everything below it."""

    name: str
    root: State
    states: dict[str, State]
    roles: dict[str, str]
    acts: ActRegistry
    doc: str = ""
    file: str = "<string>"
    datamodel: DataModel | None = None
    """The variables; None for a scheme without a data model (which runs without one)."""

    def state(self, name: str) -> State:
        return self.states[name]

    def all_states(self) -> list[State]:
        """Every state in document order (the root left out)."""
        return sorted(self.states.values(), key=lambda s: s.order)
