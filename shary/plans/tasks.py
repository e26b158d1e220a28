"""A shared plan's tasks: JAHRVIS's abstract tasks λ and primitive tasks Π.

λ = ⟨id, state, name, Δ⟩ and Π = ⟨id, state, name, agent, params, preds, Δ⟩
(Section VI-A.2).  The planner writes them in one format for the three kinds
of plans of Section VI-C (``planner/schemas/conditional-plan.schema.json``,
:mod:`planner.conditional.sharedplan`): a *usual* plan is one with no human decision and
no open value; an *AgentX* plan has agents written ``{"any-of": [...]}`` and
parameters written ``{"query", "var", "candidates"}``; a *conditional* plan has
decisions whose options start branches.  :class:`SharedPlan` reads that
format, so the plan managers handle all three with one code path.  The states
are not kept here: they live in each agent's view (:mod:`shary.plans.states`).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

__all__ = ["AbstractTask", "Decision", "PrimitiveTask", "SharedPlan", "is_open"]

ACTION, WAIT, IDLE, DONE = "action", "wait", "idle", "done"
"""A primitive task's kinds: an action, or one of the planner's turn markers."""


def is_open(value: Any) -> bool:
    """True for a value the plan leaves to execution time (an AgentX agent, a query)."""
    return isinstance(value, dict)


@dataclass(frozen=True)
class AbstractTask:
    """λ: a task the planner decomposed (``decomposition`` is Δ, its parent's id)."""

    id: int
    name: str
    decomposition: int | None
    agent: str
    params: tuple[Any, ...] = ()


@dataclass(frozen=True)
class PrimitiveTask:
    """Π: an action of one agent (or of an AgentX, ``{"any-of": [...]}``)."""

    id: int
    name: str
    agent: Any
    params: tuple[Any, ...]
    preds: tuple[int, ...]
    decomposition: int | None
    kind: str = ACTION
    decision: str | None = None
    """The human decision whose option this task starts, if any."""

    def label(self) -> str:
        """``Place(robot, green_cube, blue_cube_2)``, open values by their variable."""
        def shown(value: Any) -> str:
            if not is_open(value):
                return str(value)
            return value.get("var") or "|".join(value.get("any-of", ())) or "?"
        return f"{self.name}({', '.join(shown(v) for v in self.params)})"

    def objects(self) -> tuple[Any, ...]:
        """The parameters after the agent (the planner's actions name their agent first)."""
        return self.params[1:] if self.params and self.params[0] == self.agent else self.params


@dataclass(frozen=True)
class Decision:
    """A human's choice: after which task, and the task each option starts."""

    id: str
    agent: str
    after: int | None
    options: tuple[int, ...]


@dataclass
class SharedPlan:
    """The tasks of one plan, and how they follow each other (a tree of branches)."""

    problem: str
    abstract: dict[int, AbstractTask]
    primitive: dict[int, PrimitiveTask]
    decisions: dict[str, Decision]
    agents: dict[str, str] = field(default_factory=dict)
    """Agent -> kind ("robot" or "human"), as the planner saw them."""
    _next: dict[int | None, list[int]] = field(default_factory=dict, repr=False)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SharedPlan:
        """Read the planner's plan (``shary-conditional-plan/1``); a ValueError says why
        it cannot be followed."""
        if data.get("format") != "shary-conditional-plan/1":
            raise ValueError(f"not a shared plan: format {data.get('format')!r}")
        if not data.get("found", True):
            raise ValueError(f"the planner found no plan for {data.get('problem')!r}")
        abstract = {a["id"]: AbstractTask(a["id"], a["name"], a.get("decomposition"),
                                          a.get("agent", ""), tuple(a.get("params", ())))
                    for a in data.get("abstract", ())}
        decision_of = {o["task"]: d["id"] for d in data.get("decisions", ())
                       for o in d["options"]}
        primitive = {p["id"]: PrimitiveTask(p["id"], p["name"], p["agent"],
                                            tuple(p.get("params", ())),
                                            tuple(p.get("predecessors", ())),
                                            p.get("decomposition"), p.get("kind", ACTION),
                                            decision_of.get(p["id"]))
                     for p in data.get("primitive", ())}
        decisions = {d["id"]: Decision(d["id"], d["agent"], d.get("after"),
                                       tuple(o["task"] for o in d["options"]))
                     for d in data.get("decisions", ())}
        agents = {name: spec.get("kind", "") for name, spec in data.get("agents", {}).items()}
        plan = cls(data.get("problem", ""), abstract, primitive, decisions, agents)
        for task in primitive.values():
            for pred in task.preds or (None,):
                plan._next.setdefault(pred, []).append(task.id)
        missing = [t.id for t in primitive.values() for p in t.preds if p not in primitive]
        if missing:
            raise ValueError(f"tasks {missing} follow tasks the plan does not have")
        return plan

    @classmethod
    def from_policy(cls, policy: Any) -> SharedPlan:
        """The shared plan of a policy chosen by :func:`planner.conditional.policy.select`."""
        from planner.conditional.sharedplan import to_dict

        return cls.from_dict(to_dict(policy))

    def next(self, after: int | None) -> list[PrimitiveTask]:
        """The tasks that may follow ``after`` (None: the first ones); several when a
        human decides which branch the plan takes."""
        return [self.primitive[i] for i in self._next.get(after, ())]

    def below(self, task: int) -> Iterator[int]:
        """``task`` and every task that can follow it, in the order of the branches."""
        stack = [task]
        while stack:
            current = stack.pop()
            yield current
            stack.extend(reversed(self._next.get(current, ())))

    def path(self, task: int) -> Iterator[int]:
        """The tasks of the one branch from ``task`` to the first decision after it."""
        current: int | None = task
        while current is not None:
            yield current
            following = self._next.get(current, [])
            current = following[0] if len(following) == 1 else None

    def ancestors(self, task: int) -> list[int]:
        """The abstract tasks ``task`` (primitive or abstract) was decomposed from,
        nearest first."""
        out = []
        node = self.primitive[task] if task in self.primitive else self.abstract[task]
        parent = node.decomposition
        while parent is not None and parent in self.abstract:
            out.append(parent)
            parent = self.abstract[parent].decomposition
        return out

    def is_human(self, agent: Any) -> bool:
        return isinstance(agent, str) and self.agents.get(agent) == "human"
