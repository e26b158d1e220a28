"""Plans as the planner gives them: actions of several agents, per-agent streams,
causal links, the decomposition tree, and a score broken down by criterion.

HATP's plans are "a decomposition tree whose leaves are actions of several
agents; read as one stream per agent with causal links between streams".
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


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


@dataclass
class Plan:
    """A solution: actions, streams, links, tree, and its evaluation."""

    actions: list[PlanAction]
    links: list[CausalLink]
    orderings: list[tuple[int, int]]
    tree: dict[int, TreeNode]
    roots: list[int]
    criteria: dict[str, float] = field(default_factory=dict)
    weights: dict[str, float] = field(default_factory=dict)
    score: float = 0.0
    violations: list[str] = field(default_factory=list)

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
