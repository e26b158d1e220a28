"""Plans as the planner gives them: actions of several agents, per-agent streams,
causal links, the decomposition tree, and a score broken down by criterion.

HATP's plans are "a decomposition tree whose leaves are actions of several
agents; read as one stream per agent with causal links between streams".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

Relations = tuple[list["CausalLink"], list[tuple[int, int]]]
"""A plan's causal links and ordering constraints, sorted."""


@dataclass(frozen=True)
class PlanAction:
    """One action of the plan, in the total order the search produced it."""

    index: int
    name: str
    args: tuple[Any, ...]
    agent: str
    cost: float
    duration: float
    start: float = 0.0
    end: float = 0.0

    def __str__(self) -> str:
        return f"{self.name}({', '.join(str(a) for a in self.args)})"

    @classmethod
    def timed(cls, index: int, name: str, args: tuple[Any, ...], agent: str, cost: float,
              duration: float, start: float, end: float) -> PlanAction:
        """``PlanAction(index, ..., end)``, three times faster: a frozen dataclass's
        ``__init__`` sets each field through ``object.__setattr__``, and the evaluator
        makes one action object per action of every plan it builds."""
        action = object.__new__(cls)
        fields = action.__dict__
        fields["index"] = index
        fields["name"] = name
        fields["args"] = args
        fields["agent"] = agent
        fields["cost"] = cost
        fields["duration"] = duration
        fields["start"] = start
        fields["end"] = end
        return action


def fact_text(entity: str, attribute: Any) -> str:
    """A state key as people read it: ``obj.holder``, or an HDDL fact ``(on b1 b2)``
    (whose key is the predicate and the tuple of its arguments)."""
    if isinstance(attribute, tuple):
        return "(" + " ".join((entity, *map(str, attribute))) + ")"
    return f"{entity}.{attribute}"


@dataclass(frozen=True)
class CausalLink:
    """``consumer`` needs the value of ``entity.attribute`` that ``producer`` set."""

    producer: int
    consumer: int
    entity: str
    attribute: Any

    @property
    def fact(self) -> str:
        """What the link carries, as people read it (see :func:`fact_text`)."""
        return fact_text(self.entity, self.attribute)


@dataclass
class TreeNode:
    """A node of the decomposition tree: a compound task and the decomposition chosen,
    or an action (then ``action`` is its index in :attr:`Plan.actions`)."""

    id: int
    task: str
    args: tuple[Any, ...]
    decomposition: str | None = None
    children: list[int] = field(default_factory=list)
    action: int | None = None
    bindings: dict[str, Any] = field(default_factory=dict)


class _Derived:
    """A plan's ``links`` or ``orderings``: as given, or (given as None) derived on first
    read by the plan's ``relate``.  Finding them means replaying the plan, which costs as
    much as a third of a search on the IPC instances, and a plan whose evaluation does
    not need them (one agent, no rule about states or links) may never be asked for
    them: the evaluator leaves them to be derived on demand."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.slot = "_" + name

    def __get__(self, plan: Plan | None, owner: type) -> Any:
        if plan is None:  # no class attribute: the dataclass field stays without default
            raise AttributeError(self.slot[1:])
        value = plan.__dict__[self.slot]
        if value is None:
            if plan.relate is None:
                raise ValueError(f"the plan has no {self.slot[1:]} and no way to derive them")
            plan.links, plan.orderings = plan.relate()
            plan.relate = None
            value = plan.__dict__[self.slot]
        return value

    def __set__(self, plan: Plan, value: Any) -> None:
        plan.__dict__[self.slot] = value


@dataclass
class Plan:
    """A solution: actions, streams, links, tree, and its evaluation.  ``links`` and
    ``orderings`` may be given as None with ``relate`` to derive them when first read."""

    actions: list[PlanAction]
    links: list[CausalLink] = _Derived()  # type: ignore[assignment]
    orderings: list[tuple[int, int]] = _Derived()  # type: ignore[assignment]
    tree: dict[int, TreeNode]
    roots: list[int]
    criteria: dict[str, float] = field(default_factory=dict)
    weights: dict[str, float] = field(default_factory=dict)
    score: float = 0.0
    violations: list[str] = field(default_factory=list)
    relate: Callable[[], Relations] | None = field(default=None, repr=False, compare=False)

    @property
    def streams(self) -> dict[str, list[PlanAction]]:
        """One stream per agent: its actions in time order."""
        out: dict[str, list[PlanAction]] = {}
        for action in sorted(self.actions, key=lambda a: (a.start, a.index)):
            out.setdefault(action.agent, []).append(action)
        return out

    @property
    def makespan(self) -> float:
        return max((a.end for a in self.actions), default=0.0)

    def breakdown(self) -> dict[str, float]:
        """Each criterion's weighted share of the score."""
        return {name: self.weights.get(name, 0.0) * value for name, value in self.criteria.items()}
